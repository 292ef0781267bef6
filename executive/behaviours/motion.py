"""Motion: go to the current leg's waypoint, a sub's depth and height above the seabed, surfacing.

Setpoints have no ack: a setpoint action re-sends its target and watches the vehicle get there.
The current leg's waypoint comes from ``/mission/target``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from py_trees.common import Status

from executive import blackboard, geo
from executive.autopilot import AutopilotPort, Request, Target
from executive.autopilot.rover_motion import RoverMotion, TargetEstimate, auto_corner_cut_m, guided_switch_cut_m, vehicle_motion
from executive.behaviours.base import TimedBehaviour
from executive.behaviours.commands import CommandAction, refusal_reason
from executive.mission.model import Waypoint
from executive.seabed import depth_for_altitude
from executive.state import GlobalPosition, Outcome


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
      that replaced it must be seen first (a person's, :mod:`executive.target_watch`), never overwritten
      under way. A sub's waypoint goes with its depth (an
      altitude leg: the depth that keeps its height above the seabed, from the measured depth and
      rangefinder, re-sent as the seabed changes), so a leg never brings the sub up.
    - ``"reposition"``: MAV_CMD_DO_REPOSITION (acked; switches to GUIDED), sent once and again only
      when refused or unanswered, at most every ``resend_s``. ArduPlane needs it: it takes only the
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
    from_mission = {"acceptance_radius_m": "limits.acceptance_radius_m", "leg_timeout_s": "limits.leg_timeout_s"}
    param_docs = {
        "look_ahead": "a waypoint that needs no stop is driven through toward the next (setpoint only, ArduRover)",
    }

    def __init__(
        self,
        acceptance_radius_m: float,
        leg_timeout_s: float,
        name: str = "Go to waypoint",
        resend_s: float = 1.0,
        method: Literal["setpoint", "reposition"] = "setpoint",
        look_ahead: bool = False,
    ) -> None:
        if method not in ("setpoint", "reposition"):
            raise ValueError(f"method must be setpoint or reposition, not {method!r}")
        super().__init__(name)
        self.acceptance_radius_m = acceptance_radius_m
        self.leg_timeout_s = leg_timeout_s
        self.resend_s = resend_s
        self.method = method
        self.look_ahead = look_ahead
        self.distance_m: float | None = None
        self.bearing_deg: float | None = None
        self._ticket: Request | None = None
        # the autopilot's shaped target, and the point it heads for: kept from one leg to the next (the firmware keeps it)
        self._estimate: TargetEstimate | None = None
        self._estimate_goal: tuple[float, float] | None = None
        self._motion_of: tuple[object, RoverMotion | None] | None = None  # (the parameters, the driving they give)

    def initialise(self) -> None:
        super().initialise()
        self.target = self.get("/mission/target")
        self.distance_m = self.bearing_deg = None
        self._last_sent = float("-inf")
        self._ticket = None
        self._refusal: str | None = None
        self._seabed_depth: float | None = None  # an altitude leg's last depth target
        self._setpoint: Waypoint | None = None  # the setpoint sent last
        self._leg_start: GlobalPosition | None = None  # where the vehicle was when the leg began
        self._predict_at = -math.inf  # the look-ahead's next prediction of the swing, and its last (time, cut)
        self._last_prediction: tuple[float, float] | None = None
        self._corner: tuple[tuple[object, ...], Corner | None] | None = None  # (what it was worked out for, the corner)

    def update(self) -> Status:
        target = self.get("/mission/target")
        if target is not None and target != self.target:  # an operator edited the route during the leg: head for the waypoint as it is now
            self.target, self._last_sent, self._ticket = target, float("-inf"), None
        if self.target is None:
            self.feedback_message = "no active leg"
            return Status.FAILURE
        position: GlobalPosition | None = self.get("/vehicle/position")
        if self._leg_start is None:
            self._leg_start = position
        self._follow_shaped_target(position)
        self._send(position)
        leg = f"leg {self.get('/mission/leg_index') + 1}/{self.get('/mission/leg_count')}"
        if position is not None:
            self.distance_m, self.bearing_deg = geo.distance_bearing(position.lat, position.lon, self.target.lat, self.target.lon)
            if self.distance_m <= self.acceptance_radius_m:
                self.feedback_message = f"{leg}: reached ({self.distance_m:.1f} m)"
                return Status.SUCCESS
            through = self.drive_through(position, self.distance_m)
            if through is not None:
                self.feedback_message = f"{leg}: driven through ({self.distance_m:.1f} m out; {through})"
                return Status.SUCCESS
        if self.elapsed > self.leg_timeout_s:
            short = f", {self.distance_m:.1f} m short" if self.distance_m is not None else ""
            why = f" (DO_REPOSITION {self._refusal})" if self._refusal else ""
            self.feedback_message = f"{leg}: timed out after {self.leg_timeout_s:g} s{short}{why}"
            return Status.FAILURE
        if self.distance_m is None:
            self.feedback_message = f"{leg}: no position"
        else:
            self.feedback_message = f"{leg}: {self.distance_m:.1f} m at {self.bearing_deg:03.0f}°"
        return Status.RUNNING

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
        now = self.clock.now()
        if now - self._last_sent < self.resend_s:
            return
        if self.method == "setpoint":
            target = self._as_depth(self.target, position)
            held = target == self._setpoint and self._reported(target) and not _standing(position)
            if target is not None and not held:
                self.autopilot.go_to(leg_target(target))
                self._setpoint = target
            self._last_sent = now
            return
        if self._ticket is not None:
            self._refusal = refusal_reason(self.get(blackboard.command_key(Outcome.REPOSITION)), self._ticket, self.get("/vehicle/statustext"))
            if self._refusal is None:
                return  # accepted or still waiting for the ack: the autopilot has the target
        alt = self.target.alt_m
        if self.target.depth_m is not None:
            alt = -self.target.depth_m
        elif alt == 0.0 and position is not None:
            alt = position.alt_rel_m
        self._ticket = self.autopilot.reposition(self.target.lat, self.target.lon, alt)
        self._last_sent = now

    def _reported(self, target: Waypoint) -> bool:
        """The autopilot reports steering to ``target``, our latest ask (POSITION_TARGET_GLOBAL_INT)."""
        asked = self.autopilot.target_asked
        ours = asked is not None and (asked.lat, asked.lon) == (target.lat, target.lon)
        return ours and self.get("/vehicle/target_set_by") == "us"

    def _as_depth(self, target: Waypoint, position: GlobalPosition | None) -> Waypoint | None:
        """A sub's altitude leg as a depth target from the measured depth and rangefinder (executive.seabed: ArduSub drops
        terrain-frame targets); the last one again while the reading says nothing, the current depth before any."""
        if target.control_mode != "altitude" or target.altitude_m is None:
            return target
        if position is None:
            return None
        depth = depth_for_altitude(-position.alt_rel_m, self.get("/vehicle/rangefinder"), target.altitude_m)
        depth = depth if depth is not None else self._seabed_depth if self._seabed_depth is not None else -position.alt_rel_m
        self._seabed_depth = depth
        return target.model_copy(update={"control_mode": "depth", "depth_m": depth, "altitude_m": None})


class _VerticalSetpoint(TimedBehaviour):
    """A sub's vertical target for the current leg, held where the vehicle is when the action starts.

    The setpoint (no ack exists) is re-sent every ``resend_s`` at that same point; SUCCESS once the
    vehicle shows the target within ``tolerance_m``; FAILURE after ``timeout_s``. SUCCESS at once
    when the leg has no target of this kind.
    """

    reads = ("/mission/target", "/vehicle/position", "/vehicle/mode")
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    what = ""
    catalogued = False
    param_docs = {"tolerance_m": "reached within this of the target"}

    def __init__(self, name: str, tolerance_m: float, timeout_s: float, resend_s: float) -> None:
        super().__init__(name)
        self.tolerance_m = tolerance_m
        self.timeout_s = timeout_s
        self.resend_s = resend_s
        self.target_m: float | None = None

    def wanted(self, waypoint: Waypoint) -> float | None:
        """The leg's target of this kind, if it has one."""
        raise NotImplementedError

    def measured(self, position: GlobalPosition) -> float | None:
        """The vehicle's current value of that kind, if known."""
        raise NotImplementedError

    def send(self, lat: float, lon: float, target_m: float) -> None:
        raise NotImplementedError

    def refuse(self) -> str | None:
        """Why the setpoint cannot be sent now (None: it can)."""
        return None

    def initialise(self) -> None:
        super().initialise()
        waypoint: Waypoint | None = self.get("/mission/target")
        self.target_m = self.wanted(waypoint) if waypoint is not None else None
        self._here: tuple[float, float] | None = None
        self._last_sent = float("-inf")

    def update(self) -> Status:
        if self.target_m is None:
            self.feedback_message = f"no {self.what} for this leg"
            return Status.SUCCESS
        refusal = self.refuse()
        if refusal is not None:
            self.feedback_message = refusal
            return Status.FAILURE
        position: GlobalPosition | None = self.get("/vehicle/position")
        if self._here is None and position is not None:
            self._here = (position.lat, position.lon)
        now = self.clock.now()
        if self._here is not None and now - self._last_sent >= self.resend_s:
            self.send(*self._here, self.target_m)
            self._last_sent = now
        value = self.measured(position) if position is not None else None
        if value is not None and abs(value - self.target_m) <= self.tolerance_m and self._last_sent > float("-inf"):
            self.feedback_message = f"{self.what} {value:.1f} m (target {self.target_m:g} m)"
            return Status.SUCCESS
        now_at = f"{value:.1f} m" if value is not None else "unknown"
        if self.elapsed > self.timeout_s:
            self.feedback_message = f"{self.what} {now_at}, target {self.target_m:g} m, not reached after {self.timeout_s:g} s"
            return Status.FAILURE
        self.feedback_message = f"{self.what} {now_at} -> {self.target_m:g} m"
        return Status.RUNNING


