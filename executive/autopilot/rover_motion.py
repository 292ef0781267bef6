"""How ArduRover moves toward its targets: the firmware's parameters and the kinematics they shape.

Facts read in ArduPilot 4.7-dev's source (each cited where it is used); the code is ours:

- ``libraries/AP_Math/control.cpp`` (``sqrt_controller``, ``shape_pos_vel_accel_xy``): a target is
  approached on a square-root profile, linear within the last ``limit / gain**2`` metres, and a
  shaped target's velocity and acceleration change within jerk and acceleration limits.
- ``libraries/APM_Control/AR_PosControl.cpp`` (``input_pos_target``, ``set_limits``, ``update``):
  GUIDED's position targets are shaped with ``accel = min(path acceleration, lateral acceleration)``;
  the approach's square-root branch brakes at half of it (``accel_tc_max = 0.5 * accel_max``).
- ``libraries/AR_WPNav/AR_WPNav.cpp`` (``init``): the path acceleration is
  ``min(ATC_ACCEL_MAX, ATC_DECEL_MAX or ATC_ACCEL_MAX, WP_ACCEL if set)``, the jerk WP_JERK or that
  acceleration; AUTO's legs are S-curves with a snap of 15 m/s^4 (``AR_WPNAV_SNAP_MAX``).
- ``libraries/AP_Math/SCurve.cpp``: an S-curve leg runs from rest to rest, its jerk rising and
  falling as a raised cosine over ``jerk * pi / (2 * snap)`` seconds.

The simulated ArduRover (:mod:`executive.sim.ardupilot.rover_nav`) drives by these; GoTo's look-ahead predicts
by them, from the parameters the vehicle itself reports (:class:`RoverMotion`).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

from executive.world.bounds import clamp

if TYPE_CHECKING:
    from executive.autopilot.port import Capabilities

GRAVITY_M_S2 = 9.80665
#: AR_WPNAV_SNAP_MAX (libraries/AR_WPNav/AR_WPNav.cpp): the S-curves' snap, m/s^4.
SCURVE_SNAP_M_S4 = 15.0
#: AR_WPNAV_ACCEL_MAX: the acceleration AR_WPNav uses when ATC_ACCEL_MAX is 0 (no limit), m/s/s.
UNLIMITED_ACCEL_M_S2 = 20.0
#: CORNER_ACCELERATION_RATIO (libraries/AP_Math/control.cpp): the share of the acceleration a shaped velocity keeps for turning.
CORNER_ACCELERATION_RATIO = 1.0 / math.sqrt(2.0)

#: The parameters that shape how ArduRover drives to a point, with the firmware's defaults (ArduPilot 4.7-dev):
#: WP_* in libraries/AR_WPNav/AR_WPNav.cpp and AR_PivotTurn.cpp, ATC_* in libraries/APM_Control/AR_AttitudeControl.cpp,
#: PSC_* in libraries/APM_Control/AR_PosControl.cpp, TURN_RADIUS and LOIT_RADIUS in Rover/Parameters.cpp.
FIRMWARE_DEFAULTS: Mapping[str, float] = {
    "WP_SPEED": 2.0,  # AR_WPNAV_SPEED_DEFAULT
    "WP_RADIUS": 2.0,  # AR_WPNAV_RADIUS_DEFAULT
    "WP_ACCEL": 0.0,  # 0: ATC_ACCEL_MAX
    "WP_JERK": 0.0,  # 0: the same as the acceleration
    "WP_PIVOT_ANGLE": 60.0,  # AR_PIVOT_ANGLE_DEFAULT
    "WP_PIVOT_RATE": 60.0,  # AR_PIVOT_RATE_DEFAULT
    "ATC_ACCEL_MAX": 1.0,  # AR_ATTCONTROL_THR_ACCEL_MAX
    "ATC_DECEL_MAX": 0.0,  # 0: ATC_ACCEL_MAX
    "ATC_TURN_MAX_G": 0.6,
    "ATC_STR_RAT_MAX": 120.0,  # AR_ATTCONTROL_STEER_RATE_MAX
    "ATC_STR_ACC_MAX": 120.0,  # AR_ATTCONTROL_STEER_ACCEL_MAX
    "TURN_RADIUS": 0.9,
    "PSC_POS_P": 0.2,  # AR_POSCON_POS_P
    "PSC_VEL_P": 1.0,  # AR_POSCON_VEL_P
}
#: The parameters GoTo's look-ahead reads from the vehicle at pre-flight (ArduRover).
LOOK_AHEAD_PARAMS: tuple[str, ...] = (
    "WP_SPEED", "WP_RADIUS", "WP_ACCEL", "WP_JERK", "WP_PIVOT_ANGLE", "ATC_ACCEL_MAX", "ATC_DECEL_MAX", "ATC_TURN_MAX_G",
    "TURN_RADIUS",
)  # fmt: skip
#: The outputs that tell a skid-steered rover: ThrottleLeft (73) and ThrottleRight (74) assigned (AP_MotorsUGV::have_skid_steering;
#: ArduRover's skid-steer frame puts them on SERVO1 and SERVO3). Other outputs are not read.
SKID_STEERING_PARAMS: tuple[str, ...] = ("SERVO1_FUNCTION", "SERVO3_FUNCTION")
SKID_STEERING_FUNCTIONS = frozenset({73.0, 74.0})
#: Everything the look-ahead reads.
MOTION_PARAMS: tuple[str, ...] = LOOK_AHEAD_PARAMS + SKID_STEERING_PARAMS


def sqrt_controller(error: float, gain: float, limit: float, dt: float = 0.0) -> float:
    """The rate that closes ``error``: ``gain * error`` near zero, then the rate from which ``limit`` stops it in time.

    As ``sqrt_controller`` (libraries/AP_Math/control.cpp): linear within ``limit / gain**2`` of zero,
    ``sqrt(2 * limit * (|error| - limit / (2 * gain**2)))`` beyond (the two meet there); with ``dt``,
    never more than would close the error within one step.
    """
    size = abs(error)
    if limit <= 0.0:
        rate = gain * size
    elif gain == 0.0:
        rate = math.sqrt(2.0 * limit * size)
    else:
        linear = limit / (gain * gain)
        rate = gain * size if size <= linear else math.sqrt(2.0 * limit * (size - linear / 2.0))
    if dt > 0.0 and size / dt < rate:  # min(rate, size / dt), without the builtin call: this runs several times a 20 ms step
        rate = size / dt
    return math.copysign(rate, error) if error else 0.0


def stopping_distance(speed: float, gain: float, limit: float) -> float:
    """The error from which :func:`sqrt_controller` asks for ``speed`` (its inverse: ``inv_sqrt_controller``)."""
    speed = abs(speed)
    if limit <= 0.0:
        return speed / gain if gain > 0.0 else 0.0
    if gain == 0.0:
        return speed * speed / (2.0 * limit)
    if speed < limit / gain:
        return speed / gain
    return limit / (2.0 * gain * gain) + speed * speed / (2.0 * limit)


def _limit_length(x: float, y: float, length: float) -> tuple[float, float]:
    size = math.hypot(x, y)
    if size > length > 0.0:
        return x * length / size, y * length / size
    return x, y


@dataclass(frozen=True)
class RoverMotion:
    """The parameters that shape ArduRover's driving, and what follows from them.

    ``skid_steering``: the vehicle can pivot (AP_MotorsUGV::have_skid_steering); Rover.cpp then gives
    AR_WPNav and AR_PosControl a turn radius of 0 and enables pivot turns.
    """

    speed_m_s: float = FIRMWARE_DEFAULTS["WP_SPEED"]
    radius_m: float = FIRMWARE_DEFAULTS["WP_RADIUS"]
    wp_accel_m_s2: float = FIRMWARE_DEFAULTS["WP_ACCEL"]
    wp_jerk_m_s3: float = FIRMWARE_DEFAULTS["WP_JERK"]
    pivot_angle_deg: float = FIRMWARE_DEFAULTS["WP_PIVOT_ANGLE"]
    pivot_rate_deg_s: float = FIRMWARE_DEFAULTS["WP_PIVOT_RATE"]
    accel_max_m_s2: float = FIRMWARE_DEFAULTS["ATC_ACCEL_MAX"]
    decel_max_m_s2: float = FIRMWARE_DEFAULTS["ATC_DECEL_MAX"]
    turn_max_g: float = FIRMWARE_DEFAULTS["ATC_TURN_MAX_G"]
    steer_rate_max_deg_s: float = FIRMWARE_DEFAULTS["ATC_STR_RAT_MAX"]
    steer_accel_max_deg_s2: float = FIRMWARE_DEFAULTS["ATC_STR_ACC_MAX"]
    turn_radius_param_m: float = FIRMWARE_DEFAULTS["TURN_RADIUS"]
    pos_p: float = FIRMWARE_DEFAULTS["PSC_POS_P"]
    vel_p: float = FIRMWARE_DEFAULTS["PSC_VEL_P"]
    skid_steering: bool = False
    #: Parameters taken at the firmware's default because the vehicle did not give them (for the log).
    defaulted: tuple[str, ...] = field(default=(), compare=False)

    _FIELDS = {
        "WP_SPEED": "speed_m_s", "WP_RADIUS": "radius_m", "WP_ACCEL": "wp_accel_m_s2", "WP_JERK": "wp_jerk_m_s3",
        "WP_PIVOT_ANGLE": "pivot_angle_deg", "WP_PIVOT_RATE": "pivot_rate_deg_s", "ATC_ACCEL_MAX": "accel_max_m_s2",
        "ATC_DECEL_MAX": "decel_max_m_s2", "ATC_TURN_MAX_G": "turn_max_g", "ATC_STR_RAT_MAX": "steer_rate_max_deg_s",
        "ATC_STR_ACC_MAX": "steer_accel_max_deg_s2", "TURN_RADIUS": "turn_radius_param_m", "PSC_POS_P": "pos_p", "PSC_VEL_P": "vel_p",
    }  # fmt: skip

    @classmethod
    def from_params(cls, params: Mapping[str, float], *, skid_steering: bool = False, wanted: tuple[str, ...] | None = None) -> RoverMotion:
        """From parameter values by name; any of ``wanted`` (all by default) missing is the firmware's default, noted in ``defaulted``."""
        values = {attr: float(params.get(name, FIRMWARE_DEFAULTS[name])) for name, attr in cls._FIELDS.items()}
        missing = tuple(name for name in (wanted if wanted is not None else tuple(cls._FIELDS)) if name not in params)
        return cls(**values, skid_steering=skid_steering, defaulted=missing)

    # -- what follows from the parameters (worked out once: the simulated rover reads them every 20 ms step) --

    @cached_property
    def decel_m_s2(self) -> float:
        """AR_AttitudeControl::get_decel_max: ATC_DECEL_MAX, or ATC_ACCEL_MAX when that is 0."""
        return self.decel_max_m_s2 if self.decel_max_m_s2 > 0.0 else self.accel_max_m_s2

    @cached_property
    def path_accel_m_s2(self) -> float:
        """AR_WPNav::init: the acceleration along a path (S-curves, and the position controller's limit)."""
        atc = min(self.accel_max_m_s2, self.decel_m_s2)
        if atc <= 0.0:
            atc = UNLIMITED_ACCEL_M_S2
        return min(self.wp_accel_m_s2, atc) if self.wp_accel_m_s2 > 0.0 else atc

    @cached_property
    def jerk_m_s3(self) -> float:
        """AR_WPNav::init: WP_JERK, or the path acceleration's value when 0."""
        return self.wp_jerk_m_s3 if self.wp_jerk_m_s3 > 0.0 else self.path_accel_m_s2

    @cached_property
    def lat_accel_m_s2(self) -> float:
        """AR_AttitudeControl::get_turn_lat_accel_max: ATC_TURN_MAX_G in m/s/s."""
        return self.turn_max_g * GRAVITY_M_S2

    @cached_property
    def shaping_accel_m_s2(self) -> float:
        """AR_PosControl::input_pos_vel_accel_target: a GUIDED target is shaped within min(path, lateral) acceleration."""
        return min(self.path_accel_m_s2, self.lat_accel_m_s2)

    @cached_property
    def turn_radius_m(self) -> float:
        """Rover.cpp set_turn_params: TURN_RADIUS, or 0 for a vehicle that can pivot."""
        return 0.0 if self.skid_steering else self.turn_radius_param_m

    @cached_property
    def corner_radius_m(self) -> float:
        """AR_WPNav::advance_wp_target_along_track: a fast waypoint's turn stays within max(WP_RADIUS, turn radius) of it."""
        return max(self.radius_m, self.turn_radius_m)

    @cached_property
    def turn_speed_min_m_s(self) -> float:
        """AR_PosControl::update: the least forward speed asked while turning, sqrt(0.5 * lateral accel * turn radius)."""
        return math.sqrt(0.5 * self.lat_accel_m_s2 * self.turn_radius_m)

    @cached_property
    def pivots(self) -> bool:
        """AR_PivotTurn: pivot turns happen (a skid-steered vehicle, WP_PIVOT_ANGLE above 5 degrees)."""
        return self.skid_steering and self.pivot_angle_deg > 5.0

    def approach_speed_m_s(self, distance_m: float, speed_max_m_s: float | None = None) -> float:
        """The speed GUIDED's shaped target has at ``distance_m`` from a stop point (the square-root approach, capped)."""
        a = self.shaping_accel_m_s2
        gain = 0.5 * self.jerk_m_s3 / a
        return min(sqrt_controller(distance_m, gain, 0.5 * a), self.speed_m_s if speed_max_m_s is None else speed_max_m_s)


