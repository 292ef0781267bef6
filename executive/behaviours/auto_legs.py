"""drive: auto: each leg driven by the autopilot's own AUTO, the autopilot never holding more than a few legs of the route.

A leg is (:func:`executive.trees.parts.auto_leg`): the horizon on the autopilot
(:class:`HorizonOnAutopilot`), its mission at this leg (:class:`AutopilotAtLeg`), AUTO, then the leg
followed (:class:`FollowAutoLeg`). The route stays in the mission state, as in GUIDED; the autopilot
holds its first waypoints up to the current leg's and ``limits.auto_horizon_legs`` beyond it, one
more appended (a partial write, read back) each time a leg is reached. At the last waypoint it
holds, the firmware stops the vehicle by its own mission-end rule (ArduRover MIS_DONE_BEHAVE,
checked at pre-flight): whatever becomes of the executive, the vehicle stops within the horizon.
The horizon always holds the waypoint after the next, so the firmware plans its corners as in a
whole-route AUTO (Rover/mode_auto.cpp do_nav_wp reads the next navigation command when a leg starts).
"""

from __future__ import annotations

from collections.abc import Sequence

from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.behaviours.auto_route import AUTO, MissionTransferFollower
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.mission.model import Waypoint
from executive.mission.port import MissionPort
from executive.world import geo
from executive.world.state import (
    MISSION_STATE_COMPLETE,
    GlobalPosition,
    HomePosition,
    MissionCurrent,
    MissionItemReached,
)


class HorizonOnAutopilot(MissionTransferFollower):
    """SUCCESS while the autopilot holds the route's horizon for the current leg; RUNNING while it is being put there.

    The horizon of leg k: the route's waypoints 1..k+1 at least (through the current leg's), k+1+``horizon_legs``
    at most. Held and a prefix of the route: once the autopilot holds no more than one waypoint beyond the
    current leg's (the least AUTO needs to plan the corner it drives to next), the horizon is filled in one
    burst of appends (SUCCESS meanwhile, while the current leg's is held). Not sooner: the real ArduRover
    restarts the waypoint it drives at every write to its mission in AUTO, wherever the item lies
    (tests/data/ardurover/mission-writes-in-auto-rover.tlog), so the fewer the bursts the less time is
    lost; a horizon of H has one burst every H-1 legs. Anything else (nothing known, another route,
    more than the horizon): the horizon is uploaded whole. Never more than the horizon is sent.
    """

    reads = ("/link/mission_transfer", "/vehicle/mission_items", "/vehicle/home")
    from_mission = {"horizon_legs": "limits.auto_horizon_legs"}
    param_docs = {"horizon_legs": "waypoints the autopilot holds beyond the current leg's", "retry_s": "a failed transfer is tried again after this"}

    def __init__(self, horizon_legs: int = 2, name: str = "Horizon on the autopilot", retry_s: float = 2.0) -> None:
        super().__init__(name, retry_s)
        self.horizon_legs = horizon_legs

    def given_route(self) -> Sequence[Waypoint]:
        """The route as the autopilot is to hold it (a sub's depths bounded by the seabed floor: :mod:`executive.behaviours.auto_depth`)."""
        return self.mission_state.route.waypoints

    def update(self) -> Status:
        busy = self._settle()
        route, leg = self.given_route(), self.mission_state.leg_index
        least, most = min(len(route), leg + 1), min(len(route), leg + 1 + self.horizon_legs)
        held = self.get("/vehicle/mission_items")
        n_held = len(held) if held is not None else 0
        prefix = held is not None and n_held <= most and self.autopilot.route_differs(route[:n_held], held) is None
        if prefix and not busy and n_held < most and n_held - least <= 1 and self._may_start():
            self._started(self._extend(route, n_held, most))
            busy = True
        if prefix and n_held >= least:
            extra = f"; appending up to waypoint {most}" if busy else ""
            self.feedback_message = f"the autopilot holds waypoints 1-{n_held} of {len(route)}{extra}"
            return SUCCESS
        if not busy and not prefix and self._may_start():
            home: HomePosition | None = self.get("/vehicle/home")
            self._started(self.autopilot.upload_route(route[:most], home))
            busy = True
        why = self.autopilot.horizon_differs(route, leg, self.horizon_legs, held)
        failed = f" (the last try failed: {self.failure})" if self.failure else ""
        self.feedback_message = f"putting waypoints 1-{most} of {len(route)} on the autopilot: {why}{failed}"
        return RUNNING

    def _extend(self, route: Sequence[Waypoint], held: int, most: int) -> int:
        """Waypoints ``held``..``most`` after those held: appended, or (an autopilot without partial writes: PX4) the window uploaded again."""
        if self.autopilot.capabilities.partial_mission_writes:
            return self.autopilot.extend_route(route[held:most])
        home: HomePosition | None = self.get("/vehicle/home")
        return self.autopilot.upload_route(route[:most], home)