class ChangeDepth(_VerticalSetpoint):
    """Sub: dive (or rise) to the current leg's ``depth_m`` where the vehicle is; SUCCESS when ``/vehicle/position`` shows it.

    The depth goes as ``alt = -depth`` in the relative-altitude frame, which ArduSub takes in
    GUIDED (with the position: the vehicle holds where it was when the action started) and in
    ALT_HOLD (the depth alone). A leg with control_mode ``altitude`` or no depth: SUCCESS at once
    (ChangeAltitude's job, or nothing to do), so one tree can put both in every leg.
    """

    what = "depth"

    def __init__(self, name: str = "Change depth", tolerance_m: float = 0.5, timeout_s: float = 120.0, resend_s: float = 1.0) -> None:
        super().__init__(name, tolerance_m, timeout_s, resend_s)

    def wanted(self, waypoint: Waypoint) -> float | None:
        return None if waypoint.control_mode == "altitude" else waypoint.depth_m

    def measured(self, position: GlobalPosition) -> float | None:
        return -position.alt_rel_m

    def send(self, lat: float, lon: float, target_m: float) -> None:
        self.autopilot.hold_depth(lat, lon, depth_m=target_m)


class ChangeAltitude(_VerticalSetpoint):
    """Sub: reach the current leg's ``altitude_m`` above the seabed (control_mode ``altitude``), where the vehicle is.

    Flown as depth targets computed from the measured depth and the downward rangefinder
    (:func:`executive.seabed.depth_for_altitude`), re-sent every ``resend_s`` as the reading
    changes: ArduSub silently drops a terrain-frame target. With the seabed beyond the
    rangefinder's reach it dives, without overshooting, until the reading is good. Confirmed by the
    rangefinder (``/vehicle/altitude_above_bottom_m``). Other legs: SUCCESS at once.
    """

    reads = (*_VerticalSetpoint.reads, "/vehicle/altitude_above_bottom_m", "/vehicle/rangefinder")
    what = "altitude"

    def __init__(self, name: str = "Change altitude", tolerance_m: float = 0.5, timeout_s: float = 120.0, resend_s: float = 1.0) -> None:
        super().__init__(name, tolerance_m, timeout_s, resend_s)

    def wanted(self, waypoint: Waypoint) -> float | None:
        return waypoint.altitude_m if waypoint.control_mode == "altitude" else None

    def measured(self, position: GlobalPosition) -> float | None:
        value: float | None = self.get("/vehicle/altitude_above_bottom_m")
        return value

    def send(self, lat: float, lon: float, target_m: float) -> None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return
        depth = depth_for_altitude(-position.alt_rel_m, self.get("/vehicle/rangefinder"), target_m)
        if depth is not None:  # an invalid reading: ArduSub keeps the last depth target
            self.autopilot.hold_depth(lat, lon, depth_m=depth)