def vehicle_motion(capabilities: Capabilities, params: Mapping[str, float] | None) -> RoverMotion | None:
    """The vehicle's driving as its parameters say (:data:`MOTION_PARAMS`; the firmware's default for any not read,
    listed in ``defaulted``); None for an autopilot whose driving is not modelled (its capabilities name no parameters)."""
    if not capabilities.motion_params:
        return None
    params = params or {}
    skid = {params.get(name) for name in SKID_STEERING_PARAMS} == SKID_STEERING_FUNCTIONS
    return RoverMotion.from_params(params, skid_steering=skid, wanted=LOOK_AHEAD_PARAMS)


class TargetEstimate:
    """Where ArduRover's GUIDED target is now, worked out as the firmware shapes it from the position targets sent.

    The autopilot's position controller pulls an internal target toward each position target
    (:class:`ShapedTarget`); the vehicle follows it. The executive sees only the vehicle, a moment old;
    this runs the same shaping on its own clock, in metres north and east of ``origin`` (lat, lon), from
    the vehicle's position and velocity when GUIDED's controller (re)starts (AR_PosControl::init).
    """

    STEP_S = 0.02  # the firmware's loop (SCHED_LOOP_RATE 50 Hz)

    def __init__(self, motion: RoverMotion, speed_m_s: float, origin: tuple[float, float], now: float) -> None:
        self._m_per_deg_lat = 111_319.49
        self._m_per_deg_lon = self._m_per_deg_lat * math.cos(math.radians(origin[0]))
        self.origin = origin
        self.target = ShapedTarget(speed_m_s, motion.shaping_accel_m_s2, motion.jerk_m_s3)
        self.time = now

    def ne(self, lat: float, lon: float) -> tuple[float, float]:
        return (lat - self.origin[0]) * self._m_per_deg_lat, (lon - self.origin[1]) * self._m_per_deg_lon

    def start(self, position: tuple[float, float], velocity_ne: tuple[float, float], now: float) -> None:
        """Start from the vehicle (lat, lon) at its velocity, at ``now``."""
        self.target.reset(self.ne(*position), velocity_ne)
        self.time = now

    def advance(self, destination: tuple[float, float], now: float) -> None:
        """Shape toward ``destination`` (lat, lon) up to ``now``."""
        goal = self.ne(*destination)
        while now - self.time >= self.STEP_S - 1e-9:
            self.target.step(goal, self.STEP_S)
            self.time += self.STEP_S

    def off_by_m(self, position: tuple[float, float]) -> float:
        """How far the estimate is from the vehicle (lat, lon)."""
        n, e = self.ne(*position)
        return math.hypot(self.target.pos[0] - n, self.target.pos[1] - e)


