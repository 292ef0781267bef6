"""Kinematics of the simulated vehicles: where they are and how they move. No IO, no MAVLink.

Positions are integrated on a flat patch of earth around the start point (metres north/east),
which is accurate to centimetres over the few kilometres a mission spans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import executive
from executive.world.bounds import clamp

_EARTH_RADIUS_M = 6378137.0


def wrap_pi(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class VehicleModel(Protocol):
    """What an autopilot needs from a vehicle model (surface vehicles now; a sub or a VTOL later)."""

    powered: bool  # armed: motors respond; unpowered, the vehicle does not move at all

    @property
    def lat(self) -> float: ...
    @property
    def lon(self) -> float: ...
    @property
    def alt_m(self) -> float:
        """Height above the start point (negative = depth)."""
        ...

    @property
    def heading_deg(self) -> float: ...
    @property
    def velocity_ned(self) -> tuple[float, float, float]: ...
    @property
    def yaw_rate_rad_s(self) -> float: ...
    @property
    def speed_m_s(self) -> float:
        """Forward speed through the medium (positive ahead)."""
        ...

    @property
    def target(self) -> tuple[float, float] | None: ...
    @property
    def arrived(self) -> bool: ...

    def drive_to(self, lat: float, lon: float, speed_m_s: float | None = None) -> None: ...
    def hold(self) -> None: ...
    def stopping_point(self) -> tuple[float, float]: ...
    def distance_to(self, lat: float, lon: float) -> float: ...
    def bearing_to(self, lat: float, lon: float) -> float: ...
    def step(self, dt: float) -> None: ...


@dataclass(frozen=True)
class MotionLimits:
    """How a surface vehicle can move."""

    cruise_m_s: float = 2.0
    max_m_s: float = 3.5
    accel_m_s2: float = 1.0
    decel_m_s2: float = 1.5
    turn_rate_deg_s: float = 90.0
    arrive_m: float = 0.3  # closer than this to its target, the vehicle stops and holds
    drift_m_s: float = 0.0  # a water current (boats) that pushes a powered vehicle: LOITER corrects it
    drift_toward_deg: float = 0.0
    #: The sideways acceleration a turn may take: ATC_TURN_MAX_G, 0.6 g by default (libraries/APM_Control/AR_AttitudeControl.cpp).
    lat_accel_m_s2: float = 0.6 * 9.80665
    #: TURN_RADIUS (Rover/Parameters.cpp, 0.9 m by default). AR_PosControl::update keeps the forward speed in a turn at
    #: least sqrt(0.5 * lateral acceleration * TURN_RADIUS) (the vehicle drives round, it does not stop to turn).
    #: 0: the vehicle pivots on the spot (skid steering: AR_WPNav::set_turn_params zeroes it when a pivot is possible).
    turn_radius_m: float = 0.0
    #: Driven by an autopilot's navigator (:meth:`SurfaceVehicle.follow`): how long the vehicle (its motors and the
    #: autopilot's throttle controller) takes to reach about two thirds of a change of the speed asked, s (0: at once).
    speed_lag_s: float = 0.0
    #: ... and the least radius it can turn on at speed (an Ackermann vehicle's steering lock; 0: it can turn on the spot).
    min_turn_radius_m: float = 0.0

    @property
    def turn_speed_min_m_s(self) -> float:
        """The least forward speed in a turn (AR_PosControl::update's turn_speed_min)."""
        return math.sqrt(0.5 * self.lat_accel_m_s2 * self.turn_radius_m)


ROVER_LIMITS = MotionLimits(turn_radius_m=0.9)
BOAT_LIMITS = MotionLimits(accel_m_s2=0.6, decel_m_s2=1.0, turn_rate_deg_s=45.0, drift_m_s=0.03, drift_toward_deg=60.0, turn_radius_m=0.9)


class LocalFrame:
    """A local flat-earth frame (north, east in metres) about a start point: adequate over a simulated mission's few km.

    Subclasses keep their position in ``_n``, ``_e`` (metres from the start point).
    """

    _n: float
    _e: float

    @property
    def lat(self) -> float:
        return self._lat0 + self._n / self._m_per_deg_lat  # _latlon's, one coordinate: most messages ask both, one at a time

    @property
    def lon(self) -> float:
        return self._lon0 + self._e / self._m_per_deg_lon

    def _init_frame(self, lat: float, lon: float) -> None:
        self._lat0, self._lon0 = lat, lon
        self._m_per_deg_lat = math.radians(1.0) * _EARTH_RADIUS_M
        self._m_per_deg_lon = self._m_per_deg_lat * math.cos(math.radians(lat))

    def _ne(self, lat: float, lon: float) -> tuple[float, float]:
        return (lat - self._lat0) * self._m_per_deg_lat, (lon - self._lon0) * self._m_per_deg_lon

    def _latlon(self, n: float, e: float) -> tuple[float, float]:
        return self._lat0 + n / self._m_per_deg_lat, self._lon0 + e / self._m_per_deg_lon


class Navigator(Protocol):
    """An autopilot's navigation that drives the vehicle (ArduRover's: :class:`executive.sim.ardupilot.rover_nav.RoverNavigator`)."""

    @property
    def destination(self) -> tuple[float, float] | None:
        """Where it is going (north, east in metres), if anywhere."""
        ...

    @property
    def reached(self) -> bool: ...

    def control(self, vehicle: SurfaceVehicle, dt: float) -> tuple[float, float]:
        """The forward speed (m/s) and turn rate (rad/s, clockwise) asked after ``dt`` seconds."""
        ...


class SurfaceVehicle(LocalFrame):
    """A rover or a boat: position, heading and forward speed, with a drive-to-target controller.

    The controller turns toward the target (turn-rate and lateral-acceleration limited), drives at
    the requested speed (acceleration limited), slows down on a profile it can always brake to, and
    stops within ``limits.arrive_m`` of the target. Without a target it brakes to a stop and stays there.

    An autopilot with a navigation of its own (ArduRover's AUTO, GUIDED, RTL) drives it through
    :meth:`follow` instead: its :class:`Navigator` asks the speed and turn rate each step.
    """

    SUBSTEP_S = 0.05
    #: Driven by a navigator, steps as short as its firmware's loop (ArduRover: SCHED_LOOP_RATE 50 Hz, AP_Scheduler.cpp).
    NAVIGATOR_STEP_S = 0.02
    STANDSTILL_M_S = 0.005  # slower than this with no speed asked, a navigator-driven vehicle has stopped
    _substep_s = SUBSTEP_S
    HEADING_GAIN = 2.0  # turn rate (rad/s) asked per radian of heading error
    APPROACH_GAIN = 1.0  # speed (m/s) allowed per metre left, for the last metres

    def __init__(self, lat: float, lon: float, heading_deg: float = 0.0, limits: MotionLimits = ROVER_LIMITS) -> None:
        self.limits = limits
        self.powered = False
        self.heading_bias_deg = 0.0  # compass error the controller steers by (fault injection): it heads this far off
        self._init_frame(lat, lon)
        self._n = self._e = 0.0
        self._yaw = wrap_pi(math.radians(heading_deg))
        self._speed = 0.0
        self._yaw_rate = 0.0
        self._target: tuple[float, float] | None = None  # north, east (m)
        self._target_speed = limits.cruise_m_s
        self._arrived = False
        self._manual: tuple[float, float] | None = None  # (throttle, steering) from a pilot
        self._navigator: Navigator | None = None
        toward = math.radians(limits.drift_toward_deg)
        self._drift = (limits.drift_m_s * math.cos(toward), limits.drift_m_s * math.sin(toward))

    # -- state ---------------------------------------------------------------------------------

    @property
    def alt_m(self) -> float:
        return 0.0

    @property
    def north_east_m(self) -> tuple[float, float]:
        """Position in metres north and east of the start point."""
        return self._n, self._e

    @property
    def heading_deg(self) -> float:
        """Heading in [0, 360)."""
        return math.degrees(self._yaw) % 360.0

    @property
    def yaw_rad(self) -> float:
        """Heading in radians, clockwise from north, in [-pi, pi)."""
        return self._yaw

    @property
    def speed_m_s(self) -> float:
        return self._speed

    @property
    def yaw_rate_rad_s(self) -> float:
        return self._yaw_rate

    @property
    def velocity_ned(self) -> tuple[float, float, float]:
        """Velocity over ground (north, east, down), drift included."""
        drift_n, drift_e = self._drift if self.powered else (0.0, 0.0)
        return self._speed * math.cos(self._yaw) + drift_n, self._speed * math.sin(self._yaw) + drift_e, 0.0

    @property
    def target(self) -> tuple[float, float] | None:
        """The (lat, lon) being driven to, if any."""
        if self._navigator is not None:
            destination = self._navigator.destination
            return None if destination is None else self._latlon(*destination)
        return None if self._target is None else self._latlon(*self._target)

    @property
    def arrived(self) -> bool:
        """True once within ``limits.arrive_m`` of the target (until the next order); driven by a navigator, as it says."""
        if self._navigator is not None:
            return self._navigator.reached
        return self._arrived

    def distance_to(self, lat: float, lon: float) -> float:
        n, e = self._ne(lat, lon)
        return math.hypot(n - self._n, e - self._e)

    def bearing_to(self, lat: float, lon: float) -> float:
        """Bearing in [0, 360) from the vehicle to a point."""
        n, e = self._ne(lat, lon)
        return math.degrees(math.atan2(e - self._e, n - self._n)) % 360.0

    def stopping_point(self) -> tuple[float, float]:
        """Where the vehicle would stop if it braked now."""
        ahead = self._speed * abs(self._speed) / (2.0 * self.limits.decel_m_s2)
        return self._latlon(self._n + ahead * math.cos(self._yaw), self._e + ahead * math.sin(self._yaw))

    # -- orders ------------------------------------------------------------------------------

    def follow(self, navigator: Navigator) -> None:
        """Be driven by an autopilot's navigation (until another order): it asks the speed and turn rate every step."""
        self._target = None
        self._manual = None
        self._arrived = False
        self._navigator = navigator

    def ne_of(self, lat: float, lon: float) -> tuple[float, float]:
        """A point's metres north and east of the start point."""
        return self._ne(lat, lon)

    def drive_to(self, lat: float, lon: float, speed_m_s: float | None = None) -> None:
        """Drive to a point at ``speed_m_s`` (default cruise, capped at the maximum) and stop there."""
        self._navigator = None
        self._target = self._ne(lat, lon)
        self._manual = None
        self._target_speed = min(speed_m_s if speed_m_s and speed_m_s > 0 else self.limits.cruise_m_s, self.limits.max_m_s)
        self._arrived = False

    def hold(self) -> None:
        """Forget the target and brake to a stop."""
        self._navigator = None
        self._target = None
        self._arrived = False
        self._manual = None

    def drive_manual(self, throttle: float, steering: float) -> None:
        """A pilot's sticks, each in [-1, 1]: forward speed and turn rate as fractions of the maximum."""
        self._target = None
        self._navigator = None
        self._manual = (clamp(throttle, 1.0), clamp(steering, 1.0))

    # -- physics -------------------------------------------------------------------------------

    def step(self, dt: float) -> None:
        """Advance ``dt`` seconds, in sub-steps of at most ``SUBSTEP_S`` (``NAVIGATOR_STEP_S`` driven by a navigator)."""
        longest = self.SUBSTEP_S if self._navigator is None else self.NAVIGATOR_STEP_S  # no order changes it during a step
        while dt > 1e-9:
            h = dt if dt < longest else longest
            self._substep(h)
            dt -= h

    def _substep(self, h: float) -> None:
        if not self.powered:
            self._speed = self._yaw_rate = 0.0
            return
        self._substep_s = h
        self._speed, self._yaw_rate = self._actuate(*self._control(), h)
        self._move(h)

    def _move(self, h: float) -> None:
        """Turn and travel ``h`` seconds at the present speed and turn rate (over ground: :attr:`velocity_ned`, written out)."""
        yaw = self._yaw = wrap_pi(self._yaw + self._yaw_rate * h)
        drift_n, drift_e = self._drift if self.powered else (0.0, 0.0)
        self._n += (self._speed * math.cos(yaw) + drift_n) * h
        self._e += (self._speed * math.sin(yaw) + drift_e) * h

    def _actuate(self, want_speed: float, want_rate: float, h: float) -> tuple[float, float]:
        """The speed and turn rate reached after ``h`` seconds of asking for these (acceleration limited).

        Driven by a navigator, the autopilot has limited the acceleration already: the speed follows the demand
        with the vehicle's lag, the turn rate within its least turning radius.
        """
        limits = self.limits
        if self._navigator is not None:
            speed = want_speed
            if limits.speed_lag_s > 0.0:
                speed = self._speed + (want_speed - self._speed) * (1.0 - math.exp(-h / limits.speed_lag_s))
                if want_speed == 0.0 and abs(speed) < self.STANDSTILL_M_S:
                    speed = 0.0  # the lag's tail would creep on for ever: a drive train asked for nothing stops
            if limits.min_turn_radius_m > 0.0:
                want_rate = clamp(want_rate, abs(speed) / limits.min_turn_radius_m)
            return speed, want_rate
        change = want_speed - self._speed
        return self._speed + clamp(change, (self.limits.accel_m_s2 if change > 0 else self.limits.decel_m_s2) * h), want_rate

    def _control(self) -> tuple[float, float]:
        """Speed and turn rate wanted now."""
        if self._manual is not None:
            throttle, steering = self._manual
            return throttle * self.limits.max_m_s, steering * math.radians(self.limits.turn_rate_deg_s)
        if self._navigator is not None:
            return self._navigator.control(self, self._substep_s)
        if self._target is None or self._arrived:
            return 0.0, 0.0
        dn, de = self._target[0] - self._n, self._target[1] - self._e
        distance = math.hypot(dn, de)
        if distance <= self.limits.arrive_m:
            self._arrived = True
            return 0.0, 0.0
        limits = self.limits
        error = wrap_pi(math.atan2(de, dn) - self._yaw - math.radians(self.heading_bias_deg))
        rate_max = math.radians(limits.turn_rate_deg_s)
        if abs(self._speed) > 1e-3:
            turn_max_g = limits.lat_accel_m_s2 / abs(self._speed)  # ATC_TURN_MAX_G
            rate_max = turn_max_g if turn_max_g < rate_max else rate_max
        rate = clamp(self.HEADING_GAIN * error, rate_max)
        # a braking profile with margin, then a linear approach: never overshoots the target (the shape of ArduPilot's
        # sqrt_controller stopping a shaped target, libraries/AP_Math/control.cpp)
        brake = math.sqrt(2.0 * 0.8 * limits.decel_m_s2 * distance)
        approach = self.APPROACH_GAIN * distance
        speed = self._target_speed  # min(target speed, brake, approach)
        speed = brake if brake < speed else speed
        speed = approach if approach < speed else speed
        # turn toward a target behind before driving to it (the forward part of the speed); a vehicle under way that
        # cannot pivot keeps the least turning speed through the turn (AR_PosControl::update,
        # libraries/APM_Control/AR_PosControl.cpp); one at rest turns first (as LOITER does, Rover/mode_loiter.cpp)
        turning = speed  # min(speed, turn_speed_min, |speed now|)
        turning = limits.turn_speed_min_m_s if limits.turn_speed_min_m_s < turning else turning
        turning = abs(self._speed) if abs(self._speed) < turning else turning
        ahead = speed * math.cos(error)
        return turning if turning > ahead else ahead, rate


@dataclass(frozen=True)
class Tracks:
    """The running gear of a skid-steered (tracked) vehicle."""

    width_m: float = 0.55  # between the track centre lines (AgileX Bunker)
    max_m_s: float = 1.5  # a track at full throttle
    # Tracks skid sideways in a turn: the vehicle turns as if its tracks were this much farther apart
    # (the "expanded instantaneous centres of rotation" of tracked-vehicle kinematics).
    slip_factor: float = 1.3


BUNKER_LIMITS = MotionLimits(cruise_m_s=1.0, max_m_s=1.5, accel_m_s2=0.8, decel_m_s2=1.5, turn_rate_deg_s=60.0)
BUNKER_TRACKS = Tracks()


class SkidSteerVehicle(SurfaceVehicle):
    """A tracked vehicle steered by the speed difference of its tracks (ArduRover's skid-steer frame).

    The drive-to-target controller is the one of :class:`SurfaceVehicle`; its speed and turn-rate
    demand goes through ArduRover's skid-steer mixer (throttle +/- steering, scaled back together
    when they saturate) to a left and a right track throttle in [-1, 1] (:attr:`track_throttles`),
    and the vehicle moves as its tracks do, slipping in turns. Unpowered, both throttles are 0.

    With :attr:`base_command` set (a simulated AgileX base in CAN command mode), the throttles are
    only the autopilot's outputs: the base's own controller drives the tracks at the commanded
    linear and angular speed instead, whether the autopilot is armed or not (the base has power of
    its own). The autopilot then ramps its speed demand on its own, without seeing the base's speed.
    """

    def __init__(
        self, lat: float, lon: float, heading_deg: float = 0.0, limits: MotionLimits = BUNKER_LIMITS, tracks: Tracks = BUNKER_TRACKS
    ) -> None:
        super().__init__(lat, lon, heading_deg, limits)
        self.tracks = tracks
        #: (linear m/s, angular rad/s, positive counter-clockwise) the base's controller drives at; None: the throttles drive the tracks.
        self.base_command: tuple[float, float] | None = None
        self._left = self._right = 0.0
        self._demand_m_s = 0.0  # the autopilot's speed demand
        self._track_speeds = (0.0, 0.0)
        self._odometry = (0.0, 0.0)

    @property
    def track_throttles(self) -> tuple[float, float]:
        """Left and right track throttle in [-1, 1] (positive = forward), as last commanded."""
        return self._left, self._right

    @property
    def odometry_m(self) -> tuple[float, float]:
        """Distance the left and right tracks have run since the start (backwards counts down)."""
        return self._odometry

    def _substep(self, h: float) -> None:
        if not self.powered:
            self._left = self._right = self._demand_m_s = 0.0
            self._track_speeds = (0.0, 0.0)
        if self.base_command is not None and not self.powered:
            self._speed, self._yaw_rate = self._follow_base_command(h)
            self._move(h)
        else:
            super()._substep(h)
        left, right = self._track_speeds
        self._odometry = (self._odometry[0] + left * h, self._odometry[1] + right * h)

    def _actuate(self, want_speed: float, want_rate: float, h: float) -> tuple[float, float]:
        if self.base_command is None:
            speed, rate = super()._actuate(want_speed, want_rate, h)
        else:
            change = want_speed - self._demand_m_s
            speed, rate = self._demand_m_s + clamp(change, (self.limits.accel_m_s2 if change > 0 else self.limits.decel_m_s2) * h), want_rate
        self._demand_m_s = speed
        t = self.tracks
        # a turn-rate controller learns the steering the slip needs: ask the tracks for it
        throttle = speed / t.max_m_s
        steering = rate * t.width_m * t.slip_factor / 2.0 / t.max_m_s  # positive = right turn
        self._left, self._right = skid_steer_mix(throttle, steering)
        if self.base_command is not None:
            return self._follow_base_command(h)
        left, right = self._left * t.max_m_s, self._right * t.max_m_s
        self._track_speeds = (left, right)
        return (left + right) / 2.0, (left - right) / (t.width_m * t.slip_factor)

    def _follow_base_command(self, h: float) -> tuple[float, float]:
        """The base's controller: speed and turn rate (clockwise) reached after ``h`` s of :attr:`base_command`.

        Its speed ramps within the vehicle's limits; it asks the tracks for the turn rate the slip
        needs, and when a track would exceed its top speed both are scaled back (the turn's
        curvature is kept).
        """
        assert self.base_command is not None
        linear, angular = self.base_command
        t = self.tracks
        change = linear - self._speed
        linear = self._speed + clamp(change, (self.limits.accel_m_s2 if change > 0 else self.limits.decel_m_s2) * h)
        half_difference = -angular * t.width_m * t.slip_factor / 2.0  # counter-clockwise: the right track runs faster
        left, right = linear + half_difference, linear - half_difference
        over = max(abs(left), abs(right)) / t.max_m_s
        if over > 1.0:
            left, right = left / over, right / over
        self._track_speeds = (left, right)
        return (left + right) / 2.0, (left - right) / (t.width_m * t.slip_factor)


def skid_steer_mix(throttle: float, steering: float) -> tuple[float, float]:
    """ArduRover's skid-steer mixer (symmetric thrust, MOT_STR_THR_MIX 0.5): (left, right) in [-1, 1].

    Throttle and steering are in [-1, 1] (steering positive = turn right). When they do not fit
    together, steering is scaled back by the saturation and throttle gets what is left.
    """
    throttle, steering = clamp(throttle, 1.0), clamp(steering, 1.0)
    saturation = abs(throttle) + abs(steering)
    if saturation > 1.0:
        steering /= saturation
        throttle = math.copysign(1.0 - abs(steering), throttle)
    return clamp(throttle + steering, 1.0), clamp(throttle - steering, 1.0)


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Limits is MotionLimits
    return executive.moved_attribute(__name__, name)