class Surface(CommandAction):
    """Sub: come up with ArduSub's SURFACE mode; SUCCESS once the vehicle is at the surface and SURFACE is done.

    SURFACE climbs at PILOT_SPEED_UP (``climb_m_s``, 0.5 m/s by default) and hands over to
    ALT_HOLD by itself at the surface (ModeReason SURFACE_COMPLETE). Confirmed by the depth
    (``/vehicle/position``, within ``surface_m``) in any mode but SURFACE: the heartbeat may never
    show SURFACE at all when the vehicle is nearly up. Already there: SUCCESS without a command.
    Refused (no depth sensor...): FAILURE; not up after the climb's time plus ``margin_s``: FAILURE.
    """

    reads = ("/vehicle/position", "/vehicle/mode")
    outcome = Outcome.MODE
    param_docs = {
        "surface_m": "at the surface within this depth",
        "climb_m_s": "the climb rate (ArduSub's PILOT_SPEED_UP), for the time allowed",
        "margin_s": "time allowed over the climb's",
    }

    def __init__(self, name: str = "Surface", surface_m: float = 0.5, climb_m_s: float = 0.5, margin_s: float = 30.0) -> None:
        super().__init__(name, margin_s)
        self.surface_m = surface_m
        self.climb_m_s = climb_m_s
        self.margin_s = margin_s

    def _depth(self) -> float | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        return -position.alt_rel_m if position is not None else None

    def initialise(self) -> None:
        depth = self._depth()
        self.confirm_timeout_s = self.margin_s + max(0.0, depth or 0.0) / self.climb_m_s
        super().initialise()

    def request(self) -> Request:
        return self.autopilot.set_mode("SURFACE")

    def confirmed(self) -> bool:
        depth = self._depth()
        return depth is not None and depth <= self.surface_m and self.get("/vehicle/mode") != "SURFACE"

    def progress(self) -> str | None:
        depth = self._depth()
        return f"depth {depth:.1f} m in {self.get('/vehicle/mode')}" if depth is not None else "no position"
