"""Motion: go to the current leg's waypoint (a sub's depth and height above the seabed, surfacing: :mod:`executive.behaviours.depth`).

Setpoints have no ack: a setpoint action re-sends its target and watches the vehicle get there.
The current leg's waypoint comes from ``/mission/target``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Literal

from py_trees.common import Status

from executive.autopilot import AutopilotPort, Request, Target
from executive.autopilot.rover_motion import RoverMotion, TargetEstimate, auto_corner_cut_m, guided_switch_cut_m, vehicle_motion
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.repositioning import Repositioning
from executive.mission.model import Waypoint
from executive.world import blackboard, geo
from executive.world.seabed import depth_floor, depth_for_altitude
from executive.world.state import GlobalPosition, Outcome

#: The seabed floor's warnings: the journal's event kind "seabed".
seabed_log = logging.getLogger("executive.behaviours.seabed")


def leg_target(waypoint: Waypoint) -> Target:
    """The port's target for a mission waypoint: a sub's altitude leg by its height above the seabed, else its depth, else its altitude."""
    altitude_m = waypoint.altitude_m if waypoint.control_mode == "altitude" else None
    depth_m = waypoint.depth_m if altitude_m is None else None
    return Target(waypoint.lat, waypoint.lon, waypoint.alt_m, depth_m=depth_m, altitude_m=altitude_m)


#: GoTo's look-ahead predicts the path of the autopilot's shaped target, not the vehicle's: it keeps this share of AUTO's
#: cut of the corner, the rest left for how the vehicle follows its target (on the simulated rover the vehicle cut up
#: to 5 % more than the target did when the switch was timed to AUTO's cut exactly).
CUT_SHARE = 0.85


@dataclass(frozen=True, slots=True)
class Corner:
    """A waypoint GoTo drives through: the vehicle's driving, the turn, the next leg, its speed, and what AUTO would cut."""

    motion: RoverMotion
    turn_rad: float
    outbound_m: float
    speed_m_s: float
    auto_cut_m: float


#: Slower than this the vehicle stands (stopped short of the acceptance radius): the setpoint goes again.
STANDING_M_S = 0.2


def _standing(position: GlobalPosition | None) -> bool:
    return position is not None and position.ground_speed_m_s < STANDING_M_S


