"""A behaviour tree ticked by hand: scripted blackboard inputs, a manual clock, and what the tree asked the autopilot for."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Status

from executive.autopilot.selection import Autopilot
from executive.io.mavlink.commander import Commander, command_name
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.mission.declaration import vehicle_profile
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.mission.port import MissionPort
from executive.testing.links import FakeLink, ack
from executive.tree.ticking import BehaviourTree
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.state import Battery, EkfFlags, EkfStatus

#: Where a tick test's clock starts (any positive time: the executive never assumes 0).
START_S = 100.0
#: An EKF report as ArduPilot sends it once the EKF uses GPS (flags 0x33F, small variances): ``vehicle.set(vehicle__ekf=EKF_READY)``.
EKF_READY = EkfStatus(EkfFlags(831), 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
#: A full battery as SYS_STATUS reports it (12.6 V, 100 %): what :meth:`Harness.build`'s vehicle reports until a test says otherwise.
BATTERY_FULL = Battery(12.6, 1.0, 100, 0.0)
#: What the energy rule makes of a test vehicle's battery (no energy watch runs here): not judged, so the rule passes.
ENERGY_UNJUDGED = "a test vehicle (executive.testing) tells no battery energy"


def mode_switch_channel(mission: Mission | None) -> float:
    """The autopilot's mode-switch channel as a simulated one reports it: the mission's ``simulator.params`` (MODE_CH, FLTMODE_CH), else 8.

    8 is the firmware's default (ArduRover MODE_CHANNEL in Rover/config.h, ArduPlane FLIGHT_MODE_CHANNEL).
    """
    params = mission.simulator.params if mission is not None and mission.simulator is not None else {}
    return next((float(params[p]) for p in ("MODE_CH", "FLTMODE_CH") if p in params), 8.0)


class Vehicle:
    """Writes vehicle facts to the blackboard as the IO readers would: vehicle state, link, RC, EKF, heading.

    ``Vehicle().set(vehicle__mode="GUIDED", link__up=True)`` writes ``/vehicle/mode`` and ``/link/up``
    (``__`` stands for ``/``); any documented key under ``/link/``, ``/vehicle/``, ``/rc/`` or ``/heading/``.
    """

    def __init__(self) -> None:
        self.bb = blackboard.writer("test vehicle", blackboard.keys_under("/link/", "/vehicle/", "/rc/", "/heading/", "/energy/"))

    def set(self, **facts: object) -> None:
        """``set(vehicle__mode="GUIDED", link__up=True)`` -> ``/vehicle/mode``, ``/link/up``."""
        for name, value in facts.items():
            self.bb.set("/" + name.replace("__", "/"), value)


def describe(msg: MAVLinkMessage, commander: Commander) -> tuple[Any, ...]:
    """What a message the executive sent asks for, readable.

    ``("mode", "HOLD")``, ``("arm", True)``, ``("goto", lat, lon, alt_m)`` (a global position
    target, 7 decimals), ``("local", north_m, east_m, down_m)``, another command as
    ``("DO_CHANGE_SPEED", (param1, ..., param7))``, anything else as ``(TYPE,)``.
    """
    kind = msg.get_type()
    if kind in ("COMMAND_LONG", "COMMAND_INT"):
        if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            return ("mode", commander.modes.decode(int(msg.param2)))
        if msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            return ("arm", bool(msg.param1))
        params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.x, msg.y, msg.z) if kind == "COMMAND_INT" else (
            msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7,
        )  # fmt: skip
        return (command_name(msg.command), params)
    if kind == "SET_POSITION_TARGET_GLOBAL_INT":
        return ("goto", round(msg.lat_int / 1e7, 7), round(msg.lon_int / 1e7, 7), msg.alt)
    if kind == "SET_POSITION_TARGET_LOCAL_NED":
        return ("local", msg.x, msg.y, msg.z)
    return (kind,)


def port_for(commander: Commander, transfer: MissionTransfer | None = None) -> Autopilot:
    """The autopilot port over ``commander`` (ArduPilot until a heartbeat, or ``adopt``, says otherwise)."""
    return Autopilot(commander, transfer, commander.profile)


class Harness:
    """A tree ticked by hand: the clock advances ``dt`` before each tick; the commands it asked for are flushed to :attr:`link` after.

    The tree is set up as the runtime sets it up (``clock``, ``autopilot``, ``mission_state``): the
    autopilot port over ``commander`` and ``transfer`` (:attr:`autopilot`; ArduPilot unless given, or
    ``autopilot.adopt``). Script the inputs with :attr:`vehicle` (or any :class:`Vehicle`) between ticks,
    answer with :meth:`ack`, and assert on :meth:`asked` (or ``link.take()``) and on :meth:`status` /
    :meth:`feedback` of a node named by its path. Each tick runs as the runtime's: the clock, the
    :attr:`readers`, the tree, the :attr:`writers`, then the commands (and the mission transfer's) are sent.
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        clock: ManualClock,
        link: FakeLink,
        commander: Commander,
        mission_state: MissionState,
        autopilot: Autopilot | None = None,
        *,
        transfer: MissionTransfer | None = None,
        **setup: Any,
    ) -> None:
        """``transfer``: the mission protocol's end (to keep a route on the autopilot); ``setup``: more for the behaviours' setup."""
        self.root, self.clock, self.link, self.commander, self.transfer = root, clock, link, commander, transfer
        self.autopilot = autopilot or port_for(commander, transfer)
        self.mission_state = mission_state
        self.vehicle = Vehicle()
        #: Called each tick after the clock moves, before the tree: the IO readers' part (an RcReader's ``service``, a vehicle's facts).
        self.readers: list[Callable[[], object]] = []
        #: Called each tick after the tree, before the commands are sent: what the runtime services then (a RouteKeeper's ``service``).
        self.writers: list[Callable[[], object]] = []
        self.tree = BehaviourTree(root)
        self.tree.setup(clock=clock, autopilot=self.autopilot, mission_state=MissionPort(mission_state), **setup)

    @classmethod
    def build(
        cls,
        mission: Mission,
        root: py_trees.behaviour.Behaviour | None = None,
        *,
        clock: ManualClock | None = None,
        start: bool = True,
        transfer: bool = False,
        **setup: Any,
    ) -> Harness:
        """A harness for ``mission``: its own tree (``trees.build``) unless ``root`` is given, the mission uploaded and started.

        ``transfer``: with a :class:`MissionTransfer` on the link (:attr:`transfer`), for a tree that keeps a route on the autopilot.

        The blackboard is reset first (every documented key at its default), so build it before scripting inputs. The vehicle
        then reports what a healthy one has told by the time a mission starts and the guards need: a full battery
        (:data:`BATTERY_FULL`), its firmware's default mode-switch channel (``/vehicle/params``: MODE_CH 8 on ArduRover,
        FLTMODE_CH 8 on ArduPlane) and an energy rule that cannot judge it (:data:`ENERGY_UNJUDGED`); ``h.vehicle.set(vehicle__battery=None)``
        (or ``vehicle__params=None``, ``energy__not_judged=""``) for one that has not.
        """
        from executive.tree import select as mission_tree

        blackboard.reset()
        clock = clock or ManualClock(START_S)
        link = FakeLink()
        state = MissionState()
        state.upload(mission)
        if start:
            state.start()
        commander = Commander(link, clock, vehicle_profile(mission.vehicle))
        missions = MissionTransfer(link, clock) if transfer else None
        harness = cls(root if root is not None else mission_tree.build(mission), clock, link, commander, state, transfer=missions, **setup)
        param = harness.autopilot.capabilities.mode_switch_param
        params = {param: mode_switch_channel(mission)} if param else None
        harness.vehicle.set(vehicle__battery=BATTERY_FULL, vehicle__params=params, energy__not_judged=ENERGY_UNJUDGED)
        return harness

    # -- ticking --------------------------------------------------------------------------
    def tick(self, dt: float = 0.1) -> Status:
        """Advance the clock ``dt`` seconds, run the readers, tick the tree once, run the writers, send what was asked; returns the root's status."""
        self.clock.advance(dt)
        for read in self.readers:
            read()
        self.tree.tick()
        for write in self.writers:
            write()
        self.autopilot.service()  # as the runtime: the back end's own traffic (PX4's offboard stream), then the commands
        self.commander.flush()
        if self.transfer is not None:
            self.transfer.flush()
        return self.root.status

    def tick_until(self, done: Callable[[], bool], *, max_ticks: int = 1000, dt: float = 0.1, between: Callable[[], object] | None = None) -> int:
        """Tick until ``done()`` (checked after each tick; ``between()`` runs after each tick first, e.g. a scripted autopilot).

        Returns how many ticks it took; AssertionError after ``max_ticks``.
        """
        for n in range(1, max_ticks + 1):
            self.tick(dt)
            if between is not None:
                between()
            if done():
                return n
        raise AssertionError(f"not done after {max_ticks} ticks ({max_ticks * dt:g} s)")

    # -- the autopilot's side ---------------------------------------------------------------
    def ack(self, command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> None:
        """A COMMAND_ACK of ``command`` arrives from the autopilot (seen by the commander at once)."""
        self.commander.on_ack(ack(command, result))

    def asked(self, kind: str | None = None) -> list[tuple[Any, ...]]:
        """What the tree asked the autopilot for since the last call (taken off the link), readable (see :func:`describe`)."""
        return [describe(m, self.commander) for m in self.link.take(kind)]

    # -- the tree -----------------------------------------------------------------------------
    def node(self, path: str) -> py_trees.behaviour.Behaviour:
        """The node at ``path``: names from the root joined by ``/`` (``Mission/Route/EKF ok?``), or the end of such a path.

        KeyError (listing every path) when no node, or more than one, matches.
        """
        paths = {_path(n): n for n in self.root.iterate()}
        if path in paths:
            return paths[path]
        found = [n for p, n in paths.items() if p.endswith("/" + path)]
        if len(found) != 1:
            why = "no node" if not found else f"{len(found)} nodes"
            raise KeyError(f"{why} at {path!r}; the tree has: " + ", ".join(paths))
        return found[0]

    def status(self, path: str) -> Status:
        """The status of the node at ``path`` after the last tick."""
        return self.node(path).status

    def feedback(self, path: str) -> str:
        """The feedback message of the node at ``path`` after the last tick."""
        return self.node(path).feedback_message

    def statuses(self) -> dict[str, Status]:
        """Every node's status by path."""
        return {_path(n): n.status for n in self.root.iterate()}


def _path(node: py_trees.behaviour.Behaviour) -> str:
    from executive.runtime.loop import behaviour_path

    return behaviour_path(node)
