"""How a runtime is put together: the autopilot link every run has, and plugs for the optional parts.

:func:`build_runtime` is the builder (``executive run`` composes its plugs from the command line;
tests and benchmarks call it directly). A plug is a function of the :class:`Wiring` that adds
services to it: a new link (a sensor, a viewer, another autopilot's protocol) is a new plug.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from executive import admission, blackboard
from executive.autopilot import AutopilotName
from executive.autopilot.selection import Autopilot
from executive.clock import Clock
from executive.intervention import InterventionWatch
from executive.io.heading import HeadingFilter
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.dialect import mavlink
from executive.io.mavlink.gcs import GroundStationControl
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.link import Link, PymavlinkLink
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.parameters import ParameterWatch
from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.route_keeper import RouteKeeper
from executive.io.mavlink.streams import StreamRequester, rates_for
from executive.io.rc import RcReader
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission, rc_switch_channels
from executive.mission.reload import REPLACED
from executive.operator import Operator
from executive.runtime import Runtime
from executive.services import PacedService, RunObserver, Service, Step
from executive.status import StatusSource
from executive.vehicles import PROFILES
from executive.waiting import TreeWatch

if TYPE_CHECKING:
    import can
    import py_trees

    from executive.io.can.drive import DriveBridge
    from executive.io.systemd import Watchdog
    from executive.journal import Journal
    from executive.progress import Progress
    from executive.snapshots import SnapshotRecorder
    from executive.web.server import WebServer


@dataclass
class AutopilotLink:
    """The MAVLink side of every run: commands and acks, mission transfers, telemetry, our heartbeat, streams, route uploads, ground stations."""

    link: Link
    commander: Commander
    mission_transfer: MissionTransfer
    reader: MavlinkReader
    heartbeat: Heartbeat
    streams: StreamRequester
    route_keeper: RouteKeeper
    ground_station: GroundStationControl
    #: What the tree asks of the autopilot: intents, turned into its firmware's commands by the back end its heartbeat names (or forced).
    port: Autopilot


@dataclass
class Wiring:
    """What the plugs see and add to; the runtime runs its services in list order."""

    mission: Mission
    clock: Clock
    system_id: int
    mission_state: MissionState
    status: StatusSource
    operator: Operator
    autopilot: AutopilotLink
    simulated_vehicle: bool = True  # the built-in simulator: a simulated instrument may take the samples
    readers: list[Service] = field(default_factory=list)
    writers: list[Service] = field(default_factory=list)
    paced: list[PacedService] = field(default_factory=list)
    observers: list[RunObserver] = field(default_factory=list)
    closers: list[Callable[[], object]] = field(default_factory=list)


Plug = Callable[[Wiring], None]


def _autopilot_link(
    mission: Mission,
    link: Link,
    clock: Clock,
    state: MissionState,
    operator: Operator,
    system_id: int,
    target: tuple[int | None, int],
    forced: AutopilotName | None = None,
) -> AutopilotLink:
    commander = Commander(link, clock, PROFILES[mission.vehicle], system_id=system_id)
    transfer = MissionTransfer(link, clock, system_id=system_id)
    reader = MavlinkReader(
        link,
        clock,
        commander,
        link_timeout_s=mission.limits.link_timeout_s,
        mission=transfer,
        rc_source=mission.rc.source == "mavlink",
        target_system=target[0],
        target_component=target[1],
    )
    if isinstance(link, PymavlinkLink):
        link.skim(reader.kinds_read)  # what the reader does not read is counted from its header, never decoded
    streams = StreamRequester(commander, rates_for(mission.vehicle))
    reader.on_reconnect = streams.restart
    #: After each edit of the route (any tree, any source), the autopilot is given it: uploaded, read back, retried.
    keeper = RouteKeeper(state, transfer, commander, clock)
    ground_station = GroundStationControl([link], clock, operator, system_id=system_id)
    reader.on_command = ground_station.on_command
    heartbeat = Heartbeat(link, clock, system_id=system_id)
    port = Autopilot(commander, transfer, PROFILES[mission.vehicle], forced=forced)
    reader.on_autopilot = port.adopt

    def streams_of(name: str) -> None:
        streams.rates = rates_for(mission.vehicle, name)
        heartbeat.mav_type = mavlink.MAV_TYPE_GCS if name == "px4" else mavlink.MAV_TYPE_ONBOARD_CONTROLLER

    port.on_backend = streams_of
    return AutopilotLink(link, commander, transfer, reader, heartbeat, streams, keeper, ground_station, port)


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

    Readers run in this order: the autopilot link, the plugs' readers (other links, sensors,
    operator inputs), then what derives from them (heading filter, RC switches) and our heartbeat.
    Writers: the autopilot's streams, ground-station reports and route uploads, the plugs'
    writers, then the commands the tick asked for.
    """
    blackboard.reset()
    state = MissionState()
    status = StatusSource("runtime status", clock)
    tree_watch = TreeWatch()
    operator = Operator(
        state,
        mission.vehicle,
        status=status.snapshot,
        clock=clock,
        # what `executive run` refuses of a mission file, for every mission `ctl upload` brings (executive.admission)
        refuse=lambda m: "; ".join(admission.refusals(m, autopilot=ap.port.backend.name, simulator=simulated_vehicle)) or None,
        tree=tree_watch.view,
        autopilot_name=lambda: ap.port.backend.name,  # asked only once the link below is made
    )
    ap = _autopilot_link(mission, link, clock, state, operator, system_id, (target_system, target_component), autopilot)
    operator.autopilot = ap.port  # a person's arm, disarm and mode
    wiring = Wiring(mission, clock, system_id, state, status, operator, ap, simulated_vehicle)
    wiring.readers.append(Step("mavlink reader", ap.reader.drain))
    wiring.observers.append(tree_watch)  # first: the recorders see what the tree waits for at the tick they record
    wiring.writers += [ap.streams, ap.ground_station, ap.route_keeper, ParameterWatch(ap.port, clock)]
    for plug in plugs:
        plug(wiring)
    # a mode change we did not ask for, mid-mission, pauses the mission (a person has the vehicle): judged once the RC is read
    intervention = InterventionWatch(clock, ap.port, state, PROFILES[mission.vehicle], mission.rc)
    wiring.readers += [HeadingFilter(clock), RcReader(mission.rc, clock, rc_switch_channels(mission)), intervention, ap.heartbeat]
    wiring.writers += [
        Step("autopilot port", ap.port.service),
        Step("commands", ap.commander.flush),
        Step("mission transfers", ap.mission_transfer.flush),
    ]
    return Runtime(wiring, rate_hz=rate_hz, safe_timeout_s=safe_timeout_s, root=root, progress=progress)


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
        w.readers.append(Step("can reader", reader.drain))
        drive = _BaseDrive(DriveBridge(bus, w.clock), w.mission_state)
        w.writers.append(drive)
        w.paced.append(drive)

    return plug


