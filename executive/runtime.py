"""The onboard runtime: a fixed-rate loop of drain IO -> blackboard -> tick -> send commands.

It owns the process-level safety: a stop request (Ctrl-C, SIGTERM), a failed mission and an
exception inside a behaviour all end with the vehicle commanded into its safe mode.
"""

from __future__ import annotations

import logging
import socket
import types
from dataclasses import dataclass
from typing import Any

import can
import py_trees
from py_trees.common import Status

import trees
from executive import blackboard
from executive.behaviours.failsafe import failsafe_mode
from executive.clock import Clock
from executive.intervention import InterventionWatch
from executive.io.can import CanReader, DriveBridge
from executive.io.control import ControlServer
from executive.io.heading import HeadingFilter
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.gcs import GroundStationControl
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.link import Link
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.route_keeper import RouteKeeper
from executive.io.mavlink.streams import StreamRequester, rates_for
from executive.io.obstacles import ObstacleForwarder, ObstacleReceiver
from executive.io.rc import RcReader
from executive.io.sampler import SimulatedSampler
from executive.journal import Journal, ResumePoint
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission, SamplingOptions
from executive.operator import Operator
from executive.progress import Progress
from executive.snapshots import SnapshotRecorder
from executive.state import SwitchPosition
from executive.status import StatusSource
from executive.vehicles import PROFILES

log = logging.getLogger(__name__)


class BehaviourCrashed(RuntimeError):
    """A behaviour raised during a tick; ``path`` names it from the root."""

    def __init__(self, path: str, error: BaseException) -> None:
        super().__init__(f"{path}: {type(error).__name__}: {error}")
        self.path = path
        self.error = error


@dataclass(frozen=True)
class Outcome:
    """How a run ended."""

    status: MissionStatus
    reason: str
    ticks: int


def behaviour_path(node: py_trees.behaviour.Behaviour) -> str:
    """``Mission/Route or hold/Guarded route/EKF ok?``"""
    names = []
    current: py_trees.behaviour.Behaviour | None = node
    while current is not None:
        names.append(current.name)
        current = current.parent
    return "/".join(reversed(names))


def _crashed_behaviour(tb: types.TracebackType | None) -> py_trees.behaviour.Behaviour | None:
    """The innermost behaviour whose method is on the traceback."""
    found = None
    while tb is not None:
        candidate = tb.tb_frame.f_locals.get("self")
        if isinstance(candidate, py_trees.behaviour.Behaviour):
            found = candidate
        tb = tb.tb_next
    return found


def explain_failure(root: py_trees.behaviour.Behaviour) -> str:
    """The reason for a failed tree: the shallowest failed node that says why."""
    best: tuple[int, str] | None = None
    for node in root.iterate():
        if node.status == Status.FAILURE and node.feedback_message:
            depth = behaviour_path(node).count("/")
            if best is None or depth <= best[0]:
                best = (depth, f"{node.name}: {node.feedback_message}")
    return best[1] if best else "the mission tree failed"