class AutopilotAtLeg(MissionTransferFollower):
    """SUCCESS once the autopilot's mission goes on with the current leg: in AUTO, driving its own mission; else once it was set to the leg.

    Out of AUTO (the start, a pause, a failsafe, a crash resumed): MISSION_SET_CURRENT to the leg's
    item, confirmed by MISSION_CURRENT, so that AUTO resumes at this leg and not where the
    autopilot's mission stood (a ground station may have moved it). ArduPilot keeps a stopped
    mission's item and resumes there (AP_Mission::set_current_cmd, libraries/AP_Mission/AP_Mission.cpp).
    A mission completed in AUTO before the leg's item (the horizon ran out under a lagging executive, or
    the link was down) does not start again by itself there: the vehicle is held first, then set to the
    leg and put in AUTO. One completed at the leg's item is the leg's end: :class:`FollowAutoLeg` judges it.

    Out of AUTO, a MISSION_CURRENT newer than that is waited for (``fresh_wait_s`` at most: ArduPilot
    streams it, at 1 Hz as the executive asks), so that a link just back is heard before the leg is set.
    Every tick, the legs the autopilot finished unheard are caught up (the link was down while
    it drove on through its horizon, or the executive was restarted): those through the highest
    MISSION_ITEM_REACHED, or through the item its MISSION_CURRENT says its mission COMPLETED at,
    reported since this run first saw the vehicle in AUTO; never the route's last leg,
    which is judged on the position. So a vehicle that drove its horizon while cut off is not sent
    back along it when the link returns.
    """

    reads = ("/link/mission_transfer", "/vehicle/mode", "/vehicle/mission_current", "/vehicle/mission_reached")
    param_docs = {
        "retry_s": "a failed MISSION_SET_CURRENT is tried again after this",
        "fresh_wait_s": "out of AUTO, how long to wait for a MISSION_CURRENT newer than that (what the autopilot did unheard) before setting it",
    }

    def __init__(self, name: str = "Autopilot at the leg", retry_s: float = 2.0, fresh_wait_s: float = 3.0) -> None:
        super().__init__(name, retry_s)
        self.fresh_wait_s = fresh_wait_s
        self._out_since: float | None = None  # since when the vehicle is out of AUTO with this leg to start
        self._set_for: int | None = None  # the leg the autopilot's mission was set to since it last drove in AUTO
        self._asking: int | None = None
        self._set_item: int | None = None  # the item we set, while the autopilot has not run its mission since
        self._first_auto: float | None = None  # when this run first saw the vehicle in AUTO: reports before are another run's

    def update(self) -> Status:
        if not self._settle() and self._asking is not None:
            self._set_for = self._asking if not self.failure else None
            self._asking = None
        in_auto = self.get("/vehicle/mode") == self.autopilot.mode_name(AUTO)
        if in_auto and self._first_auto is None:
            self._first_auto = self.clock.now()
        self._catch_up()
        leg = self.mission_state.leg_index
        seq = self.autopilot.capabilities.first_item_seq + leg
        current: MissionCurrent | None = self.get("/vehicle/mission_current")
        if in_auto and current is not None and current.state == MISSION_STATE_COMPLETE and current.seq < seq:  # ended before this leg
            if self._set_for is None:
                self.autopilot.hold()
                self._set_for = -1  # asked once per run out
            self.feedback_message = f"the autopilot's mission ended in AUTO before leg {leg + 1}: holding, to set it to item {seq}"
            return RUNNING
        if in_auto:
            self._set_for = self._out_since = None
            self.feedback_message = f"the autopilot drives its mission (leg {leg + 1})"
            return SUCCESS
        if self._set_for == leg:
            self.feedback_message = f"the autopilot's mission set to item {seq}"
            return SUCCESS
        now = self.clock.now()
        self._out_since = now if self._out_since is None else self._out_since
        if (current is None or current.time <= self._out_since) and now - self._out_since < self.fresh_wait_s:
            self.feedback_message = "waiting for the autopilot's MISSION_CURRENT (what it did meanwhile)"
            return RUNNING
        if self._asking is None and self._may_start():
            self._asking, self._set_item = leg, seq
            self._started(self.autopilot.set_route_leg(leg))
        failed = f" (the last try failed: {self.failure})" if self.failure else ""
        self.feedback_message = f"setting the autopilot's mission to item {seq}{failed}"
        return RUNNING

    def _catch_up(self) -> None:
        """Advance the leg index past the items the autopilot reported done since this run first saw it in AUTO (see the class).

        Not before: ArduPilot keeps a completed mission's state and item through uploads until it is
        started again (AP_Mission::truncate and replace_cmd leave the state), so the report of a mission
        run before this one (the same route driven again without a reboot) would pass for this run's.
        Nor a COMPLETE at the item we set: PX4 says COMPLETE with the item MISSION_SET_CURRENT gave until AUTO.MISSION
        runs again (mission_result.finished, cleared by mission_base.cpp set_mission_result on activation; real SIH:
        (4, COMPLETE) after setting 4, tests/data/px4/README.md): that item is not done."""
        if self._first_auto is None:
            return
        done = -1
        reached: MissionItemReached | None = self.get("/vehicle/mission_reached")
        if reached is not None and reached.time >= self._first_auto:
            done = reached.highest
        current: MissionCurrent | None = self.get("/vehicle/mission_current")
        if current is not None and current.state != MISSION_STATE_COMPLETE:
            self._set_item = None
        elif current is not None and current.time >= self._first_auto and current.seq != self._set_item:
            done = max(done, current.seq)
        first, state = self.autopilot.capabilities.first_item_seq, self.mission_state
        while state.leg_index < state.leg_count - 1 and first + state.leg_index <= done:
            state.leg_done()


