"""The route on the autopilot and driven in AUTO: ArduPilot drives its own mission, the executive keeps and follows it.

The route lives in the mission state (an operator records and edits it while driving); these
behaviours keep the autopilot's mission equal to it and follow the autopilot while AUTO drives it:

- :class:`KeepRouteOnAutopilot` uploads the route whenever what the autopilot holds (as last read
  back, ``/vehicle/mission_items``) is not it: one NAV_WAYPOINT per waypoint, items 1..n after a
  home item 0, read back item by item before the upload counts.
- :class:`DriveRouteInAuto` waits for the operator to put the vehicle in AUTO with the route on the
  autopilot, follows MISSION_CURRENT and MISSION_ITEM_REACHED into the mission's leg index, and
  succeeds when the last waypoint is reached.

Both need ``mission_state`` and the ``autopilot`` port from ``tree.setup``. A waypoint's
``speed_m_s`` is not uploaded: AUTO drives at the autopilot's own speed (WP_SPEED).
"""

from __future__ import annotations

from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, ExecutiveBehaviour, TimedBehaviour
from executive.mission.port import MissionPort
from executive.mission.route import Route
from executive.world import geo
from executive.world.clock import Clock
from executive.world.state import (
    MISSION_STATE_COMPLETE,
    GlobalPosition,
    HomePosition,
    MissionCurrent,
    MissionItemReached,
    MissionTransferStatus,
    TransferState,
)

#: The autopilot mode that drives its own mission.
AUTO = "AUTO"


class MissionTransferFollower(ExecutiveBehaviour):
    """Follows one mission transfer of its own at a time (``/link/mission_transfer``); a failed one is tried again ``retry_s`` later."""

    needs = ("clock", "mission_state", "autopilot")
    mission_state: MissionPort
    autopilot: AutopilotPort

    def __init__(self, name: str, retry_s: float = 2.0) -> None:
        super().__init__(name)
        self.retry_s = retry_s
        # kept across re-entries: a transfer started before a guard failed goes on
        self._ticket: int | None = None
        self.failure = ""
        self._failed_at = float("-inf")

    def _settle(self) -> bool:
        """Follow our transfer; True while it runs."""
        if self._ticket is None:
            return False
        status: MissionTransferStatus | None = self.get("/link/mission_transfer")
        if status is None or status.ticket != self._ticket:  # superseded by another request
            self._ticket = None
            return False
        if status.state is TransferState.IN_PROGRESS:
            return True
        self._ticket = None
        if status.state is TransferState.FAILED:
            self.failure, self._failed_at = status.reason, self.clock.now()
        else:
            self.failure = ""
        return False

    def _may_start(self) -> bool:
        """No transfer runs (ours or another's) and no failure is being waited out."""
        return self.autopilot.route_transfer_idle and self.clock.now() - self._failed_at >= self.retry_s

    def _started(self, ticket: int) -> None:
        self._ticket = ticket


class KeepRouteOnAutopilot(MissionTransferFollower):
    """Upload the mission state's route whenever the autopilot's mission is not it; never ends (RUNNING).

    One upload at a time, with the autopilot's home (``/vehicle/home``, else a placeholder ArduPilot
    replaces) as item 0 and a read-back before it counts. A route changed during an upload is
    uploaded again once that one ends. A failed upload is tried again ``retry_s`` later; the
    reason stays in the feedback meanwhile. Another component's transfer in progress is waited for.
    """

    reads = ("/link/mission_transfer", "/vehicle/mission_items", "/vehicle/home")
    clock: Clock

    def __init__(self, name: str = "Keep the route on the autopilot", retry_s: float = 5.0) -> None:
        super().__init__(name, retry_s)

    def update(self) -> Status:
        now = self.clock.now()
        if self._settle():
            status: MissionTransferStatus = self.get("/link/mission_transfer")
            step = "reading back" if status.verifying else "sending"
            self.feedback_message = f"uploading the route: {step} {status.progress}/{status.total} items"
            return RUNNING
        waypoints = self.mission_state.route.waypoints
        why = self.autopilot.route_differs(waypoints, self.get("/vehicle/mission_items"))
        if why is None:
            self.failure = ""
            self.feedback_message = f"the autopilot holds the route: {len(waypoints)} waypoints, read back"
            return RUNNING
        if self.failure and now - self._failed_at < self.retry_s:
            self.feedback_message = f"upload failed ({self.failure}); trying again in {self._failed_at + self.retry_s - now:.0f} s"
            return RUNNING
        if not self.autopilot.route_transfer_idle:
            self.feedback_message = "waiting for another mission transfer to end"
            return RUNNING
        home: HomePosition | None = self.get("/vehicle/home")
        self._started(self.autopilot.upload_route(waypoints, home))
        self.feedback_message = f"uploading {len(waypoints)} waypoints: {why}"
        return RUNNING


#: Waypoints closer than this to the first are the same place: a route of them was recorded by a vehicle that never moved.
SAME_PLACE_M = 1.0