class GoTo(TimedBehaviour):
    """Go to the current leg's waypoint in GUIDED.

    RUNNING with feedback (distance, bearing) on the way; SUCCESS inside the acceptance radius;
    FAILURE after the leg timeout. A target changed during the leg (an operator edited the route)
    is followed at once. ``method``:

    - ``"setpoint"``: SET_POSITION_TARGET_GLOBAL_INT, re-sent every ``resend_s`` until the autopilot
      reports it as its target (``/vehicle/target_set_by`` ``us``): ArduPilot gives no ack for it and
      drops it silently outside GUIDED. Once reported it is sent again only while the vehicle stands
      (stopped short of the acceptance radius: a new target drives it on): a ground station's Go-to
      that replaced it must be seen first (a person's, :mod:`executive.autopilot.target_watch`), never overwritten
      under way. A sub's waypoint goes with its depth (an
      altitude leg: the depth that keeps its height above the seabed, from the measured depth and
      rangefinder, re-sent as the seabed changes), so a leg never brings the sub up.
    - ``"reposition"``: MAV_CMD_DO_REPOSITION (acked; switches to GUIDED), sent once and again only
      when refused or unanswered, at most every ``resend_s`` (:mod:`executive.behaviours.repositioning`,
      the one asking mechanism). ArduPlane needs it: it takes only the
      altitude from a setpoint. A waypoint without an altitude (``alt_m`` 0, which ArduPlane refuses)
      is flown at the vehicle's current height. A plane circles the point at WP_LOITER_RAD
      (60 m by default): give it an acceptance radius larger than that.

    With ``look_ahead``, a waypoint that needs no stop (another follows, ``/mission/next_target``,
    and it is not a sample point) is driven through: SUCCESS, so the next leg's target goes out,
    as soon as :meth:`drive_through` says so. ArduRover takes a GUIDED position
    target as a stop point (AR_WPNav::set_desired_location_expect_fast_update, no next destination:
    Rover/mode_guided.cpp) and brakes for it on its shaped approach, while its AUTO drives a waypoint
    with a next one through (a "fast waypoint", Rover/mode_auto.cpp do_nav_wp); a target replaced
    under way keeps the shaped velocity, which swings round toward the new one
    (AR_PosControl::input_pos_target). The switch is as early as cuts the corner no more than the
    autopilot's own AUTO would, both worked out from the vehicle's parameters (read at pre-flight,
    ``/vehicle/params``; :mod:`executive.autopilot.rover_motion`). Only for an autopilot whose driving
    is modelled so (ArduRover: ``capabilities.motion_params``); elsewhere every waypoint is a stop.
    A corner a skid-steered rover would pivot at (sharper than WP_PIVOT_ANGLE) is a stop, as in AUTO.
    The last leg and sample points stop within the acceptance radius.
    """

    reads = (
        "/mission/target", "/mission/next_target", "/mission/leg_index", "/mission/leg_count", "/vehicle/position",
        "/vehicle/statustext", "/vehicle/rangefinder", "/vehicle/params", blackboard.command_key(Outcome.REPOSITION),
        "/vehicle/target_set_by",
    )  # fmt: skip
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    from_mission = {
        "acceptance_radius_m": "limits.acceptance_radius_m",
        "leg_timeout_s": "limits.leg_timeout_s",
        "seabed_clearance_m": "vehicle.seabed_clearance_m",
        "height_tolerance_m": "vehicle.height_tolerance_m",
    }
    param_docs = {
        "look_ahead": "a waypoint that needs no stop is driven through toward the next (setpoint only, ArduRover)",
        "seabed_clearance_m": "sub: no depth target closer to the seabed than this, as the sonar reads it (null: no floor)",
        "height_tolerance_m": "a waypoint with a height (alt_m) is reached only within this of it as well (null: distance only)",
    }

    def __init__(
        self,
        acceptance_radius_m: float,
        leg_timeout_s: float,
        name: str = "Go to waypoint",
        resend_s: float = 1.0,
        method: Literal["setpoint", "reposition"] = "setpoint",
        look_ahead: bool = False,
        seabed_clearance_m: float | None = None,
        height_tolerance_m: float | None = None,
    ) -> None:
        if method not in ("setpoint", "reposition"):
            raise ValueError(f"method must be setpoint or reposition, not {method!r}")
        super().__init__(name)
        self.acceptance_radius_m = acceptance_radius_m
        self.leg_timeout_s = leg_timeout_s
        self.resend_s = resend_s
        self.method = method
        self.look_ahead = look_ahead
        self.seabed_clearance_m = seabed_clearance_m
        self.height_tolerance_m = height_tolerance_m
        self.distance_m: float | None = None
        self.bearing_deg: float | None = None
        self._repositioning = Repositioning(self, resend_s)
        # the autopilot's shaped target, and the point it heads for: kept from one leg to the next (the firmware keeps it)
        self._estimate: TargetEstimate | None = None
        self._estimate_goal: tuple[float, float] | None = None
        self._motion_of: tuple[object, RoverMotion | None] | None = None  # (the parameters, the driving they give)

    def initialise(self) -> None:
        super().initialise()
        self.target = self.get("/mission/target")
        self.distance_m = self.bearing_deg = None
        self._last_sent = float("-inf")
        self._repositioning.restart()
        self._seabed_depth: float | None = None  # an altitude leg's last depth target
        self._setpoint: Waypoint | None = None  # the setpoint sent last
        self._floor_told: str | None = None  # the seabed floor's kind last warned of
        self._leg_start: GlobalPosition | None = None  # where the vehicle was when the leg began
        self._predict_at = -math.inf  # the look-ahead's next prediction of the swing, and its last (time, cut)
        self._last_prediction: tuple[float, float] | None = None
        self._corner: tuple[tuple[object, ...], Corner | None] | None = None  # (what it was worked out for, the corner)

    def update(self) -> Status:
        target = self.get("/mission/target")
        # an operator edited the route during the leg: head for the waypoint as it is now (the same object is equal to itself:
        # most ticks, and a model's == is dear)
        if target is not None and target is not self.target and target != self.target:
            self.target, self._last_sent = target, float("-inf")
            self._repositioning.aim()
        if self.target is None:
            self.feedback_message = "no active leg"
            return FAILURE
        position: GlobalPosition | None = self.get("/vehicle/position")
        if self._leg_start is None:
            self._leg_start = position
        self._follow_shaped_target(position)
        self._send(position)
        leg = f"leg {self.get('/mission/leg_index') + 1}/{self.get('/mission/leg_count')}"
        height = self._height_off(position)
        if position is not None:
            self.distance_m, self.bearing_deg = geo.distance_bearing(position.lat, position.lon, self.target.lat, self.target.lon)
            if self.distance_m <= self.acceptance_radius_m and height is None:
                self.feedback_message = f"{leg}: reached ({self.distance_m:.1f} m)"
                return SUCCESS
            through = self.drive_through(position, self.distance_m)
            if through is not None:
                self.feedback_message = f"{leg}: driven through ({self.distance_m:.1f} m out; {through})"
                return SUCCESS
        if self.elapsed > self.leg_timeout_s:
            short = f", {self.distance_m:.1f} m short" if self.distance_m is not None else ""
            refusal = self._repositioning.refusal
            why = f" (DO_REPOSITION {refusal})" if refusal else ""
            off = f", {height}" if height else ""
            self.feedback_message = f"{leg}: timed out after {self.leg_timeout_s:g} s{short}{off}{why}"
            return FAILURE
        if self.distance_m is None:
            self.feedback_message = f"{leg}: no position"
        else:
            self.feedback_message = f"{leg}: {self.distance_m:.1f} m at {self.bearing_deg:03.0f}°{f', {height}' if height else ''}"
        return RUNNING

    def _height_off(self, position: GlobalPosition | None) -> str | None:
        """How the vehicle's height misses the waypoint's, if by more than ``height_tolerance_m`` (None: reached in height, or not
        judged: no tolerance, or ``alt_m`` 0, flown at the height the vehicle is at)."""
        assert self.target is not None
        if self.height_tolerance_m is None or self.target.alt_m == 0.0:
            return None
        if position is None:
            return "height unknown"
        off = position.alt_rel_m - self.target.alt_m
        if abs(off) <= self.height_tolerance_m:
            return None
        return f"at {position.alt_rel_m:.1f} m above home, {abs(off):.1f} m {'above' if off > 0 else 'below'} its {self.target.alt_m:g} m"

    def drive_through(self, position: GlobalPosition, distance_m: float) -> str | None:
        """Whether the next leg's target goes out now, ``distance_m`` short of the waypoint (why, for the feedback); None: not yet,
        or this leg ends in a stop.

        The corner is worked out once (:meth:`corner`); then each tick the swing a switch now would make
        is predicted (:func:`~executive.autopilot.rover_motion.guided_switch_cut_m`) from the autopilot's
        shaped target as the executive follows it (:meth:`_follow_shaped_target`), and taken as soon as it
        cuts the corner by no more than :data:`CUT_SHARE` of AUTO's cut.
        """
        corner = self.corner(position)
        if corner is None:
            return None
        motion, estimate = corner.motion, self._estimate
        accel: float | None = None
        if estimate is not None:  # the autopilot's own target: where the swing starts
            assert self.target is not None
            (n, e), (vn, ve), (an, ae) = estimate.target.pos, estimate.target.vel, estimate.target.acc
            cn, ce = estimate.ne(self.target.lat, self.target.lon)
            ahead, speed = math.hypot(cn - n, ce - e), math.hypot(vn, ve)
            accel = (an * vn + ae * ve) / speed if speed > 0.0 else 0.0
        else:  # the vehicle, moved on by its position's age
            speed = position.ground_speed_m_s
            ahead = max(0.0, distance_m - speed * max(0.0, self.clock.now() - position.time))
        if ahead > corner.auto_cut_m + speed * speed / motion.shaping_accel_m_s2 + motion.corner_radius_m:
            return None  # too far out for any swing to stay within the cut: not worth predicting
        lag = max(0.5, 0.5 * speed)  # half a second of the target's speed
        if estimate is not None and (estimate.off_by_m((position.lat, position.lon)) > lag or abs(position.ground_speed_m_s - speed) > lag):
            return None  # the vehicle is not following the target as the estimate has it (held up, stopped short): no drive-through
        now, allowed = self.clock.now(), CUT_SHARE * corner.auto_cut_m
        if now < self._predict_at:
            return None
        cut = guided_switch_cut_m(motion, ahead, speed, corner.turn_rad, corner.outbound_m, corner.speed_m_s, accel)
        if cut <= allowed:
            return f"the swing cuts the corner by {cut:.1f} m, AUTO by {corner.auto_cut_m:.1f} m"
        self._predict_at = self._next_prediction(now, cut, allowed)
        return None

    def _next_prediction(self, now: float, cut: float, allowed: float) -> float:
        """When to predict again: half-way to when the cut, closing in as it has since the last prediction, would fit
        (each tick near it); every 0.3 s while it does not close in. A prediction costs ~0.3 ms: ticks stay cheap."""
        last, self._last_prediction = self._last_prediction, (now, cut)
        if last is None or now <= last[0]:
            return now
        closing = (last[1] - cut) / (now - last[0])  # m of cut lost per s
        if closing <= 0.0:
            return now + 0.3
        return now + min(1.0, 0.5 * (cut - allowed) / closing)

    def _follow_shaped_target(self, position: GlobalPosition | None) -> None:
        """Keep :class:`~executive.autopilot.rover_motion.TargetEstimate` of the autopilot's shaped target in step (the look-ahead's).

        Started from the vehicle when there is none, when it was not kept up (the autopilot's controller
        starts again from the vehicle after a pause, AR_PosControl::init) or when it strayed farther from
        the vehicle than twice WP_RADIUS; shaped toward the target last sent, up to now.
        """
        if not self.look_ahead or self.method != "setpoint" or self.target is None or position is None:
            return
        motion = self._motion()
        if motion is None:
            self._estimate = None
            return
        now, here = self.clock.now(), (position.lat, position.lon)
        estimate = self._estimate
        stale = estimate is None or now - estimate.time > 0.5 or estimate.off_by_m(here) > max(2.0 * motion.radius_m, 5.0)
        if stale or self._estimate_goal is None:
            estimate = TargetEstimate(motion, self.target.speed_m_s or motion.speed_m_s, here, now)
            age = max(0.0, now - position.time)
            n, e = position.vn_m_s * age, position.ve_m_s * age
            estimate.target.reset((n, e), (position.vn_m_s, position.ve_m_s))  # where the vehicle is by now
            self._estimate, self._estimate_goal = estimate, (self.target.lat, self.target.lon)
        assert estimate is not None and self._estimate_goal is not None
        estimate.advance(self._estimate_goal, now)
        self._estimate_goal = (self.target.lat, self.target.lon)  # from this tick on the autopilot heads for this leg's waypoint

    def corner(self, position: GlobalPosition) -> Corner | None:
        """The waypoint as a corner to drive through (its turn, the next leg, AUTO's cut); None when the leg ends in a stop."""
        following: Waypoint | None = self.get("/mission/next_target")
        if not self.look_ahead or self.method != "setpoint" or following is None or self.target is None or self.target.sample:
            return None
        start = self._leg_start or position
        motion = self._motion()
        # by identity: the mission state hands out the same waypoints, _motion the same object until a parameter comes
        key = (id(self.target), id(following), id(motion), start.lat, start.lon)
        if self._corner is None or self._corner[0] != key:
            self._corner = (key, self._work_out_corner(motion, start, following))
        return self._corner[1]

    def _motion(self) -> RoverMotion | None:
        """The vehicle's driving by its parameters (``/vehicle/params``): worked out again only when a parameter came."""
        params = self.get("/vehicle/params")
        if self._motion_of is None or self._motion_of[0] is not params:
            self._motion_of = (params, vehicle_motion(self.autopilot.capabilities, params))
        return self._motion_of[1]

    def _work_out_corner(self, motion: RoverMotion | None, start: GlobalPosition, following: Waypoint) -> Corner | None:
        assert self.target is not None
        if motion is None:
            return None
        inbound_m, inbound = geo.distance_bearing(start.lat, start.lon, self.target.lat, self.target.lon)
        outbound_m, outbound = geo.distance_bearing(self.target.lat, self.target.lon, following.lat, following.lon)
        turn = math.radians(abs((outbound - inbound + 180.0) % 360.0 - 180.0))
        if motion.pivots and math.degrees(turn) > motion.pivot_angle_deg:
            return None  # AR_WPNav: a corner it would pivot at is never a fast waypoint
        speed = self.target.speed_m_s or motion.speed_m_s
        auto_cut = auto_corner_cut_m(motion, inbound_m, outbound_m, turn, speed)
        if auto_cut is None:
            return None  # AUTO would stop there too
        return Corner(motion, turn, outbound_m, speed, auto_cut)

    def _send(self, position: GlobalPosition | None) -> None:
        assert self.target is not None
        if self.method == "reposition":
            self._repositioning.follow_up(self._reposition)
            return
        now = self.clock.now()
        if now - self._last_sent < self.resend_s:
            return
        target = self._as_depth(self.target, position)
        if target is not None and not (target == self._setpoint and self._reported(target) and not _standing(position)):
            self.autopilot.go_to(leg_target(target))
            self._setpoint = target
        self._last_sent = now

    def _reposition(self) -> Request:
        """Ask for the waypoint (a waypoint without an altitude at the vehicle's height; a sub's at its depth)."""
        assert self.target is not None
        position: GlobalPosition | None = self.get("/vehicle/position")
        alt = self.target.alt_m
        if self.target.depth_m is not None:
            alt = -self.target.depth_m
        elif alt == 0.0 and position is not None:
            alt = position.alt_rel_m
        return self.autopilot.reposition(self.target.lat, self.target.lon, alt)

    def _reported(self, target: Waypoint) -> bool:
        """The autopilot reports steering to ``target``, our latest ask (POSITION_TARGET_GLOBAL_INT)."""
        asked = self.autopilot.target_asked
        ours = asked is not None and (asked.lat, asked.lon) == (target.lat, target.lon)
        return ours and self.get("/vehicle/target_set_by") == "us"

    def _as_depth(self, target: Waypoint, position: GlobalPosition | None) -> Waypoint | None:
        """A sub's altitude leg as a depth target from the measured depth and rangefinder (executive.world.seabed: ArduSub drops
        terrain-frame targets); the last one again while the reading says nothing, the current depth before any. Any
        sub's depth no deeper than the seabed floor (``seabed_clearance_m``: :func:`executive.world.seabed.depth_floor`)."""
        if target.control_mode != "altitude" or target.altitude_m is None:
            return self._above_floor(target, position)
        if position is None:
            return None
        depth = depth_for_altitude(-position.alt_rel_m, self.get("/vehicle/rangefinder"), target.altitude_m)
        depth = depth if depth is not None else self._seabed_depth if self._seabed_depth is not None else -position.alt_rel_m
        self._seabed_depth = depth
        return self._above_floor(target.model_copy(update={"control_mode": "depth", "depth_m": depth, "altitude_m": None}), position)

    def _above_floor(self, target: Waypoint, position: GlobalPosition | None) -> Waypoint:
        """``target``'s depth, no deeper than the seabed floor (a warning the first time the floor holds the leg)."""
        if self.seabed_clearance_m is None or target.depth_m is None or position is None:
            return target
        floor = depth_floor(-position.alt_rel_m, self.get("/vehicle/rangefinder"), self.seabed_clearance_m, self.clock.now())
        if floor is None or floor.depth_m >= target.depth_m:
            return target
        if floor.kind != "beyond" and self._floor_told != floor.kind:
            self._floor_told = floor.kind
            seabed_log.warning(
                "%s: depth %g m held at %.1f m: %s, %g m above it (limits.altitude_m.min)", self.name, target.depth_m, floor.depth_m, floor.why,
                self.seabed_clearance_m,
            )  # fmt: skip
        return target.model_copy(update={"depth_m": floor.depth_m})