class ShapedTarget:
    """GUIDED's target as AR_PosControl::input_pos_target shapes it toward the latest position target (north, east in m).

    Each step moves the target on by its velocity and acceleration, then asks a velocity toward the
    destination on the square-root profile (gain ``0.5 * jerk / accel``, limit ``0.5 * accel``, capped at
    the speed), and an acceleration toward that velocity (gain ``jerk / accel``; the part across the
    velocity kept within ``accel / sqrt(2)`` when the part along it is larger), changed at most by the
    jerk (``shape_pos_vel_accel_xy`` and ``shape_vel_accel_xy``, libraries/AP_Math/control.cpp). A new
    destination keeps the velocity and acceleration reached: the target swings round, it does not stop.
    """

    def __init__(self, speed_m_s: float, accel_m_s2: float, jerk_m_s3: float) -> None:
        self.speed_m_s = speed_m_s
        self.accel_m_s2 = accel_m_s2
        self.jerk_m_s3 = jerk_m_s3
        # the square-root controllers' gains and limits, worked out once and passed by position (step runs every 20 ms: a
        # starred call builds a tuple and takes CPython's slow call path)
        self._approach_gain, self._approach_limit = 0.5 * jerk_m_s3 / accel_m_s2, 0.5 * accel_m_s2
        self._accel_gain = jerk_m_s3 / accel_m_s2
        self._corner_m_s2 = CORNER_ACCELERATION_RATIO * accel_m_s2
        self.pos = (0.0, 0.0)
        self.vel = (0.0, 0.0)
        self.acc = (0.0, 0.0)

    def reset(self, pos: tuple[float, float], vel: tuple[float, float], acc: tuple[float, float] = (0.0, 0.0)) -> None:
        """AR_PosControl::init: the target starts where the vehicle is, at its velocity."""
        self.pos, self.vel, self.acc = pos, vel, acc

    def step(self, destination: tuple[float, float], dt: float) -> None:
        (pn, pe), (vn, ve), (an, ae) = self.pos, self.vel, self.acc
        pn, pe = pn + vn * dt + 0.5 * an * dt * dt, pe + ve * dt + 0.5 * ae * dt * dt
        vn, ve = vn + an * dt, ve + ae * dt
        a, j = self.accel_m_s2, self.jerk_m_s3
        # the velocity that closes the distance to the destination
        en, ee = destination[0] - pn, destination[1] - pe
        size = math.hypot(en, ee)
        want_n = want_e = 0.0
        if size > 0.0:
            rate = sqrt_controller(size, self._approach_gain, self._approach_limit, dt)
            want_n, want_e = _limit_length(en * rate / size, ee * rate / size, self.speed_m_s)
        # the acceleration that closes the velocity error, with room kept for turning
        dn, de = want_n - vn, want_e - ve
        size = math.hypot(dn, de)
        cn = ce = 0.0
        if size > 0.0:
            rate = sqrt_controller(size, self._accel_gain, j, dt)
            cn, ce = dn * rate / size, de * rate / size
        want_speed = math.hypot(want_n, want_e)
        if want_speed == 0.0:
            cn, ce = _limit_length(cn, ce, a)
        else:
            un, ue = want_n / want_speed, want_e / want_speed
            along = cn * un + ce * ue
            xn, xe = cn - along * un, ce - along * ue
            if along * along <= xn * xn + xe * xe:
                cn, ce = _limit_length(cn, ce, a)
            else:
                xn, xe = _limit_length(xn, xe, self._corner_m_s2)
                # max(0.0, room2) written out, and clamp (ties and NaN as the builtins give them, which cost several times a
                # comparison: this runs 5 times a tick, and every 20 ms in the simulated rover)
                room2 = a * a - xn * xn - xe * xe
                room = math.sqrt(room2 if room2 > 0.0 else 0.0)
                along = clamp(along, room)
                cn, ce = xn + along * un, xe + along * ue
        # the acceleration moves toward that within the jerk
        dn, de = _limit_length(cn - an, ce - ae, j * dt)
        self.pos, self.vel, self.acc = (pn, pe), (vn, ve), (an + dn, ae + de)