def obstacle_camera(sock: socket.socket) -> Plug:
    """A camera's obstacle distances on ``sock``: read each tick, each new scan sent on to the autopilot."""

    def plug(w: Wiring) -> None:
        from executive.io.obstacles import ObstacleForwarder, ObstacleReceiver

        receiver = ObstacleReceiver(sock, w.clock)
        w.readers.append(Step("obstacle receiver", receiver.drain))
        w.writers.append(ObstacleForwarder(w.autopilot.link, w.clock))

    return plug


def ground_stations(link: Link, allowed_systems: Iterable[int] = (255,)) -> Plug:
    """Ground stations on their own endpoint ``link``: their commands answered (from ``allowed_systems`` only), the mission reported to them.

    Our HEARTBEAT goes there too at 1 Hz (an onboard controller, component 191, no autopilot): a ground station lists the executive
    as a component of the vehicle only once it hears one.
    """

    def plug(w: Wiring) -> None:
        gcs = w.autopilot.ground_station
        gcs.links.append(link)
        gcs.allowed_systems = frozenset(allowed_systems)
        w.writers.append(Heartbeat(link, w.clock, system_id=w.system_id))

        def listen() -> None:
            while (msg := link.recv()) is not None:
                if msg.get_type() == "COMMAND_LONG":
                    gcs.on_command(msg, link)

        w.readers.append(Step("ground stations", listen))

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