class FollowAutoLeg(TimedBehaviour):
    """The current leg as AUTO drives it: SUCCESS when it is reached, FAILURE after the leg timeout.

    Reached: the autopilot says so (MISSION_ITEM_REACHED of the leg's item or a later one in this run,
    or MISSION_CURRENT past it since the leg began), the waypoint driven through as the firmware counts
    it: the leg index never runs ahead of the autopilot's, so the horizon appended after it never
    holds more than it should. Where the vehicle must be at the point, the last waypoint and a sample
    point (a stop in the autopilot's mission, which it never reports reached: see
    :func:`~executive.io.mavlink.mission_protocol.route_items`), it is reached on the position (within the
    acceptance radius), as in GUIDED, not on the autopilot's word; a sub's (``depth_tolerance_m``) at the depth
    its item gives too.
    """

    reads = (
        "/vehicle/position", "/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/mission_items",
        "/mission/leg_index", "/mission/leg_count",
    )  # fmt: skip
    needs = ("clock", "mission_state", "autopilot")
    from_mission = {"acceptance_radius_m": "limits.acceptance_radius_m", "leg_timeout_s": "limits.leg_timeout_s"}
    mission_state: MissionPort
    autopilot: AutopilotPort

    param_docs = {"depth_tolerance_m": "sub: the last waypoint is reached within this of the depth its mission item gives (null: not a sub)"}

    def __init__(
        self, acceptance_radius_m: float, leg_timeout_s: float, name: str = "Follow the leg in AUTO", depth_tolerance_m: float | None = None
    ) -> None:
        super().__init__(name)
        self.acceptance_radius_m = acceptance_radius_m
        self.leg_timeout_s = leg_timeout_s
        self.depth_tolerance_m = depth_tolerance_m
        self._run_started: float | None = None  # reports before this run's first leg are another run's
        self._leg = 0  # the leg whose timeout runs

    def initialise(self) -> None:
        super().initialise()
        self._leg = self.mission_state.leg_index
        if self._run_started is None:
            self._run_started = self.started

    def update(self) -> Status:
        state = self.mission_state
        target, leg, n = state.target, state.leg_index, state.leg_count
        if leg != self._leg:  # caught up under it (AutopilotAtLeg, on the autopilot's report): that leg's own timeout
            self._leg, self.started = leg, self.clock.now()
        if target is None:
            self.feedback_message = "no active leg"
            return FAILURE
        position: GlobalPosition | None = self.get("/vehicle/position")
        distance = where = None
        if position is not None:
            distance, bearing = geo.distance_bearing(position.lat, position.lon, target.lat, target.lon)
            where = f"{distance:.1f} m at {bearing:03.0f}°"
        depth_off = self._depth_off(leg, position)
        within = distance is not None and distance <= self.acceptance_radius_m and depth_off is None
        where = f"{where}{depth_off or ''}" if where else where
        said = self._autopilot_passed(self.autopilot.capabilities.first_item_seq + leg)
        stop = leg + 1 == n or target.sample  # the vehicle must be there: judged on the position
        if said and not stop:
            self.feedback_message = f"leg {leg + 1}/{n} in AUTO: reached as AUTO counts it ({where or 'no position'})"
            return SUCCESS
        if within and stop:
            self.feedback_message = f"leg {leg + 1}/{n} in AUTO: reached ({where})"
            return SUCCESS
        if self.elapsed > self.leg_timeout_s:
            self.feedback_message = f"leg {leg + 1}/{n} in AUTO: timed out after {self.leg_timeout_s:g} s" + (f", {where}" if where else "")
            return FAILURE
        stopped_short = " (the autopilot says reached: short of the acceptance radius)" if said else ""
        self.feedback_message = f"leg {leg + 1}/{n} in AUTO: {where or 'no position'}{stopped_short}"
        return RUNNING

    def _depth_off(self, leg: int, position: GlobalPosition | None) -> str | None:
        """A sub away from the depth the autopilot's item ``leg`` gives (beyond ``depth_tolerance_m``): how far; else None."""
        held = self.get("/vehicle/mission_items")
        if self.depth_tolerance_m is None or position is None or held is None or leg >= len(held):
            return None
        depth, item_depth = -position.alt_rel_m, -held[leg].z
        if abs(depth - item_depth) <= self.depth_tolerance_m:
            return None
        return f", at {depth:.1f} m, its depth {item_depth:.2f} m"

    def _autopilot_passed(self, seq: int) -> bool:
        """The autopilot reported item ``seq`` reached, or its mission moved past it, in this run (this leg, for MISSION_CURRENT)."""
        assert self._run_started is not None
        reached: MissionItemReached | None = self.get("/vehicle/mission_reached")
        if reached is not None and reached.time >= self._run_started and reached.highest >= seq:
            return True
        current: MissionCurrent | None = self.get("/vehicle/mission_current")
        return current is not None and current.time > self.started and current.seq > seq