@dataclass(frozen=True)
class _Segment:
    """A span of an S-curve: its jerk is constant, or rises/falls to/from ``jerk`` as a raised cosine."""

    start_s: float
    duration_s: float
    shape: str  # "const" | "rise" | "fall"
    jerk: float
    acc: float  # at the start
    vel: float
    pos: float

    def at(self, t: float) -> tuple[float, float, float]:
        """(position, velocity, acceleration) ``t`` seconds into the span."""
        a0, v0, p0, j = self.acc, self.vel, self.pos, self.jerk
        if self.shape == "const" or self.duration_s <= 0.0:
            return p0 + v0 * t + a0 * t * t / 2.0 + j * t**3 / 6.0, v0 + a0 * t + j * t * t / 2.0, a0 + j * t
        k = self.duration_s / math.pi
        s, c = math.sin(t / k), math.cos(t / k)
        half = j / 2.0
        if self.shape == "rise":  # jerk = j/2 * (1 - cos(t/k))
            acc = a0 + half * (t - k * s)
            vel = v0 + a0 * t + half * (t * t / 2.0 + k * k * (c - 1.0))
            pos = p0 + v0 * t + a0 * t * t / 2.0 + half * (t**3 / 6.0 + k * k * (k * s - t))
        else:  # jerk = j/2 * (1 + cos(t/k))
            acc = a0 + half * (t + k * s)
            vel = v0 + a0 * t + half * (t * t / 2.0 + k * k * (1.0 - c))
            pos = p0 + v0 * t + a0 * t * t / 2.0 + half * (t**3 / 6.0 + k * k * (t - k * s))
        return pos, vel, acc


