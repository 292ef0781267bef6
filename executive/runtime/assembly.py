"""How a runtime is put together: the autopilot link and the operator side every run has, and plugs for the optional parts.

:func:`build_runtime` is the builder (``executive run`` composes its plugs from the command line;
tests and benchmarks call it directly). A plug is a function of the :class:`Wiring` that adds
services to it: a new link (a sensor, a viewer, another autopilot's protocol) is a new plug.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from executive.admission import checks as admission
from executive.admission.reach import ReachGate
from executive.autopilot import AutopilotName
from executive.autopilot_link import AutopilotLink
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.link import Link
from executive.mission.declaration import vehicle_profile
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.mission.rules import rc_switch_channels
from executive.operator import Operator
from executive.operator.ground_station import GroundStationControl
from executive.operator.intervention import InterventionWatch
from executive.operator.persons_commands import PersonsCommands
from executive.operator.status import StatusSource
from executive.runtime.loop import Runtime
from executive.runtime.services import FunctionService, PacedService, RunObserver, Service
from executive.sensing.energy import EnergyWatch
from executive.sensing.heading import HeadingFilter
from executive.sensing.rc import RcReader
from executive.tree.waiting import TreeWatch
from executive.world import blackboard
from executive.world.clock import Clock

if TYPE_CHECKING:
    import can
    import py_trees

    from executive.io.can.drive import DriveBridge
    from executive.io.systemd import Watchdog
    from executive.operator.progress import Progress


@dataclass
class Wiring:
    """What the plugs see and add to; the runtime runs its services in list order."""

    mission: Mission
    clock: Clock
    system_id: int
    mission_state: MissionState
    status: StatusSource
    operator: Operator
    #: The autopilot: pumped before the readers, flushed after the writers.
    link: AutopilotLink
    #: The ground-station endpoint: commands to us answered, the mission reported (on the autopilot's link and on any added).
    ground_station: GroundStationControl
    simulated_vehicle: bool = True  # the built-in simulator: a simulated instrument may take the samples
    readers: list[Service] = field(default_factory=list)
    writers: list[Service] = field(default_factory=list)
    paced: list[PacedService] = field(default_factory=list)
    observers: list[RunObserver] = field(default_factory=list)
    closers: list[Callable[[], object]] = field(default_factory=list)


Plug = Callable[[Wiring], None]


def build_runtime(
    mission: Mission,
    link: Link,
    clock: Clock,
    *,
    plugs: Sequence[Plug] = (),
    system_id: int = 1,
    target_system: int | None = None,
    target_component: int = 1,
    rate_hz: float = 10.0,
    safe_timeout_s: float | None = None,
    root: py_trees.behaviour.Behaviour | None = None,
    progress: Progress | None = None,
    autopilot: AutopilotName | None = None,
    simulated_vehicle: bool = True,
) -> Runtime:
    """A runtime for ``mission`` on the autopilot at the other end of ``link``, with the optional parts ``plugs`` add.

    ``target_system``/``target_component``: the autopilot to command, alone (None: the only one on the link).
    ``autopilot``: the back end (``ardupilot``, ``px4``) whatever the heartbeat says (None: the heartbeat's).
    ``simulated_vehicle``: the autopilot is the built-in simulator (False: samples must come from a real instrument).

    Each tick: the autopilot link pumped (its messages onto the blackboard, our heartbeat); then the
    readers: the ground station's commands to us, the plugs' readers (other links, sensors, operator
    inputs), what derives from them (heading filter, RC switches, a person's intervention); the
    tree; the writers: the ground station's reports, the plugs' writers; the link flushed (stream
    set-up, route uploads, parameter asks, then the commands the tick asked for).
    """
    blackboard.for_runtime(f"{mission.vehicle} {mission.name!r}")  # its own: two runtimes in one process share no key
    state = MissionState()
    status = StatusSource("runtime status", clock)
    tree_watch = TreeWatch()
    ap = AutopilotLink(
        link, clock, mission, state, system_id=system_id, target_system=target_system, target_component=target_component, forced=autopilot,
        period_s=1.0 / rate_hz,
    )  # fmt: skip
    persons = PersonsCommands(clock, state)  # a person's arm, disarm and mode, followed to what the vehicle did
    operator = Operator(
        state,
        mission.vehicle,
        status=status.snapshot,
        clock=clock,
        # what `executive run` refuses of a mission file, for every mission `ctl upload` brings (executive.admission.checks)
        refuse=lambda m: "; ".join(admission.refusals(m, autopilot=ap.autopilot.backend.name, simulator=simulated_vehicle)) or None,
        autopilot=ap.autopilot,  # a person's arm, disarm and mode
        tree=tree_watch.view,
        autopilot_name=lambda: ap.autopilot.backend.name,
        persons=persons,
    )
    ground_station = GroundStationControl([link], clock, operator, system_id=system_id)
    commands = FunctionService("ground-station commands", lambda: ground_station.answer(ap.commands_for_us(), link))
    wiring = Wiring(mission, clock, system_id, state, status, operator, ap, ground_station, simulated_vehicle)
    wiring.readers.append(commands)
    wiring.observers.append(tree_watch)  # first: the recorders see what the tree waits for at the tick they record
    wiring.writers.append(ground_station)
    for plug in plugs:
        plug(wiring)
    # a mode change we did not ask for, mid-mission, pauses the mission (a person has the vehicle): judged once the RC is read
    intervention = InterventionWatch(clock, ap.autopilot, state, vehicle_profile(mission.vehicle), mission.rc)
    wiring.readers += [HeadingFilter(clock), RcReader(mission.rc, clock, rc_switch_channels(mission)), persons, intervention]
    wiring.readers.append(EnergyWatch(clock, state, lambda: ap.autopilot.backend.name))
    return Runtime(
        mission,
        clock,
        ap,
        state,
        operator=operator,
        status=status,
        readers=wiring.readers,
        writers=wiring.writers,
        paced=wiring.paced,
        observers=wiring.observers,
        closers=wiring.closers,
        reporters=[commands, ground_station],
        simulated_vehicle=simulated_vehicle,
        rate_hz=rate_hz,
        safe_timeout_s=safe_timeout_s,
        root=root,
        progress=progress,
        reach=ReachGate(clock, show=tree_watch.hold),  # the tree watch: the one writer of /mission/waiting
    )


# -- plugs -----------------------------------------------------------------------------------


class _BaseDrive:
    """The AgileX base driven at its own rate: the autopilot's skid-steer outputs while a mission runs, else zero motion."""

    def __init__(self, drive: DriveBridge, state: MissionState) -> None:
        self._drive = drive
        self._state = state

    def service(self) -> None:
        self._drive.in_control = self._state.status in (MissionStatus.RUNNING, MissionStatus.PAUSED)

    @property
    def next_due(self) -> float:
        return self._drive.next_due

    def pace(self) -> bool:
        return self._drive.service()

    def stop(self) -> None:
        self._drive.in_control = False
        self._drive.service()


def can_base(bus: can.BusABC) -> Plug:
    """The AgileX base on ``bus``: its frames read each tick; the autopilot's skid-steer outputs driven onto it at 50 Hz."""

    def plug(w: Wiring) -> None:
        from executive.io.can import CanReader, DriveBridge

        reader = CanReader(bus, w.clock, rc=w.mission.rc.source == "can")
        w.readers.append(FunctionService("can reader", reader.drain))
        drive = _BaseDrive(DriveBridge(bus, w.clock), w.mission_state)
        w.writers.append(drive)
        w.paced.append(drive)

    return plug


def obstacle_camera(sock: socket.socket) -> Plug:
    """A camera's obstacle distances on ``sock``: read each tick, each new scan sent on to the autopilot."""

    def plug(w: Wiring) -> None:
        from executive.io.obstacles import ObstacleForwarder, ObstacleReceiver

        receiver = ObstacleReceiver(sock, w.clock)
        w.readers.append(FunctionService("obstacle receiver", receiver.drain))
        w.writers.append(ObstacleForwarder(w.link.transport, w.clock))

    return plug


def ground_stations(link: Link, allowed_systems: Iterable[int] = (255,)) -> Plug:
    """Ground stations on their own endpoint ``link``: their commands answered (from ``allowed_systems`` only), the mission reported to them.

    Our HEARTBEAT goes there too at 1 Hz (an onboard controller, component 191, no autopilot): a ground station lists the executive
    as a component of the vehicle only once it hears one.
    """

    def plug(w: Wiring) -> None:
        gcs = w.ground_station
        gcs.serve(link, allowed_systems)
        w.writers.append(Heartbeat(link, w.clock, system_id=w.system_id))
        w.readers.append(FunctionService("ground stations", lambda: gcs.answer(iter(link.recv, None), link)))

    return plug


def control_socket(path: str) -> Plug:
    """The control socket at ``path`` for ``executive ctl``: its requests go to the operator."""

    def plug(w: Wiring) -> None:
        from executive.io.control import ControlServer

        def answer(request: dict[str, Any]) -> dict[str, Any]:
            args = {k: v for k, v in request.items() if k != "op"}
            return w.operator.request(request["op"], source="ctl", **args).to_dict()

        server = ControlServer(path, answer)
        w.readers.append(server)
        w.closers.append(server.close)

    return plug


def service_manager(watchdog: Watchdog) -> Plug:
    """Under systemd: ``watchdog`` fed from the tick loop (WATCHDOG=1), with the status line as the service's STATUS=."""

    def plug(w: Wiring) -> None:
        from executive.operator.status import status_line

        def status() -> tuple[object, str]:
            now = w.status.snapshot()
            return (now["state"], now["leg"], now["mode"], now["armed"]), status_line(now)

        watchdog.status = status
        w.writers.append(watchdog)

    return plug
