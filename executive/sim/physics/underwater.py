"""Kinematics of the simulated underwater vehicle (an ArduSub ROV/AUV) and of the seabed under it. No IO.

Horizontally the vehicle moves like a slow :class:`~executive.sim.physics.vehicle.SurfaceVehicle`; vertically
it has its own depth controller. Depth is positive down from the surface (altitude = -depth).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from executive.sim.physics.vehicle import MotionLimits, SurfaceVehicle
from executive.world.bounds import clamp


@dataclass(frozen=True)
class Seabed:
    """A plane seabed: ``depth_m`` deep under the start point, deepening by ``slope`` (m per m) toward ``downhill_deg``."""

    depth_m: float = 30.0
    slope: float = 0.02
    downhill_deg: float = 90.0
    min_depth_m: float = 1.0  # a shoal never rises above this

    def depth_at(self, north_m: float, east_m: float) -> float:
        """Water depth (m) at a point given in metres from the start point."""
        toward = math.radians(self.downhill_deg)
        along = north_m * math.cos(toward) + east_m * math.sin(toward)
        depth = self.depth_m + self.slope * along
        return depth if depth > self.min_depth_m else self.min_depth_m


SUB_HORIZONTAL_LIMITS = MotionLimits(cruise_m_s=0.8, max_m_s=1.0, accel_m_s2=0.3, decel_m_s2=0.5, turn_rate_deg_s=30.0, arrive_m=0.3)


@dataclass(frozen=True)
class SubLimits:
    """How an underwater vehicle can move."""

    horizontal: MotionLimits = SUB_HORIZONTAL_LIMITS
    climb_m_s: float = 0.5
    descend_m_s: float = 0.5
    vertical_accel_m_s2: float = 0.3
    buoyancy_m_s: float = 0.05  # not holding a depth, a slightly buoyant vehicle rises this fast (as ArduSub vehicles are trimmed)
    hull_m: float = 0.3  # the vehicle's bottom is this far below its depth sensor: how close it gets to the seabed


SUB_LIMITS = SubLimits()


class UnderwaterVehicle:
    """An underwater vehicle: a horizontal drive-to-target controller plus a depth controller.

    The depth controller holds a depth (:meth:`hold_depth_at`) or a height above the seabed
    (:meth:`hold_altitude_at`), at limited vertical speed and acceleration, braking on a profile;
    released (:meth:`release_depth`) or unpowered, the vehicle rises at ``limits.buoyancy_m_s``.
    The surface and the seabed stop it.
    """

    SUBSTEP_S = SurfaceVehicle.SUBSTEP_S
    DEPTH_GAIN = 0.5  # vertical speed (m/s) asked per metre of depth error, for the last metres

    def __init__(self, lat: float, lon: float, heading_deg: float = 0.0, limits: SubLimits = SUB_LIMITS, seabed: Seabed | None = None) -> None:
        self.limits = limits
        self.seabed = seabed if seabed is not None else Seabed()
        self._horizontal = SurfaceVehicle(lat, lon, heading_deg, limits.horizontal)
        self._depth = 0.0
        self._vz = 0.0  # down positive
        self._depth_target: float | None = None
        self._altitude_target: float | None = None

    # -- the horizontal part -----------------------------------------------------------------

    @property
    def powered(self) -> bool:
        return self._horizontal.powered

    @powered.setter
    def powered(self, value: bool) -> None:
        self._horizontal.powered = value

    @property
    def heading_bias_deg(self) -> float:
        """Compass error the horizontal controller steers by (fault injection)."""
        return self._horizontal.heading_bias_deg

    @heading_bias_deg.setter
    def heading_bias_deg(self, value: float) -> None:
        self._horizontal.heading_bias_deg = value

    @property
    def lat(self) -> float:
        return self._horizontal.lat

    @property
    def lon(self) -> float:
        return self._horizontal.lon

    @property
    def north_east_m(self) -> tuple[float, float]:
        """Position in metres north and east of the start point."""
        return self._horizontal.north_east_m

    @property
    def heading_deg(self) -> float:
        return self._horizontal.heading_deg

    @property
    def yaw_rate_rad_s(self) -> float:
        return self._horizontal.yaw_rate_rad_s

    @property
    def speed_m_s(self) -> float:
        return self._horizontal.speed_m_s

    @property
    def target(self) -> tuple[float, float] | None:
        return self._horizontal.target

    @property
    def arrived(self) -> bool:
        """Horizontally within the arrival distance of the target (the depth may still be changing)."""
        return self._horizontal.arrived

    def drive_to(self, lat: float, lon: float, speed_m_s: float | None = None) -> None:
        self._horizontal.drive_to(lat, lon, speed_m_s)

    def hold(self) -> None:
        """Brake to a stop horizontally (the depth controller is left as it is)."""
        self._horizontal.hold()

    def stopping_point(self) -> tuple[float, float]:
        return self._horizontal.stopping_point()

    def distance_to(self, lat: float, lon: float) -> float:
        return self._horizontal.distance_to(lat, lon)

    def bearing_to(self, lat: float, lon: float) -> float:
        return self._horizontal.bearing_to(lat, lon)

    # -- the vertical part -------------------------------------------------------------------

    @property
    def depth_m(self) -> float:
        """Depth of the depth sensor below the surface (>= 0)."""
        return self._depth

    @property
    def alt_m(self) -> float:
        """Height above the surface: minus the depth."""
        return -self._depth

    @property
    def velocity_ned(self) -> tuple[float, float, float]:
        vn, ve, _ = self._horizontal.velocity_ned
        return vn, ve, self._vz

    @property
    def seabed_depth_m(self) -> float:
        """Water depth under the vehicle."""
        return self.seabed.depth_at(*self.north_east_m)

    @property
    def altitude_m(self) -> float:
        """Height of the vehicle's depth sensor above the seabed (what a downward rangefinder measures)."""
        return self.seabed_depth_m - self._depth

    @property
    def depth_target_m(self) -> float | None:
        """The depth being held or gone to (for an altitude target, the depth that gives it here)."""
        if self._altitude_target is not None:
            return self._clamp_depth(self.seabed_depth_m - self._altitude_target)
        return self._depth_target

    @property
    def holding_altitude(self) -> bool:
        """The depth controller follows the seabed."""
        return self._altitude_target is not None

    def hold_depth_at(self, depth_m: float) -> None:
        """Go to and hold a depth (clamped between the surface and the seabed)."""
        self._depth_target, self._altitude_target = self._clamp_depth(depth_m), None

    def hold_depth(self) -> None:
        """Hold the depth where the vehicle can stop its vertical motion."""
        ahead = self._vz * abs(self._vz) / (2.0 * self.limits.vertical_accel_m_s2)
        self.hold_depth_at(self._depth + ahead)

    def hold_altitude_at(self, altitude_m: float) -> None:
        """Follow the seabed at this height above it."""
        self._depth_target, self._altitude_target = None, max(0.0, altitude_m)

    def release_depth(self) -> None:
        """No depth control: the vehicle's buoyancy takes it up."""
        self._depth_target = self._altitude_target = None

    def _clamp_depth(self, depth_m: float) -> float:
        return min(max(depth_m, 0.0), max(0.0, self.seabed_depth_m - self.limits.hull_m))

    # -- physics -----------------------------------------------------------------------------

    def step(self, dt: float) -> None:
        """Advance ``dt`` seconds, in sub-steps of at most ``SUBSTEP_S``."""
        while dt > 1e-9:
            h = self.SUBSTEP_S if dt > self.SUBSTEP_S else dt
            self._horizontal.step(h)
            self._vertical_substep(h)
            dt -= h

    def _vertical_substep(self, h: float) -> None:
        limits = self.limits
        target = self.depth_target_m if self.powered else None
        if target is None:
            want = -limits.buoyancy_m_s
        else:
            error = target - self._depth
            brake = math.sqrt(2.0 * 0.8 * limits.vertical_accel_m_s2 * abs(error))
            want = math.copysign(min(brake, self.DEPTH_GAIN * abs(error), limits.descend_m_s if error > 0 else limits.climb_m_s), error)
        step = limits.vertical_accel_m_s2 * h
        self._vz += clamp(want - self._vz, step)
        self._depth += self._vz * h
        floor = self.seabed_depth_m - limits.hull_m
        floor = floor if floor > 0.0 else 0.0
        if self._depth <= 0.0 or self._depth >= floor:
            self._depth = min(max(self._depth, 0.0), floor)
            self._vz = 0.0