class SCurveLeg:
    """One straight leg as AR_WPNav's S-curve drives it: from rest at ``origin`` to rest at ``destination`` (north, east in m).

    The speed rises to at most ``speed_m_s`` within ``accel_m_s2`` and ``jerk_m_s3``, each change of
    jerk a raised cosine lasting ``jerk * pi / (2 * snap)`` (SCurve::calculate_path), holds, and falls
    symmetrically. ``elapsed_s`` is the leg's own clock (AR_WPNav may run it slower than real time).
    """

    def __init__(
        self, origin: tuple[float, float], destination: tuple[float, float], speed_m_s: float, accel_m_s2: float, jerk_m_s3: float,
        snap_m_s4: float = SCURVE_SNAP_M_S4,
    ) -> None:  # fmt: skip
        self.origin, self.destination = origin, destination
        self.speed_limit_m_s = speed_m_s  # the leg's speed limit (vel_max), whether it reaches it or not
        dn, de = destination[0] - origin[0], destination[1] - origin[1]
        self.length_m = math.hypot(dn, de)
        self.unit = (dn / self.length_m, de / self.length_m) if self.length_m > 0.0 else (0.0, 0.0)
        self.elapsed_s = 0.0
        self._segments: list[_Segment] = []
        self._starts: list[float] = []  # the segments' start times, for :meth:`along`'s look-up
        self.accel_end_s = self.decel_start_s = self.end_s = 0.0
        if self.length_m > 0.0 and speed_m_s > 0.0 and accel_m_s2 > 0.0 and jerk_m_s3 > 0.0:
            self._build(speed_m_s, accel_m_s2, jerk_m_s3, snap_m_s4)

    @staticmethod
    def _ramp(peak_m_s: float, accel: float, jerk: float, ramp_s: float) -> tuple[float, float, float, float]:
        """Jerk, raised-cosine time, constant-jerk time and constant-acceleration time to go from rest to ``peak_m_s``.

        A rise of the acceleration to ``top`` and its fall back last ``2 * ramp_s + t2`` each (``top = jerk * (ramp_s + t2)``)
        and gain ``top * (2 * ramp_s + t2)`` between them; a hold at ``top`` gains ``top * t4``.
        """
        if peak_m_s >= accel * (ramp_s + accel / jerk):  # the acceleration reaches its limit
            t2 = accel / jerk - ramp_s
            return jerk, ramp_s, t2, (peak_m_s - accel * (2.0 * ramp_s + t2)) / accel
        top = jerk * (math.sqrt(ramp_s * ramp_s + 4.0 * peak_m_s / jerk) - ramp_s) / 2.0  # top * (ramp_s + top / jerk) = peak
        if top >= jerk * ramp_s:
            return jerk, ramp_s, top / jerk - ramp_s, 0.0
        return peak_m_s / (2.0 * ramp_s * ramp_s), ramp_s, 0.0, 0.0  # a small change: the jerk itself is less

    def _build(self, speed: float, accel: float, jerk: float, snap: float) -> None:
        ramp_s = jerk * math.pi / (2.0 * snap)
        if accel < jerk * ramp_s:  # too little acceleration for one raised cosine: shorter ramps, less jerk
            ramp_s = math.sqrt(accel * math.pi / (2.0 * snap))
            jerk = 2.0 * snap * ramp_s / math.pi

        def duration(peak: float) -> float:
            _, tj, t2, t4 = self._ramp(peak, accel, jerk, ramp_s)
            return 2.0 * (2.0 * tj + t2) + t4

        half = self.length_m / 2.0
        peak = speed
        # speeding up to ``peak`` covers peak * duration / 2 (the speed is symmetric about its half-way value)
        if peak * duration(peak) / 2.0 > half:
            low, high = 0.0, speed
            for _ in range(60):
                mid = (low + high) / 2.0
                low, high = (mid, high) if mid * duration(mid) / 2.0 <= half else (low, mid)
            peak = low
        j, tj, t2, t4 = self._ramp(peak, accel, jerk, ramp_s)
        plan = [("rise", tj, j), ("const", t2, j), ("fall", tj, j), ("const", t4, 0.0), ("rise", tj, -j), ("const", t2, -j), ("fall", tj, -j)]
        cruise = max(0.0, (self.length_m - peak * (2.0 * (2.0 * tj + t2) + t4)) / peak) if peak > 0.0 else 0.0
        plan += [("const", cruise, 0.0)] + [(shape, d, -jj) for shape, d, jj in plan]
        t = p = v = a = 0.0
        for index, (shape, d, jj) in enumerate(plan):
            segment = _Segment(t, d, shape, jj, a, v, p)
            self._segments.append(segment)
            p, v, a = segment.at(d)
            if index == 6:
                a = 0.0  # numerical dust
            t += d
            if index == 6:
                self.accel_end_s = t
            if index == 7:
                self.decel_start_s = t
        self.end_s = t
        self._starts = [segment.start_s for segment in self._segments]

    @property
    def finished(self) -> bool:
        return self.elapsed_s >= self.end_s

    @property
    def remaining_s(self) -> float:
        return max(0.0, self.end_s - self.elapsed_s)

    def along(self, t: float) -> tuple[float, float, float]:
        """(distance from the origin, speed, acceleration) along the leg ``t`` seconds into it."""
        if not self._segments:
            return 0.0, 0.0, 0.0
        if t >= self.end_s:
            return self.length_m, 0.0, 0.0
        t = t if t > 0.0 else 0.0  # max(0.0, t), written out as in ShapedTarget.step
        index = bisect_right(self._starts, t) - 1  # the last span begun by t (of spans of no time, the last)
        if index < 0:
            return 0.0, 0.0, 0.0
        segment = self._segments[index]
        pos, vel, acc = segment.at(t - segment.start_s)
        pos = 0.0 if pos < 0.0 else pos  # min(max(pos, 0.0), length), written out
        return self.length_m if self.length_m < pos else pos, vel, acc

    def state(self, t: float) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
        """Offset from the origin, velocity and acceleration (north, east) ``t`` seconds into the leg."""
        pos, vel, acc = self.along(t)
        un, ue = self.unit
        return (un * pos, ue * pos), (un * vel, ue * vel), (un * acc, ue * acc)

    @property
    def speed_max_m_s(self) -> float:
        """The highest speed the leg reaches."""
        return self.along(self.accel_end_s)[1] if self._segments else 0.0


