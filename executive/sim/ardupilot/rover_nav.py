"""ArduRover's navigation, as the simulated ArduRover drives with it: GUIDED's shaped targets, AUTO's S-curves, pivots.

From ArduPilot 4.7-dev's source (facts, not code):

- GUIDED (Rover/mode_guided.cpp, GUID_OPTIONS 0): every position target goes to
  ``AR_WPNav::set_desired_location_expect_fast_update``: a stop point the position controller's
  input shaping pulls a target toward (:class:`~executive.autopilot.rover_motion.ShapedTarget`); a new
  target keeps the shaped velocity. Reached when the shaped target is within 1 cm of the point and the
  vehicle within WP_RADIUS of the shaped target (``update_psc_input_shaping``).
- AUTO and RTL (Rover/mode_auto.cpp ``do_nav_wp``): ``AR_WPNav::set_desired_location`` with the next
  waypoint when there is one and no hold time: the leg is an S-curve, and a "fast waypoint" blends into
  the next leg's S-curve while it decelerates (``SCurve::advance_target_along_track``: once this leg
  brakes, will end before the next one has finished speeding up, and the turn's mid point lies within
  max(WP_RADIUS, TURN_RADIUS) of the waypoint, slower than either leg's speed and within the lateral
  acceleration). A fast waypoint is reached half-way through the turn; a stop one when the S-curve has
  ended and the vehicle is within WP_RADIUS or past the finish line. The S-curve's clock runs slower
  when the vehicle lags its target (``advance_wp_target_along_track``'s track scaler).
- Pivots (libraries/AR_WPNav/AR_PivotTurn.cpp), for skid steering only: when a new leg's bearing is more
  than WP_PIVOT_ANGLE off the heading (or a fast waypoint would turn more than that: it is then a stop),
  the vehicle stops, turns on the spot at up to WP_PIVOT_RATE until within 5 degrees, then drives.
- AR_PosControl::update turns the target into a forward speed and a turn rate: velocity toward the target
  (PSC_POS_P), plus the target's velocity, an acceleration from the velocity error (PSC_VEL_P) plus the
  target's acceleration; the forward part is the speed (kept at least the turning speed unless stopping),
  changed within ATC_ACCEL_MAX / ATC_DECEL_MAX (AR_AttitudeControl::get_desired_speed_accel_limited); the
  sideways part over the speed (at least 1 m/s) is the turn rate (get_turn_rate_from_lat_accel), which
  AR_AttitudeControl::get_steering_out_rate limits by ATC_STR_ACC_MAX, ATC_STR_RAT_MAX and ATC_TURN_MAX_G.
- A stop (Mode::stop_vehicle) brings the speed to 0 within ATC_DECEL_MAX, without turning.
"""

from __future__ import annotations

import math
from typing import Literal, Protocol

from executive.autopilot.rover_motion import RoverMotion, SCurveLeg, ShapedTarget, sqrt_controller, stopping_distance
from executive.world.bounds import within

#: AR_PIVOT_ANGLE_ACCURACY: a pivot ends within this many degrees of the bearing.
PIVOT_ACCURACY_DEG = 5.0
#: AR_ATTCONTROL_STEER_ANG_P: turn rate per radian of heading error in a pivot.
STEER_ANGLE_P = 2.0
#: AR_ATTCONTROL_STEER_SPEED_MIN: the turn rate for a lateral acceleration is taken at no less than this speed.
STEER_SPEED_MIN_M_S = 1.0
#: AR_WPNAV_OVERSPEED_RATIO_MAX is not used (overspeed off); the track scaler keeps this much over the vehicle's speed.
TRACK_SCALER_MARGIN = 0.05
#: AR_AttitudeControl::get_steering_out_rate's least turn-rate limit at speed.
ONE_DEGREE_RAD = math.radians(1.0)