class DriveRouteInAuto(TimedBehaviour):
    """Wait for the operator to drive the route in AUTO, follow the autopilot along it; SUCCESS at the last waypoint.

    Waiting (RUNNING, saying for what): a route recorded, the same route on the autopilot, the
    mode AUTO, the vehicle armed. Waiting longer than ``operator_timeout_s`` at a stretch: FAILURE.
    The wait starts again whenever the drive stops (the operator takes the vehicle out of AUTO or
    disarms it, the route changes and is uploaded again).

    Driving: the autopilot's MISSION_CURRENT (item k: legs before k done; mission_state 5: all
    done) reported since the tick before the drive started, and the highest MISSION_ITEM_REACHED
    reported in this run (latched by the reader: one that arrives in the tick the vehicle enters
    AUTO, or before its heartbeat shows AUTO, counts) move the mission's leg index forward; the
    feedback is the next waypoint, its distance and bearing. No waypoint reached within
    ``leg_timeout_s`` of driving: FAILURE (the autopilot holds still in AUTO, and says nothing).
    SUCCESS when the last waypoint is reached, unless every waypoint is the same place (the vehicle
    never moved while the route was recorded): then FAILURE, nothing was driven.
    """

    reads = ("/vehicle/mode", "/vehicle/armed", "/vehicle/mission_items", "/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/position")
    needs = ("clock", "mission_state", "autopilot")
    from_mission = {"operator_timeout_s": "rc_route.operator_timeout_s", "leg_timeout_s": "limits.leg_timeout_s"}
    mission_state: MissionPort
    autopilot: AutopilotPort

    def __init__(self, operator_timeout_s: float, name: str = "Drive the route in AUTO", leg_timeout_s: float = 600.0) -> None:
        super().__init__(name)
        self.operator_timeout_s = operator_timeout_s
        self.leg_timeout_s = leg_timeout_s
        self._waiting_since = 0.0
        self._driving_since: float | None = None
        self._run_started: float | None = None  # the first tick of this run: reports before it are another run's
        self._last_update = float("-inf")
        self._progress_at = 0.0  # when the leg index last moved while driving

    def initialise(self) -> None:
        super().initialise()
        self._waiting_since = self.started
        self._driving_since = None
        if self._run_started is None:
            self._run_started = self._last_update = self.started

    def update(self) -> Status:
        now, before = self.clock.now(), self._last_update
        self._last_update = now
        route = self.mission_state.route
        why = self._why_not_driving(route)
        if why is not None:
            if self._driving_since is not None:
                self._driving_since, self._waiting_since = None, now
            waited = now - self._waiting_since
            if waited > self.operator_timeout_s:
                self.feedback_message = f"the operator did not drive the route within {self.operator_timeout_s:g} s: {why}"
                return FAILURE
            self.feedback_message = f"waiting for the operator ({waited:.0f}/{self.operator_timeout_s:g} s): {why}"
            return RUNNING
        if self._driving_since is None:
            self._driving_since = before  # what the readers drained in this tick arrived after the last one
            self._progress_at = now
        leg_before = self.mission_state.leg_index
        self._follow_autopilot(len(route))
        n, leg = len(route), self.mission_state.leg_index
        if leg != leg_before:
            self._progress_at = now
        if leg >= n:
            return self._done(route)
        target = route.waypoints[leg]
        position: GlobalPosition | None = self.get("/vehicle/position")
        where = ""
        if position is not None:
            distance, bearing = geo.distance_bearing(position.lat, position.lon, target.lat, target.lon)
            where = f": {distance:.1f} m at {bearing:03.0f}°"
        if now - self._progress_at > self.leg_timeout_s:
            self.feedback_message = f"no progress in AUTO: waypoint {leg + 1}/{n} not reached within {self.leg_timeout_s:g} s{where}"
            return FAILURE
        self.feedback_message = f"waypoint {leg + 1}/{n}{where}"
        return RUNNING

    def _done(self, route: Route) -> Status:
        n = len(route)
        first = route.waypoints[0]
        if n > 1 and all(geo.distance(first.lat, first.lon, wp.lat, wp.lon) < SAME_PLACE_M for wp in route.waypoints):
            self.feedback_message = (
                f"the route's {n} waypoints are all one place (the vehicle never moved while they were recorded): nothing was driven"
            )
            return FAILURE
        self.feedback_message = f"route done: {n}/{n} waypoints reached"
        return SUCCESS

    def _why_not_driving(self, route: Route) -> str | None:
        if not route.waypoints:
            return "no route recorded (switch A down with the knob in the middle adds a waypoint here)"
        why = self.autopilot.route_differs(route.waypoints, self.get("/vehicle/mission_items"))
        if why is not None:
            return f"the route is not on the autopilot yet: {why}"
        mode = self.get("/vehicle/mode")
        if mode != self.autopilot.mode_name(AUTO):
            return f"switch C to the middle (AUTO) drives the route; the mode is {mode}"
        if not self.get("/vehicle/armed"):
            return "the vehicle is disarmed (it arms in MANUAL only: switch C up, switch D down)"
        return None

    def _follow_autopilot(self, n: int) -> None:
        """Move the leg index up to what the autopilot reported."""
        assert self._driving_since is not None and self._run_started is not None
        done = 0
        first = self.autopilot.capabilities.first_item_seq  # the first waypoint's item: 1 after ArduPilot's home, 0 on PX4
        current: MissionCurrent | None = self.get("/vehicle/mission_current")
        if current is not None and current.time > self._driving_since:
            if current.state == MISSION_STATE_COMPLETE:
                done = n
            elif current.seq >= first:
                done = current.seq - first
        reached: MissionItemReached | None = self.get("/vehicle/mission_reached")
        if reached is not None and reached.time >= self._run_started:
            done = max(done, reached.highest + 1 - first)
        while self.mission_state.leg_index < min(done, n):
            self.mission_state.leg_done()