# -- corners: what AUTO cuts, and what a GUIDED target switched early would cut ------------------------------


def _route_distance(point: tuple[float, float], corner: tuple[float, float], inbound: tuple[float, float], outbound: tuple[float, float]) -> float:
    """Distance from ``point`` to the route through ``corner``: the inbound leg's line before it, the outbound's after it (unit vectors)."""
    dn, de = point[0] - corner[0], point[1] - corner[1]
    distances = []
    for (un, ue), sign in ((inbound, -1.0), (outbound, 1.0)):
        along = (dn * un + de * ue) * sign  # how far along this leg, away from the corner
        if along <= 0.0:
            distances.append(math.hypot(dn, de))
        else:
            distances.append(abs(dn * ue - de * un))
    to_inbound, to_outbound = distances
    return to_outbound if to_outbound < to_inbound else to_inbound  # min(), written out as in ShapedTarget.step


def _unit(bearing_rad: float) -> tuple[float, float]:
    return math.cos(bearing_rad), math.sin(bearing_rad)


def auto_corner_cut_m(motion: RoverMotion, inbound_m: float, outbound_m: float, turn_rad: float, speed_m_s: float | None = None) -> float | None:
    """How far from the route AUTO's target goes through a fast waypoint between legs of these lengths.

    As SCurve::advance_target_along_track: each leg an S-curve from rest to rest; the next one starts,
    added to this one, once this one decelerates, will end before the next has finished speeding up, and
    the mid point of the overlap lies within max(WP_RADIUS, TURN_RADIUS) of the waypoint, slower than
    the legs' speed and within the lateral acceleration. None when the turn never blends (a stop there).
    """
    speed = speed_m_s if speed_m_s and speed_m_s > 0.0 else motion.speed_m_s
    a, j = motion.path_accel_m_s2, motion.jerk_m_s3
    inbound, outbound = (1.0, 0.0), _unit(turn_rad)
    corner = (inbound_m, 0.0)
    this = SCurveLeg((0.0, 0.0), corner, speed, a, j)
    following = SCurveLeg(corner, (corner[0] + outbound[0] * outbound_m, outbound[1] * outbound_m), speed, a, j)
    dt = 0.02
    t = this.decel_start_s
    while t < this.end_s:
        overlap = this.end_s - t
        if overlap <= following.accel_end_s:
            half = overlap / 2.0
            (p1, v1, a1), (p2, v2, a2) = this.state(t + half), following.state(half)
            mid = (p1[0] + p2[0] - corner[0], p1[1] + p2[1])
            fits = math.hypot(*mid) < motion.corner_radius_m and math.hypot(v1[0] + v2[0], v1[1] + v2[1]) < speed
            if fits and math.hypot(a1[0] + a2[0], a1[1] + a2[1]) < motion.lat_accel_m_s2:
                break
        t += dt
    else:
        return None
    worst, start = 0.0, t
    while t <= this.end_s + following.end_s:
        (p1, _, _), (p2, _, _) = this.state(t), following.state(t - start)
        here = _route_distance((p1[0] + p2[0], p1[1] + p2[1]), corner, inbound, outbound)
        worst = here if here > worst else worst  # max(), written out as in ShapedTarget.step
        if t - start >= this.end_s - start + 1.0:
            break
        t += dt
    return worst