def _wrap_pi(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class Driven(Protocol):
    """What the navigator reads of the vehicle (north, east in metres; heading in radians, clockwise from north)."""

    @property
    def north_east_m(self) -> tuple[float, float]: ...
    @property
    def velocity_ned(self) -> tuple[float, float, float]: ...
    @property
    def yaw_rad(self) -> float: ...
    @property
    def speed_m_s(self) -> float: ...
    @property
    def yaw_rate_rad_s(self) -> float: ...


class RoverNavigator:
    """AR_WPNav with AR_PosControl and AR_PivotTurn, and the speed and steering limits of AR_AttitudeControl.

    :meth:`guided_to`, :meth:`auto_to` and :meth:`stop` are the modes' orders; :meth:`control` (every
    step of the vehicle) returns the forward speed and turn rate wanted now.
    """

    def __init__(self, motion: RoverMotion, speed_m_s: float | None = None) -> None:
        self.motion = motion
        # what the parameters fix, worked out once rather than every 20 ms step
        #: AC_P_2D's limit: the position error's square-root branch within min(accel, lateral accel) and jerk / P.
        self._accel_limit = min(min(motion.path_accel_m_s2, motion.lat_accel_m_s2), motion.jerk_m_s3 / motion.pos_p)
        #: ATC_STR_ACC_MAX and ATC_STR_RAT_MAX in rad/s/s and rad/s (None: that limit is off, the parameter 0).
        self._steer_accel_rad_s2 = math.radians(motion.steer_accel_max_deg_s2) if motion.steer_accel_max_deg_s2 > 0.0 else None
        self._steer_rate_rad_s = math.radians(motion.steer_rate_max_deg_s) if motion.steer_rate_max_deg_s > 0.0 else None
        self.speed_max_m_s = speed_m_s if speed_m_s and speed_m_s > 0.0 else motion.speed_m_s
        self.kind: Literal["stop", "shaping", "scurve"] = "stop"
        self.destination: tuple[float, float] | None = None
        self.origin: tuple[float, float] | None = None
        self.reached = False
        self.fast_waypoint = False
        self._pivot_at_next = False
        self.pivoting = False
        self._shaped: ShapedTarget | None = None
        self._this: SCurveLeg | None = None
        self._prev: SCurveLeg | None = None
        self._next: SCurveLeg | None = None
        self._track_scaler = 1.0
        self._target: tuple[tuple[float, float], tuple[float, float], tuple[float, float]] | None = None  # pos, vel, acc
        self._desired_speed = 0.0  # AR_AttitudeControl's last accel-limited desired speed
        self._desired_rate = 0.0  # its last desired turn rate
        self._active = False  # navigated in the last step (AR_WPNav::is_active)

    @property
    def speed_max_m_s(self) -> float:
        """AR_WPNav's speed limit (WP_SPEED, or DO_CHANGE_SPEED's)."""
        return self._speed_max_m_s

    @speed_max_m_s.setter
    def speed_max_m_s(self, speed_m_s: float) -> None:
        self._speed_max_m_s = speed_m_s
        #: The position error beyond which the position controller asks no more than the speed limit.
        self._error_max_m = stopping_distance(speed_m_s, self.motion.pos_p, self._accel_limit)

    # -- orders ------------------------------------------------------------------------------

    def set_speed(self, speed_m_s: float) -> None:
        """AR_WPNav::set_speed_max (DO_CHANGE_SPEED): the shaped target at once; AUTO's legs from the next one planned."""
        self.speed_max_m_s = speed_m_s
        if self._shaped is not None:
            self._shaped.speed_m_s = speed_m_s

    def stop(self) -> None:
        """Mode::stop_vehicle: brake to a stop, no turning; the next order starts from the stopping point."""
        self.kind, self.destination, self.reached = "stop", None, False
        self._active = False
        self.pivoting = False
        self._target = None

    def guided_to(self, destination: tuple[float, float], vehicle: Driven) -> None:
        """A GUIDED position target (set_desired_location_expect_fast_update)."""
        if not self._active or self.kind != "shaping":
            self._shaped = ShapedTarget(self.speed_max_m_s, self.motion.shaping_accel_m_s2, self.motion.jerk_m_s3)
            (vn, ve, _), pos = vehicle.velocity_ned, vehicle.north_east_m
            self._shaped.reset(pos, (vn, ve))
            self.destination = self._stopping_point(vehicle)
        self.origin, self.destination = self.destination, destination
        self.kind, self.reached, self.fast_waypoint = "shaping", False, False
        self._check_pivot(self._bearing(vehicle, destination), vehicle, force=False)
        self._active = True

    def auto_to(self, destination: tuple[float, float], following: tuple[float, float] | None, vehicle: Driven) -> None:
        """An AUTO (or RTL) destination, with the next one when the vehicle should not stop there (set_desired_location)."""
        motion, speed = self.motion, self.speed_max_m_s
        if not self._active or not self.reached or self.kind != "scurve":
            self.destination = self._stopping_point(vehicle)
            self._prev = self._this = self._next = None
        self._prev = self._this
        self.origin, self.destination = self.destination, destination
        self.kind, self.reached = "scurve", False
        if not self.fast_waypoint:
            self.pivoting = False
            self._check_pivot(self._bearing(vehicle, destination), vehicle, force=self._pivot_at_next)
        assert self.origin is not None
        if self.fast_waypoint and self._next is not None and not self._next.finished:
            self._this = self._next  # the turn onto this leg is already under way
        else:
            self._this = SCurveLeg(self.origin, destination, speed, motion.path_accel_m_s2, motion.jerk_m_s3)
        self._next, self.fast_waypoint, self._pivot_at_next = None, False, False
        if following is not None:
            turn = math.degrees(abs(_wrap_pi(_bearing_of(destination, following) - _bearing_of(self.origin, destination))))
            self._pivot_at_next = motion.pivots and turn > motion.pivot_angle_deg
            if not self._pivot_at_next:
                self._next = SCurveLeg(destination, following, speed, motion.path_accel_m_s2, motion.jerk_m_s3)
                self.fast_waypoint = True
        self._active = True

    # -- every step ------------------------------------------------------------------------------

    def control(self, vehicle: Driven, dt: float) -> tuple[float, float]:
        """The forward speed (m/s) and turn rate (rad/s, clockwise) wanted after ``dt`` seconds."""
        if self.kind == "stop" or self.destination is None:
            return self._speed_limited(0.0, dt), self._rate_limited(0.0, vehicle, dt)
        if self.pivoting:
            speed = self._speed_limited(0.0, dt)
            rate = 0.0
            if speed == 0.0:
                rate = self._pivot_rate(vehicle)
            return speed, self._rate_limited(rate, vehicle, dt)
        if self.kind == "shaping":
            self._advance_shaping(vehicle, dt)
        else:
            self._advance_scurve(vehicle, dt)
        return self._position_control(vehicle, dt)

    # -- internals -------------------------------------------------------------------------------

    def _stopping_point(self, vehicle: Driven) -> tuple[float, float]:
        """AR_WPNav::get_stopping_location: ahead along the velocity by speed^2 / (2 * deceleration)."""
        (vn, ve, _), (n, e) = vehicle.velocity_ned, vehicle.north_east_m
        speed = math.hypot(vn, ve)
        if speed <= 0.0:
            return n, e
        ahead = 0.5 * speed * speed / self.motion.decel_m_s2 / speed
        return n + vn * ahead, e + ve * ahead

    @staticmethod
    def _bearing(vehicle: Driven, destination: tuple[float, float]) -> float:
        return _bearing_of(vehicle.north_east_m, destination)

    def _check_pivot(self, bearing: float, vehicle: Driven, *, force: bool) -> None:
        """AR_PivotTurn::check_activation: pivot when the bearing is more than WP_PIVOT_ANGLE off the heading (or forced)."""
        motion = self.motion
        if not motion.pivots:
            self.pivoting = False
            return
        error = math.degrees(abs(_wrap_pi(bearing - vehicle.yaw_rad)))
        if error > motion.pivot_angle_deg or force:
            self.pivoting = True

    def _pivot_rate(self, vehicle: Driven) -> float:
        """AR_PivotTurn::get_turn_rate_rads: toward the bearing at up to WP_PIVOT_RATE; done within 5 degrees."""
        assert self.destination is not None
        bearing = self._bearing(vehicle, self.destination)
        error = _wrap_pi(bearing - vehicle.yaw_rad)
        if math.degrees(abs(error)) < PIVOT_ACCURACY_DEG:  # WP_PIVOT_DELAY 0: drive on at once
            self.pivoting = False
            return 0.0
        rate = max(-math.radians(self.motion.pivot_rate_deg_s), min(math.radians(self.motion.pivot_rate_deg_s), STEER_ANGLE_P * error))
        # AR_AttitudeControl::get_turn_rate_from_heading: slow enough to stop turning at the heading (ATC_STR_ACC_MAX)
        stop_rate = math.sqrt(2.0 * abs(error) * math.radians(self.motion.steer_accel_max_deg_s2))
        return max(-stop_rate, min(stop_rate, rate))

    def _advance_shaping(self, vehicle: Driven, dt: float) -> None:
        assert self._shaped is not None and self.destination is not None
        shaped = self._shaped
        shaped.step(self.destination, dt)
        self._target = (shaped.pos, shaped.vel, shaped.acc)
        if not self.reached:
            (tn, te), (n, e) = shaped.pos, vehicle.north_east_m
            near = math.hypot(self.destination[0] - tn, self.destination[1] - te) < 0.01
            self.reached = near and math.hypot(tn - n, te - e) < self.motion.radius_m

    def _advance_scurve(self, vehicle: Driven, dt: float) -> None:
        assert self._this is not None and self.origin is not None and self.destination is not None
        # slow the S-curve's clock while the vehicle lags its target (a time constant of accel / jerk)
        if self._target is not None:
            (tn, te), (tvn, tve), _ = self._target
            target_speed = math.hypot(tvn, tve)
            scaler = 1.0
            if target_speed > 0.0:
                un, ue = tvn / target_speed, tve / target_speed
                (n, e), (vn, ve, _) = vehicle.north_east_m, vehicle.velocity_ned
                track_error = (tn - n) * un + (te - e) * ue
                track_speed = vn * un + ve * ue
                scaler = TRACK_SCALER_MARGIN + (track_speed - self.motion.pos_p * track_error) / target_speed
                scaler = max(0.0, min(1.0, scaler))
            tc = self.motion.path_accel_m_s2 / self.motion.jerk_m_s3
            self._track_scaler += (scaler - self._track_scaler) * min(1.0, dt / tc)
        step = self._track_scaler * dt
        this, prev, following = self._this, self._prev, self._next
        # the target is the sum of the legs under way: the tail of the one before (about its destination, this origin),
        # this one, and the next one once its turn has begun (SCurve::advance_target_along_track)
        pos, vel, acc = [self.origin[0], self.origin[1]], [0.0, 0.0], [0.0, 0.0]
        if prev is not None:
            prev.elapsed_s = min(prev.elapsed_s + step, prev.end_s)
            _add(pos, vel, acc, prev.state(prev.elapsed_s), -prev.length_m, prev.unit)
        this.elapsed_s = min(this.elapsed_s + step, this.end_s)
        _add(pos, vel, acc, this.state(this.elapsed_s))
        finished = this.finished
        if following is not None and self.fast_waypoint:
            if following.elapsed_s == 0.0:
                if this.elapsed_s >= this.decel_start_s and this.remaining_s <= following.accel_end_s and self._turn_fits(this, following):
                    following.elapsed_s = step
                    _add(pos, vel, acc, following.state(following.elapsed_s))
            else:
                following.elapsed_s = min(following.elapsed_s + step, following.end_s)
                _add(pos, vel, acc, following.state(following.elapsed_s))
                if following.elapsed_s >= this.remaining_s:
                    finished = True  # half-way through the turn
        self._target = ((pos[0], pos[1]), (vel[0], vel[1]), (acc[0], acc[1]))
        if not self.reached and finished:
            if self.fast_waypoint:
                self.reached = True
            else:
                (n, e) = vehicle.north_east_m
                near = math.hypot(self.destination[0] - n, self.destination[1] - e) <= self.motion.radius_m
                self.reached = near or _past_finish_line(self.origin, self.destination, (n, e))

    def _turn_fits(self, this: SCurveLeg, following: SCurveLeg) -> bool:
        """SCurve::advance_target_along_track: start the next leg now? Its mid point near the waypoint, slow and gentle enough."""
        half = this.remaining_s / 2.0
        (p1, v1, a1), (p2, v2, a2) = this.state(this.elapsed_s + half), following.state(half)
        # relative to the waypoint: this leg's offset less its length, plus the next leg's offset
        un, ue = this.unit
        pn, pe = p1[0] - un * this.length_m + p2[0], p1[1] - ue * this.length_m + p2[1]
        speed = math.hypot(v1[0] + v2[0], v1[1] + v2[1])
        accel = math.hypot(a1[0] + a2[0], a1[1] + a2[1])
        speed_min = min(this.speed_limit_m_s, following.speed_limit_m_s)  # SCurve::get_speed_along_track: each leg's limit
        return math.hypot(pn, pe) < self.motion.corner_radius_m and speed < speed_min and accel < self.motion.lat_accel_m_s2

    def _position_control(self, vehicle: Driven, dt: float) -> tuple[float, float]:
        """AR_PosControl::update: the target's position, velocity and acceleration into a forward speed and a turn rate."""
        assert self._target is not None
        motion = self.motion
        (tn, te), (tvn, tve), (tan, tae) = self._target
        (n, e), (vn, ve, _) = vehicle.north_east_m, vehicle.velocity_ned
        # position error to velocity (AC_P_2D: square-root limited by min(accel, lateral accel) and jerk / P)
        en, ee = tn - n, te - e
        error = math.hypot(en, ee)
        error_max = self._error_max_m
        if error > error_max > 0.0:
            en, ee, error = en * error_max / error, ee * error_max / error, error_max
        want_n = want_e = 0.0
        if error > 0.0:
            rate = sqrt_controller(error, motion.pos_p, self._accel_limit)
            want_n, want_e = en * rate / error, ee * rate / error
        want_n, want_e = want_n + tvn, want_e + tve
        stopping = tvn == 0.0 and tve == 0.0
        size = math.hypot(want_n, want_e)
        speed_max = self._speed_max_m_s
        if size > speed_max > 0.0:
            want_n, want_e, size = want_n * speed_max / size, want_e * speed_max / size, speed_max
        vel_p = motion.vel_p
        accel_n = vel_p * (want_n - vn) + tan
        accel_e = vel_p * (want_e - ve) + tae
        yaw = vehicle.yaw_rad
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)  # forward (cos, sin), right (-sin, cos)
        speed = want_n * cos_yaw + want_e * sin_yaw
        if not stopping:  # at least the turning speed: max(min(size, turn_speed_min), speed)
            turning = motion.turn_speed_min_m_s
            turning = turning if turning < size else size
            speed = speed if speed > turning else turning
        speed = self._speed_limited(speed, dt)
        lateral = 0.0 if stopping else accel_n * -sin_yaw + accel_e * cos_yaw
        if not stopping and abs(lateral) < 1e-6 and accel_n * cos_yaw + accel_e * sin_yaw < 0.0:
            lateral = math.hypot(accel_n, accel_e)  # a target dead astern: a real vehicle's noise picks a side; here, the right
        steer_speed = abs(speed)
        steer_speed = STEER_SPEED_MIN_M_S if steer_speed < STEER_SPEED_MIN_M_S else steer_speed
        rate = lateral / math.copysign(steer_speed, speed if speed else 1.0)
        return speed, self._rate_limited(rate, vehicle, dt)

    def _speed_limited(self, speed: float, dt: float) -> float:
        """AR_AttitudeControl::get_desired_speed_accel_limited: from the last desired speed within ATC_ACCEL_MAX (ATC_DECEL_MAX slowing)."""
        motion = self.motion
        if motion.accel_max_m_s2 <= 0.0:
            self._desired_speed = speed
            return speed
        last = self._desired_speed
        slowing = abs(speed) < abs(last) and motion.decel_max_m_s2 > 0.0
        change = (motion.decel_max_m_s2 if slowing else motion.accel_max_m_s2) * dt
        self._desired_speed = within(speed, last - change, last + change)
        return self._desired_speed

    def _rate_limited(self, rate: float, vehicle: Driven, dt: float) -> float:
        """AR_AttitudeControl::get_steering_out_rate: ATC_STR_ACC_MAX, ATC_STR_RAT_MAX, then the lateral acceleration at this speed."""
        accel, limit = self._steer_accel_rad_s2, self._steer_rate_rad_s
        if accel is not None:
            change = accel * dt
            rate = within(rate, self._desired_rate - change, self._desired_rate + change)
        if limit is not None:
            rate = within(rate, -limit, limit)
        self._desired_rate = rate
        speed = abs(vehicle.speed_m_s)
        g_limit = self.motion.lat_accel_m_s2 / speed if speed > 0.0 else math.inf
        if g_limit < ONE_DEGREE_RAD:
            g_limit = ONE_DEGREE_RAD
        return within(rate, -g_limit, g_limit)

    def settle(self) -> None:
        """The speed and steering controllers at rest (disarmed, or a mode that does not use them)."""
        self._desired_speed = self._desired_rate = 0.0
        self._active = False


def _bearing_of(start: tuple[float, float], end: tuple[float, float]) -> float:
    return math.atan2(end[1] - start[1], end[0] - start[0])


def _past_finish_line(origin: tuple[float, float], destination: tuple[float, float], here: tuple[float, float]) -> bool:
    """Location::past_interval_finish_line: beyond the line through the destination square to the leg."""
    dn, de = destination[0] - origin[0], destination[1] - origin[1]
    return (here[0] - destination[0]) * dn + (here[1] - destination[1]) * de >= 0.0


def _add(
    pos: list[float], vel: list[float], acc: list[float], state: tuple[tuple[float, float], tuple[float, float], tuple[float, float]],
    shift_m: float = 0.0, unit: tuple[float, float] = (0.0, 0.0),
) -> None:  # fmt: skip
    """Add an S-curve's offset (shifted ``shift_m`` along ``unit``), velocity and acceleration to the running sums."""
    (pn, pe), (vn, ve), (an, ae) = state
    pos[0] += pn + unit[0] * shift_m
    pos[1] += pe + unit[1] * shift_m
    vel[0] += vn
    vel[1] += ve
    acc[0] += an
    acc[1] += ae