class _JournalRuns:
    """The journal's part in a run: the run begun and ended, each leg recorded (with where the vehicle was) as it changes.

    A run ended as REPLACED (hot reload) is continued by the next, the new mission's: it begins
    with the event, the samples kept (renumbered to its legs) and its leg, so that ``--resume``
    after a crash finds them there.
    """

    def __init__(self, journal: Journal, state: MissionState) -> None:
        self._journal = journal
        self._state = state
        self._bb = blackboard.reader("journal", ["/vehicle/position"])
        self._replaced: tuple[int, str] | None = None  # the run a replacement ended, and why

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        replaced, self._replaced = self._replaced, None
        if replaced is None:
            self._journal.begin_run(mission, resumed_from=resumed_from)
            return
        self._journal.begin_run(mission, resumed_from=replaced[0])
        self._journal.event("mission", replaced[1])
        self._journal.carry_samples(self._state.samples)
        self.ticked(0, 0.0)

    def ticked(self, tick: int, now: float) -> None:
        position = self._bb.get("/vehicle/position")
        self._journal.observe_leg(self._state, *((position.lat, position.lon) if position else (None, None)))

    def end(self, status: str, reason: str) -> None:
        if status == REPLACED and self._journal.run is not None:
            self._journal.event("mission", reason)
            self._replaced = (self._journal.run, reason)
        self._journal.end_run(status, reason)


def journal_recorder(journal: Journal) -> Plug:
    """Record the run in ``journal``: transitions, legs, samples, route edits, the outcome."""

    def plug(w: Wiring) -> None:
        journal.attach(w.mission_state)
        w.observers.append(_JournalRuns(journal, w.mission_state))

    return plug


class _SnapshotRuns:
    def __init__(self, recorder: SnapshotRecorder) -> None:
        self._recorder = recorder

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self._recorder.attach(root)

    def ticked(self, tick: int, now: float) -> None:
        self._recorder.record(tick, now)

    def end(self, status: str, reason: str) -> None:
        self._recorder.record_end()  # the last tick as the run ended; the file goes on with the next run's tree


def snapshot_recorder(recorder: SnapshotRecorder) -> Plug:
    """Record every tick of the tree (node statuses, blackboard changes) for ``executive replay``."""

    def plug(w: Wiring) -> None:
        w.observers.append(_SnapshotRuns(recorder))

    return plug


def service_manager(watchdog: Watchdog) -> Plug:
    """Under systemd: ``watchdog`` fed from the tick loop (WATCHDOG=1), with the status line as the service's STATUS=."""

    def plug(w: Wiring) -> None:
        from executive.status import status_line

        def status() -> tuple[object, str]:
            now = w.status.snapshot()
            return (now["state"], now["leg"], now["mode"], now["armed"]), status_line(now)

        watchdog.status = status
        w.writers.append(watchdog)

    return plug


def live_view(server: WebServer) -> Plug:
    """The live view in a browser on ``server``: a frame handed over after each tick it asks for one, its buttons' requests to the operator."""

    def plug(w: Wiring) -> None:
        from executive.web.feed import LiveFeed
        from executive.web.server import LiveSource

        feed = LiveFeed(w.mission_state, w.status, w.operator, w.clock.now)
        w.readers.append(Step("live view requests", feed.answer))
        w.writers.append(Step("live view", feed.publish))
        w.observers.append(feed)
        server.start(LiveSource(feed), ask=feed.ask)
        w.closers.append(server.close)

    return plug