def guided_switch_cut_m(
    motion: RoverMotion, distance_m: float, speed_m_s: float, turn_rad: float, outbound_m: float, speed_max_m_s: float | None = None,
    accel_m_s2: float | None = None,
) -> float:  # fmt: skip
    """How far from the route GUIDED's shaped target goes when the next waypoint replaces the corner ``distance_m`` ahead.

    The target, under way toward the corner at ``speed_m_s`` (changing at ``accel_m_s2``; by default braking on the
    approach's square-root curve), is pulled toward the next waypoint (:class:`ShapedTarget`): its velocity swings
    round within the shaping's acceleration, keeping a share for turning; the path rounds the corner inside. The
    faster it comes, the farther it carries on toward the corner before it turns: the less it cuts.
    """
    a = motion.shaping_accel_m_s2
    target = ShapedTarget(speed_max_m_s if speed_max_m_s and speed_max_m_s > 0.0 else motion.speed_m_s, a, motion.jerk_m_s3)
    inbound, outbound = (1.0, 0.0), _unit(turn_rad)
    corner = (distance_m, 0.0)
    if accel_m_s2 is None:
        accel_m_s2 = -min(0.5 * a, speed_m_s * speed_m_s / (2.0 * max(distance_m, 1e-3)))  # on the approach's square-root curve
    target.reset((0.0, 0.0), (speed_m_s, 0.0), (accel_m_s2, 0.0))
    destination = (corner[0] + outbound[0] * outbound_m, outbound[1] * outbound_m)
    bisector = (inbound[0] + outbound[0], inbound[1] + outbound[1])
    worst, last, dt = 0.0, 0.0, 0.05
    for _ in range(round(30.0 / dt)):
        target.step(destination, dt)
        (n, e), (vn, ve) = target.pos, target.vel
        here = _route_distance((n, e), corner, inbound, outbound)
        worst = here if here > worst else worst  # max(), written out as in ShapedTarget.step
        round_it = (n - corner[0]) * bisector[0] + e * bisector[1] > 0.0 and vn * outbound[0] + ve * outbound[1] > 0.98 * math.hypot(vn, ve)
        if round_it and here < last:
            break  # round the corner, on the next leg's course, closing on its line: the worst is behind
        last = here
    return worst
