"""A scripted autopilot for tick tests: it answers what the tree asks for at once, and a test (or a subclass) says how."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from py_trees.common import Status

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.modes import ArduPilotModes, ModeTable
from executive.mission.declaration import vehicle_profile
from executive.testing.harness import BATTERY_FULL, ENERGY_UNJUDGED, Harness, Vehicle, mode_switch_channel
from executive.testing.links import AUTOPILOT
from executive.world import blackboard
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink
from executive.world.geo import destination, distance_bearing
from executive.world.state import GlobalPosition

_M = mavlink


class ScriptedAutopilot:
    """An autopilot behind a :class:`Harness` that obeys at once: modes and arming acked, GUIDED targets stepped toward.

    After each tick, :meth:`respond` takes what the tree sent, answers each message (acks go to
    the commander, as the reader would pass them on), moves the vehicle one tick (:meth:`move`)
    and publishes its facts to the blackboard (:meth:`facts`). :attr:`commands` is what it was
    told, readable: ``("mode", "GUIDED")``, ``("arm", 1.0)``, ``("DO_CHANGE_SPEED",)`` (:meth:`take` empties it); :attr:`targets`
    the GUIDED targets it followed, ``(lat, lon)``. A command kind
    (``"arm"``, a mode name, a command name such as ``"DO_CHANGE_SPEED"``) in :attr:`refuse` is
    answered :attr:`refusal`. Subclass it for another firmware: override :meth:`on_command`,
    :meth:`on_setpoint`, :meth:`enter_mode`, :meth:`move` and :meth:`facts`.
    """

    def __init__(
        self,
        harness: Harness | None,
        start: tuple[float, float] = (0.0, 0.0),
        *,
        step_m: float = 8.0,
        mode: str = "MANUAL",
        commander: Commander | None = None,
    ) -> None:
        self.h = harness  # type: ignore[assignment]  # None only for a subclass that talks over a link (ObedientAutopilot)
        #: The executive's commander (the harness's unless given): its mode table decodes what it sent, as it meant it.
        self.commander = commander if commander is not None or harness is None else harness.commander
        self.lat, self.lon = start
        self.alt = 0.0
        self.step_m = step_m
        self.mode, self.armed = mode, False
        self.target: tuple[float, float] | None = None
        self.commands: list[tuple[Any, ...]] = []
        self.targets: list[tuple[float, float]] = []
        self.refuse: set[str] = set()
        self.refusal = _M.MAV_RESULT_FAILED
        self.received = 0
        self.publish()
        self.report_health()

    def report_health(self) -> None:
        """What a healthy autopilot has told by now, where the test has not said otherwise (the key unset): a full battery
        (:data:`~executive.testing.BATTERY_FULL`), an energy rule that cannot judge it, the firmware's mode-switch channel
        (MODE_CH or FLTMODE_CH: the mission's ``simulator.params``, else 8), which the guards and pre-flight need. Once, when it
        is made: a test's ``vehicle.set`` wins."""
        from executive.autopilot.ardupilot import MODE_SWITCH_PARAMS

        profile = self.commander.profile if self.commander is not None else getattr(self, "profile", None)
        param = MODE_SWITCH_PARAMS.get(profile.mav_type) if profile is not None else None
        mission = self.h.mission_state.mission if self.h is not None else None
        facts: dict[str, object] = {}
        if blackboard.value("/vehicle/battery") is None:
            facts["vehicle__battery"] = BATTERY_FULL
        if blackboard.value("/energy/estimate") is None and not blackboard.value("/energy/unknown"):
            facts["energy__not_judged"] = ENERGY_UNJUDGED
        known = blackboard.value("/vehicle/params") or {}
        if param is not None and param not in known:
            facts["vehicle__params"] = {**known, param: mode_switch_channel(mission)}
        if facts:
            Vehicle().set(**facts)

    # -- what it tells the executive -----------------------------------------------------------
    def facts(self) -> dict[str, object]:
        """The blackboard facts it publishes after each tick (``vehicle__mode=...``, as :meth:`Vehicle.set` takes them)."""
        return {
            "vehicle__mode": self.mode,
            "vehicle__armed": self.armed,
            "vehicle__position": GlobalPosition(self.lat, self.lon, self.alt, 0.0, 0.0, 0.0, 0.0, 0.0),
        }

    def publish(self) -> None:
        """Write :meth:`facts` to the blackboard."""
        self.h.vehicle.set(**self.facts())

    @property
    def modes(self) -> ModeTable:
        """The firmware's mode numbers (the executive's own table: what it sent is decoded as it meant it)."""
        assert self.commander is not None, "a scripted autopilot without a harness needs commander="
        return self.commander.modes

    @property
    def guided_mode(self) -> str:
        """The mode that follows position targets."""
        assert self.commander is not None, "a scripted autopilot without a harness needs commander="
        return self.commander.profile.guided_mode

    def acknowledge(self, command: int, result: int) -> None:
        """Send the COMMAND_ACK of ``command``."""
        self.h.ack(command, result)

    # -- how it answers -------------------------------------------------------------------------
    def respond(self) -> None:
        """Answer what the tree sent since the last call, move one tick, publish."""
        for msg in self.h.link.take():
            self.answer(msg)
        self.move()
        self.publish()

    def answer(self, msg: MAVLinkMessage) -> None:
        """Answer one message the executive sent."""
        self.received += 1
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            result = self.on_command(msg)
            if result is not None:
                self.acknowledge(msg.command, result)
        elif kind.startswith("SET_POSITION_TARGET"):
            self.on_setpoint(msg)
        else:
            self.on_message(msg)

    def result_for(self, kind: str) -> int:
        """The result for a command of ``kind``: refused if listed in :attr:`refuse`, else accepted."""
        return self.refusal if kind in self.refuse else _M.MAV_RESULT_ACCEPTED

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        """Answer a COMMAND_LONG / COMMAND_INT: the MAV_RESULT to ack with (None: no ack). Modes and arming here; others accepted."""
        if msg.command == _M.MAV_CMD_DO_SET_MODE:
            mode = self.modes.decode(int(msg.param2))
            self.commands.append(("mode", mode))
            result = self.result_for(mode)
            if result == _M.MAV_RESULT_ACCEPTED and not self.enter_mode(mode):
                result = _M.MAV_RESULT_FAILED
            return result
        if msg.command == _M.MAV_CMD_COMPONENT_ARM_DISARM:
            self.commands.append(("arm", msg.param1))
            result = self.result_for("arm")
            if result == _M.MAV_RESULT_ACCEPTED:
                self.armed = bool(msg.param1)
            return result
        from executive.io.mavlink.commander import command_name

        name = command_name(msg.command)
        self.commands.append((name,))
        return self.result_for(name)

    def enter_mode(self, mode: str) -> bool:
        """Switch to ``mode`` (False refuses it); the target is forgotten, as a mode change does."""
        self.mode, self.target = mode, None
        return True

    def on_setpoint(self, msg: MAVLinkMessage) -> None:
        """A position target: followed in the guided mode (ignored silently elsewhere, as ArduPilot does)."""
        if msg.get_type() == "SET_POSITION_TARGET_GLOBAL_INT" and self.mode == self.guided_mode:
            self.target = (msg.lat_int / 1e7, msg.lon_int / 1e7)
            self.targets.append(self.target)

    def on_message(self, msg: MAVLinkMessage) -> None:
        """Anything else the executive sent (ignored)."""

    def move(self) -> None:
        """One tick of motion: armed, in the guided mode, ``step_m`` toward the target."""
        if self.target and self.armed and self.mode == self.guided_mode:
            d, b = distance_bearing(self.lat, self.lon, *self.target)
            self.lat, self.lon = destination(self.lat, self.lon, b, min(d, self.step_m))

    # -- driving the test ----------------------------------------------------------------------
    def take(self) -> list[tuple[Any, ...]]:
        """What it was told since the last take (:attr:`commands`, emptied)."""
        taken, self.commands = self.commands, []
        return taken

    def run(self, ticks: int, until: Callable[[], bool] | None = None, dt: float = 0.1) -> list[Status]:
        """Tick and respond up to ``ticks`` times, stopping when the tree is no longer RUNNING or ``until()``; the statuses."""
        statuses = []
        for _ in range(ticks):
            statuses.append(self.h.tick(dt))
            self.respond()
            if statuses[-1] != Status.RUNNING or (until is not None and until()):
                break
        return statuses


class MissionAutopilot(ScriptedAutopilot):
    """A scripted autopilot that holds a mission as ArduPilot does, behind a harness with a mission transfer (``Harness.build(..., transfer=True)``).

    :attr:`store` is the simulator's own :class:`~executive.sim.ardupilot.mission_store.ArduPilotMissionStore` (home at item
    0, uploads driven by MISSION_REQUEST, items read back as stored). The mission messages the
    executive sends go to it (none while :attr:`answers_missions` is off: a link that loses them);
    its replies wait in :attr:`replies` until :meth:`deliver` hands them over as the MAVLink reader
    would (a COMMAND_ACK put there reaches the commander then). AUTO is refused without a mission
    and runs the store's; armed in AUTO, :meth:`move` steps toward the current item and, within
    ``step_m`` of it, reports it reached, as ArduRover does. ``home`` is where item 0 reads back.
    """

    system_id = component_id = 1

    def __init__(self, harness: Harness, start: tuple[float, float] = (0.0, 0.0), *, home: tuple[float, float] | None = None, **options: Any) -> None:
        from executive.sim.ardupilot.mission_store import ArduPilotMissionStore

        assert harness.transfer is not None, "a mission autopilot needs a harness with a mission transfer (Harness.build(..., transfer=True))"
        self.transfer = harness.transfer
        self.clock = harness.clock
        self.home: tuple[float, float] | None = home or start
        self.answers_missions = True
        self.replies: list[MAVLinkMessage] = []
        self.store = ArduPilotMissionStore(self, self.replies.append, self.statustext)
        self._wire = _M.MAVLink(None, srcSystem=1, srcComponent=EXECUTIVE_COMPONENT)
        super().__init__(harness, start, **options)

    def statustext(self, severity: int, text: str) -> None:
        """A STATUSTEXT of the autopilot's (the store's notices): on the blackboard, as the reader writes it."""
        self.h.vehicle.set(vehicle__statustext=(severity, text))

    def on_message(self, msg: MAVLinkMessage) -> None:
        """Mission messages to the store, as it receives them: packed with the executive's header, decoded."""
        if msg.get_type() in self.store.MESSAGES and self.answers_missions:
            self.store.handle(_M.MAVLink(None).decode(bytearray(msg.pack(self._wire))))

    def enter_mode(self, mode: str) -> bool:
        """AUTO needs a mission (and starts or resumes it); leaving AUTO stops it."""
        if mode == self.store.AUTO_MODE and not self.store.present:
            return False
        if self.mode == self.store.AUTO_MODE:
            self.store.stop()
        super().enter_mode(mode)
        if mode == self.store.AUTO_MODE:
            self.store.start_or_resume()
        return True

    def move(self) -> None:
        """In AUTO, armed: a step toward the current item, reached within ``step_m``; MISSION_CURRENT then. Else as guided."""
        if self.mode != self.store.AUTO_MODE:
            super().move()
            return
        item = self.store.current
        if item is not None and self.armed:
            d, b = distance_bearing(self.lat, self.lon, item.lat, item.lon)
            self.lat, self.lon = destination(self.lat, self.lon, b, min(d, self.step_m))
            if d <= self.step_m:
                self.store.advance()
        self.replies.append(self.store.current_message())

    def deliver(self) -> None:
        """The replies so far reach the executive: mission messages to the transfer, acks to the commander."""
        t = self.transfer
        handlers = {
            "MISSION_REQUEST": t.on_request, "MISSION_REQUEST_INT": t.on_request, "MISSION_ACK": t.on_ack, "MISSION_COUNT": t.on_count,
            "MISSION_ITEM_INT": t.on_item, "MISSION_CURRENT": t.on_current, "MISSION_ITEM_REACHED": t.on_reached,
        }  # fmt: skip
        replies = list(self.replies)
        self.replies.clear()  # in place: the store appends to this list
        for msg in replies:
            if msg.get_type() == "COMMAND_ACK":
                self.commander.on_ack(msg)
            else:
                handlers[msg.get_type()](msg, self.clock.now())

    def held(self) -> list[tuple[float, float]]:
        """The waypoints it holds (items 1..n), as stored (1e-7 degree)."""
        return [(self.store.command(seq).lat, self.store.command(seq).lon) for seq in range(1, self.store.count)]


class ObedientAutopilot(ScriptedAutopilot):
    """The scripted autopilot behind a whole runtime's :class:`~executive.testing.FakeLink`: it answers as the messages are sent.

    Each HEARTBEAT of the executive is answered with its own (type of ``vehicle``, :attr:`mode`,
    :attr:`armed`), each command with a COMMAND_ACK queued on the link, as the reader would receive
    them; :meth:`beat` sends a heartbeat now, and where the vehicle is (``start``, a
    GLOBAL_POSITION_INT: the runtime runs no tree before it knows the position, see
    :mod:`executive.admission.reach`; none at the default 0, 0, which autopilots send for "no fix"). Other
    facts (the EKF) are the test's to write.
    """

    def __init__(
        self, link: Any, vehicle: str = "rover", *, mode: str = "GUIDED", armed: bool = True, start: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        self.link, self.profile = link, vehicle_profile(vehicle)
        self._modes = ArduPilotModes(self.profile.modes)
        super().__init__(None, start, mode=mode)
        self.armed = armed
        self._send = link.send
        link.send = self._receive

    @property
    def modes(self) -> ModeTable:
        return self._modes

    @property
    def guided_mode(self) -> str:
        return self.profile.guided_mode

    def publish(self) -> None:
        """Nothing to write: the heartbeat carries the mode and arming."""

    def report_health(self) -> None:
        """Nothing written: over a link, what it reports is what it sends; other facts (battery, parameters) are the test's."""

    def acknowledge(self, command: int, result: int) -> None:
        self.link.incoming.append(AUTOPILOT.command_ack(command, result, 0, 0, 1, 191))

    def _receive(self, msg: MAVLinkMessage) -> None:
        self._send(msg)
        if msg.get_type() == "HEARTBEAT":
            self.beat()
        else:
            self.answer(msg)

    def beat(self) -> None:
        """The autopilot's HEARTBEAT arrives."""
        base = _M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (_M.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
        self.link.incoming.append(AUTOPILOT.heartbeat(self.profile.mav_type, _M.MAV_AUTOPILOT_ARDUPILOTMEGA, base, self.profile.modes[self.mode], 4))
        if (self.lat, self.lon) != (0.0, 0.0):
            lat, lon = round(self.lat * 1e7), round(self.lon * 1e7)
            self.link.incoming.append(AUTOPILOT.global_position_int(0, lat, lon, round(self.alt * 1000), round(self.alt * 1000), 0, 0, 0, 65535))