class Runtime:
    """One executive attached to one vehicle: IO, the mission lifecycle, and the tree of the running mission.

    The tree is built when a mission starts (from READY, or again after it ended), so an operator
    can upload another mission and start it without restarting the executive. ``serve`` keeps
    the executive up between missions, waiting for operator requests, instead of returning when
    the mission ends.
    """

    def __init__(
        self,
        mission: Mission,
        link: Link,
        clock: Clock,
        *,
        rate_hz: float = 10.0,
        system_id: int = 1,
        progress: Progress | None = None,
        safe_timeout_s: float = 5.0,
        root: py_trees.behaviour.Behaviour | None = None,
        control_socket: str | None = None,
        gcs_link: Link | None = None,
        gcs_systems: tuple[int, ...] = (255,),
        journal: Journal | None = None,
        snapshots: SnapshotRecorder | None = None,
        can_bus: can.BusABC | None = None,
        obstacle_socket: socket.socket | None = None,
    ) -> None:
        """``root`` replaces the tree the first mission selects (for tests and tools)."""
        blackboard.reset()
        self.mission = mission
        self.clock = clock
        self.period_s = 1.0 / rate_hz
        self.profile = PROFILES[mission.vehicle]
        self.commander = Commander(link, clock, self.profile, system_id=system_id)
        self.mission_transfer = MissionTransfer(link, clock, system_id=system_id)
        self.reader = MavlinkReader(
            link,
            clock,
            self.commander,
            link_timeout_s=mission.limits.link_timeout_s,
            mission=self.mission_transfer,
            rc_source=mission.rc.source == "mavlink",
        )
        self.rc = RcReader(mission.rc, clock)
        self.heading = HeadingFilter(clock)
        #: The AgileX base: its frames read each tick; the autopilot's skid-steer outputs driven onto it at 50 Hz.
        self.can_reader = CanReader(can_bus, clock, rc=mission.rc.source == "can") if can_bus is not None else None
        self.drive = DriveBridge(can_bus, clock) if can_bus is not None else None
        #: A camera's obstacle distances: read each tick, each new scan sent on to the autopilot.
        self.obstacles = ObstacleReceiver(obstacle_socket, clock) if obstacle_socket is not None else None
        self.obstacle_forwarder = ObstacleForwarder(link, clock) if obstacle_socket is not None else None
        self.heartbeat = Heartbeat(link, clock, system_id=system_id)
        self.streams = StreamRequester(self.commander, rates_for(mission.vehicle))
        self.reader.on_reconnect = self.streams.restart
        self.mission_state = MissionState()
        self.mission_state.listeners.append(self._on_transition)
        #: After each edit of the route (any tree, any source), the autopilot is given it: uploaded, read back, retried.
        self.route_keeper = RouteKeeper(self.mission_state, self.mission_transfer, self.commander, clock)
        self.status = StatusSource("runtime status")
        self.operator = Operator(self.mission_state, mission.vehicle, status=self.status.snapshot, clock=clock)
        self.gcs_link = gcs_link
        self.ground_station = GroundStationControl(
            [link, *([gcs_link] if gcs_link else [])], clock, self.operator, system_id=system_id, allowed_systems=gcs_systems
        )
        self.reader.on_command = self.ground_station.on_command
        self.control = ControlServer(control_socket, self._on_control_request) if control_socket else None
        self.journal = journal
        self.snapshots = snapshots
        self._resume: ResumePoint | None = None
        if journal is not None:
            journal.attach(self.mission_state)
        self.sampler: SimulatedSampler | None = None
        self._next_root = root
        self.tree: py_trees.trees.BehaviourTree | None = None
        self.mission_state.upload(mission)
        self.progress = progress
        #: A mode change we did not ask for, mid-mission, pauses the mission: a person has the vehicle.
        self.intervention = InterventionWatch(clock, self.commander, self.mission_state, self.profile, takeover=self._takeover)
        self._bb = blackboard.reader("runtime", ["/vehicle/mode", "/link/up", "/rc/channels", "/rc/switches", "/vehicle/position"])
        self.safe_timeout_s = safe_timeout_s
        self.ticks = 0
        self._stop_reason: str | None = None

    # -- phases ------------------------------------------------------------------------------
    def connect(self, timeout_s: float) -> bool:
        """Announce ourselves and wait for the autopilot's heartbeat (bounded)."""
        deadline = self.clock.now() + timeout_s
        while self.clock.now() < deadline:
            self.heartbeat.service()
            self.reader.drain()
            if self.reader.autopilot is not None:
                return True
            self.clock.sleep_until(self.clock.now() + self.period_s)
        return False

    def tick(self) -> Status:
        """One tick: drain the links, answer the operator, tick the tree, send what was asked for.

        Returns the tree's status (INVALID when no mission is active).
        """
        self.reader.drain()
        if self.can_reader is not None:
            self.can_reader.drain()
        if self.obstacles is not None:
            self.obstacles.drain()
        self.heading.service()
        self.rc.service()
        self.intervention.service()
        self.heartbeat.service()
        self._serve_operator()
        status = Status.INVALID
        if self.tree is not None and self.mission_state.status in (MissionStatus.RUNNING, MissionStatus.PAUSED):
            try:
                self.tree.tick()
            except Exception as exc:
                node = _crashed_behaviour(exc.__traceback__)
                raise BehaviourCrashed(behaviour_path(node) if node else "(tree)", exc) from exc
            status = self.tree.root.status
            if self.snapshots is not None:
                self.snapshots.record(self.ticks, self.clock.now())
        if self.journal is not None:
            position = self._bb.get("/vehicle/position")
            self.journal.observe_leg(self.mission_state, *((position.lat, position.lon) if position else (None, None)))
        if self.sampler is not None:
            self.sampler.service()
        self.streams.service()
        self.ground_station.service()
        self.route_keeper.service()
        if self.drive is not None:
            self.drive.in_control = self.mission_state.status in (MissionStatus.RUNNING, MissionStatus.PAUSED)
        if self.obstacle_forwarder is not None:
            self.obstacle_forwarder.service()
        self.commander.flush()
        self.mission_transfer.flush()
        self.ticks += 1
        return status

    def request_stop(self, reason: str) -> None:
        """Ask the loop to stop at the next tick (safe from a signal handler)."""
        self._stop_reason = reason

    def run(self, *, start: bool = True, serve: bool = False, resume: ResumePoint | None = None) -> Outcome:
        """Tick at the fixed rate: start the mission (or wait for the operator to), until it ends or, with ``serve``, until stopped.

        ``resume`` (from the journal of a run that never ended) continues at its first unfinished
        leg with the samples it had taken: none is taken twice.
        """
        if start:
            self._resume = resume
            self.mission_state.start()
            if resume is not None:
                if resume.route is not None:  # the operator had edited it: that is the route being driven
                    route = resume.route
                    reason = "the route as last edited, from the journal"
                    self.mission_state.set_route(route.waypoints, reason, leg_index=route.current, home=route.home)
                self.mission_state.continue_from(resume.leg_index, resume.samples)
        outcome = Outcome(self.mission_state.status, self.mission_state.reason, self.ticks)
        next_tick = self.clock.now()
        try:
            while True:
                if self._stop_reason is not None:
                    if self.mission_state.status in (MissionStatus.RUNNING, MissionStatus.PAUSED):
                        return self._abort(f"stopped: {self._stop_reason}")
                    self.make_safe()
                    return outcome
                ended = self._tick_once()
                if ended is not None:
                    outcome = ended
                    if not serve:
                        return outcome
                next_tick += self.period_s
                now = self.clock.now()
                if next_tick < now - self.period_s:  # fell behind by more than a tick: do not try to catch up
                    next_tick = now
                self._wait_until(next_tick)
        finally:
            if self.progress:
                self.progress.update(force=True)
                self.progress.close()

    def _wait_until(self, t: float) -> None:
        """Sleep until the next tick, sending the base its motion commands (50 Hz) meanwhile."""
        if self.drive is None:
            self.clock.sleep_until(t)
            return
        while self.clock.now() < t:
            self.drive.service()
            self.clock.sleep_until(min(t, self.drive.next_due))

    def close(self) -> None:
        """Release the control socket."""
        if self.control is not None:
            self.control.close()

    def make_safe(self) -> bool:
        """Command the vehicle's safe mode (or the mode of the failsafe that ended the mission) and wait (bounded) for the heartbeat to confirm it."""
        safe = self.profile.safe_mode
        if self.tree is not None:
            safe = failsafe_mode(self.tree.root) or safe  # an RTL or a surfacing the mission's failsafe asked for is not undone
            self.tree.interrupt()
            self.tree.root.stop(Status.INVALID)  # stop what is running: a sample in progress is cancelled, not left open
        if self.drive is not None:  # the base stops at once; the autopilot is told below
            self.drive.in_control = False
            self.drive.service()
        person = self._person_has_the_vehicle(safe)
        if person:
            log.warning("not commanding %s: %s", safe, person)
            return False
        deadline = self.clock.now() + self.safe_timeout_s
        requested = False
        while self.clock.now() < deadline:
            self.reader.drain()
            self.heartbeat.service()
            if self._bb.get("/link/up") and self._bb.get("/vehicle/mode") == safe:
                log.info("vehicle in %s", safe)
                return True
            if not requested:
                self.commander.set_mode(safe)
                requested = True
            self.commander.flush()
            self.clock.sleep_until(self.clock.now() + self.period_s / 2)
        log.error("could not confirm %s within %g s", safe, self.safe_timeout_s)
        return False

    def _person_has_the_vehicle(self, ours: str) -> str | None:
        """Why a person has the vehicle, if one has: then hands off.

        The RC take-over switch high, switch C in MANUAL, or a mode in which a person drives (MANUAL,
        ACRO...) other than ``ours`` (the mode a failsafe of ours left it in): set by the RC, a ground
        station, or by us at the operator's request (handed over).
        """
        takeover = self._takeover()
        if takeover is not None:
            return takeover
        mode = self._bb.get("/vehicle/mode")
        if mode in self.profile.pilot_modes and mode != ours:
            return f"the vehicle is in {mode}: a person drives it"
        return None

    def _takeover(self) -> str | None:
        """Why the RC says a person has the vehicle (the take-over switch high, or switch C in MANUAL), if it does."""
        rc = self.mission.rc
        if rc.source == "mavlink":
            channels = self._bb.get("/rc/channels")
            value = channels[rc.takeover_channel - 1] if len(channels) >= rc.takeover_channel else 0
            return f"RC channel {rc.takeover_channel} high ({value} µs): a person has the vehicle" if value > rc.takeover_above_us else None
        switches = self._bb.get("/rc/switches")
        return "RC switch C in MANUAL: a person has the vehicle" if switches is not None and switches.swc == SwitchPosition.UP else None

    def _abort(self, reason: str) -> Outcome:
        log.warning("mission aborted: %s", reason)
        self.make_safe()
        self.mission_state.abort(reason)
        return Outcome(MissionStatus.ABORTED, reason, self.ticks)

    def _tick_once(self) -> Outcome | None:
        """Tick, and end the active mission if it is over; returns how it ended, if it did."""
        active = self.tree is not None
        try:
            status = self.tick()
        except BehaviourCrashed as crash:
            log.error("behaviour crashed: %s", crash, exc_info=crash.error)
            return self._end(self._abort(f"behaviour crashed: {crash}"))
        if self.progress:
            self.progress.update()
        if not active:
            return None
        if self.mission_state.status in (MissionStatus.ABORTED, MissionStatus.IDLE):  # the operator aborted or deleted it
            self.make_safe()
            return self._end(Outcome(self.mission_state.status, self.mission_state.reason, self.ticks))
        if status == Status.SUCCESS:
            self.mission_state.complete()
            return self._end(Outcome(MissionStatus.COMPLETED, "every waypoint reached", self.ticks))
        if status == Status.FAILURE:
            return self._end(self._abort(explain_failure(self.tree.root)))  # type: ignore[union-attr]
        return None

    def _end(self, outcome: Outcome) -> Outcome:
        self.tree = None
        if self.journal is not None:
            self.journal.end_run(str(outcome.status), outcome.reason)
        return outcome

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is MissionStatus.RUNNING and before is not MissionStatus.PAUSED:
            self._install_tree()

    def _install_tree(self) -> None:
        """Build the tree (and its sampler) of the mission that is starting."""
        mission = self.mission_state.mission
        assert mission is not None
        root, self._next_root = self._next_root or trees.build(mission), None
        takes_samples = mission.sampling is not None or any(wp.sample for wp in mission.waypoints)  # the sampling: section is optional
        self.sampler = SimulatedSampler(self.clock, mission.sampling or SamplingOptions()) if takes_samples else None
        self.tree = py_trees.trees.BehaviourTree(root)
        if self.journal is not None:
            self.journal.begin_run(mission, resumed_from=self._resume.run if self._resume else None)
            self._resume = None
        if self.snapshots is not None:
            self.snapshots.attach(root)
        self.tree.setup(
            clock=self.clock, commander=self.commander, mission_state=self.mission_state, mission_transfer=self.mission_transfer, sampler=self.sampler
        )

    def _serve_operator(self) -> None:
        if self.gcs_link is not None:
            while (msg := self.gcs_link.recv()) is not None:
                if msg.get_type() == "COMMAND_LONG":
                    self.ground_station.on_command(msg, self.gcs_link)
        if self.control is not None:
            self.control.service()

    def _on_control_request(self, request: dict[str, Any]) -> dict[str, Any]:
        args = {k: v for k, v in request.items() if k != "op"}
        return self.operator.request(request["op"], source="ctl", **args).to_dict()
