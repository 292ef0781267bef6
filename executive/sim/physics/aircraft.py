"""Kinematics of the simulated QuadPlane: a fixed-wing aircraft with lift motors. No IO, no MAVLink.

The aircraft flies in one of two regimes, chosen by its autopilot: as a multicopter (hovers,
moves slowly, climbs and lands vertically) or as an aeroplane (flies at cruise airspeed, turns
with a limited bank, cannot stop, so it circles where it is told to stay). Switching regimes is
instant here; the autopilot decides when the aircraft is fast enough for wing-borne flight (the
transition) and the aircraft keeps its height meanwhile, as the lift motors do. Altitudes are
metres above the start point; there is no wind.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from executive.sim.physics.vehicle import LocalFrame, wrap_pi
from executive.world.bounds import clamp

GRAVITY_M_S2 = 9.80665


@dataclass(frozen=True)
class AircraftLimits:
    """How a QuadPlane flies (ArduPlane defaults where one exists)."""

    mc_speed_m_s: float = 5.0  # Q_WP_SPEED
    mc_accel_m_s2: float = 2.0
    climb_m_s: float = 2.5  # Q_WP_SPEED_UP
    descend_m_s: float = 1.5  # Q_WP_SPEED_DN
    vertical_accel_m_s2: float = 2.5
    land_final_alt_m: float = 6.0  # Q_LAND_FINAL_ALT: below it, the last part of a landing is slower
    land_final_m_s: float = 0.5  # Q_LAND_FINAL_SPD
    trans_decel_m_s2: float = 2.0  # Q_TRANS_DECEL: braking from wing-borne speed on the lift motors
    cruise_m_s: float = 18.0
    fw_accel_m_s2: float = 2.0
    fw_climb_m_s: float = 5.0  # TECS_CLMB_MAX
    fw_sink_m_s: float = 5.0  # TECS_SINK_MAX
    bank_deg: float = 45.0  # ROLL_LIMIT_DEG
    fall_m_s: float = 15.0  # unpowered in the air: it drops
    arrive_m: float = 1.0


QUADPLANE_LIMITS = AircraftLimits()


class Regime(Enum):
    """How the aircraft holds itself up."""

    MULTICOPTER = "mc"
    FIXED_WING = "fw"


class QuadPlaneModel(LocalFrame):
    """Position, velocity and heading of a QuadPlane, with a controller for each regime.

    Multicopter orders: :meth:`hover_at` (go to a point and altitude and hover there),
    :meth:`hover` (stop where it can and hover), :meth:`land` (descend vertically to the ground).
    Fixed-wing orders: :meth:`orbit` (fly to a circle and around it), :meth:`cruise` (fly straight
    on at an altitude). On the ground, fixed-wing orders do nothing (no runway take-off) and the
    aircraft leaves the ground only by a multicopter climb. Unpowered, it stops on the ground and
    falls in the air.
    """

    SUBSTEP_S = 0.05
    POSITION_GAIN = 1.0  # multicopter speed (m/s) per metre left, for the last metres
    HEIGHT_GAIN = 1.0  # climb rate (m/s) per metre of height error, for the last metres
    FW_HEIGHT_GAIN = 0.5
    HEADING_GAIN = 2.0
    ORBIT_GAIN = 2.0  # how hard the orbit guidance pulls back toward the circle, per radius off it

    def __init__(self, lat: float, lon: float, heading_deg: float = 0.0, limits: AircraftLimits = QUADPLANE_LIMITS) -> None:
        self.limits = limits
        self.powered = False
        self.regime = Regime.MULTICOPTER
        self._init_frame(lat, lon)
        self._n = self._e = self._h = 0.0
        self._vn = self._ve = self._vd = 0.0
        self._yaw = wrap_pi(math.radians(heading_deg))
        self._yaw_rate = 0.0
        self._target: tuple[float, float] = (0.0, 0.0)  # north, east (m): hover point or orbit centre
        self._target_h = 0.0
        self._landing = False
        self._radius = 0.0  # > 0: orbit the target; 0: fly straight on (fixed wing)
        self._ccw = False

    # -- state -------------------------------------------------------------------------------

    @property
    def alt_m(self) -> float:
        """Height above the start point (>= 0)."""
        return self._h

    @property
    def heading_deg(self) -> float:
        return math.degrees(self._yaw) % 360.0

    @property
    def yaw_rate_rad_s(self) -> float:
        return self._yaw_rate

    @property
    def velocity_ned(self) -> tuple[float, float, float]:
        return self._vn, self._ve, self._vd

    def throttle(self) -> float:
        """The throttle it flies on, 0..1: half on the lift motors, more with speed on the wing."""
        if self.regime is Regime.MULTICOPTER:
            return 0.5
        return min(1.0, 0.3 + 0.5 * self.speed_m_s / self.limits.cruise_m_s)

    @property
    def speed_m_s(self) -> float:
        """Airspeed (no wind: the horizontal ground speed)."""
        return math.hypot(self._vn, self._ve)

    @property
    def on_ground(self) -> bool:
        return self._h <= 0.0

    @property
    def landing(self) -> bool:
        """Descending to land (:meth:`land`)."""
        return self._landing

    @property
    def target(self) -> tuple[float, float] | None:
        """The hover point or the orbit centre (lat, lon)."""
        return self._latlon(*self._target)

    @property
    def target_alt_m(self) -> float:
        """The altitude being flown to (0 when landing)."""
        return 0.0 if self._landing else self._target_h

    @property
    def arrived(self) -> bool:
        """At the hover point (multicopter), or on the circle (fixed wing orbit)."""
        distance = math.hypot(self._target[0] - self._n, self._target[1] - self._e)
        if self.regime is Regime.MULTICOPTER:
            return distance <= self.limits.arrive_m and abs(self.target_alt_m - self._h) <= self.limits.arrive_m
        return self._radius > 0 and abs(distance - self._radius) <= 0.1 * self._radius

    def distance_to(self, lat: float, lon: float) -> float:
        n, e = self._ne(lat, lon)
        return math.hypot(n - self._n, e - self._e)

    def bearing_to(self, lat: float, lon: float) -> float:
        n, e = self._ne(lat, lon)
        return math.degrees(math.atan2(e - self._e, n - self._n)) % 360.0

    def stopping_point(self) -> tuple[float, float]:
        """Where braking on the lift motors would stop the aircraft."""
        speed = self.speed_m_s
        if speed < 1e-6:
            return self.lat, self.lon
        decel = self.limits.trans_decel_m_s2 if speed > self.limits.mc_speed_m_s else self.limits.mc_accel_m_s2
        ahead = speed / (2.0 * decel)
        return self._latlon(self._n + self._vn * ahead, self._e + self._ve * ahead)

    # -- orders ------------------------------------------------------------------------------

    def hover_at(self, lat: float, lon: float, alt_m: float) -> None:
        """Multicopter: go to a point and altitude and hover there."""
        self.regime, self._landing = Regime.MULTICOPTER, False
        self._target, self._target_h = self._ne(lat, lon), max(0.0, alt_m)

    def hover(self) -> None:
        """Multicopter: stop where it can and hover at the current altitude."""
        self.hover_at(*self.stopping_point(), self._h)

    def land(self) -> None:
        """Multicopter: stop where it can and descend vertically to the ground."""
        self.hover()
        self._landing = True

    def orbit(self, lat: float, lon: float, alt_m: float, radius_m: float, ccw: bool = False) -> None:
        """Fixed wing: fly to the circle of ``radius_m`` around a point, at an altitude, and around it."""
        self.regime, self._landing = Regime.FIXED_WING, False
        self._target, self._target_h = self._ne(lat, lon), max(0.0, alt_m)
        self._radius, self._ccw = max(1.0, radius_m), ccw

    def cruise(self, alt_m: float) -> None:
        """Fixed wing: fly straight on at an altitude."""
        self.regime, self._landing = Regime.FIXED_WING, False
        self._target, self._target_h, self._radius = (self._n, self._e), max(0.0, alt_m), 0.0

    def set_target_alt(self, alt_m: float) -> None:
        """Change the altitude of the current order."""
        self._target_h = max(0.0, alt_m)

    # VehicleModel's orders, in multicopter terms
    def drive_to(self, lat: float, lon: float, speed_m_s: float | None = None) -> None:
        self.hover_at(lat, lon, self._target_h if self.regime is Regime.MULTICOPTER else self._h)

    def hold(self) -> None:
        self.hover()

    # -- physics -----------------------------------------------------------------------------

    def step(self, dt: float) -> None:
        """Advance ``dt`` seconds, in sub-steps of at most ``SUBSTEP_S``."""
        while dt > 1e-9:
            h = self.SUBSTEP_S if dt > self.SUBSTEP_S else dt  # min(dt, SUBSTEP_S), as the other mins of every step: see clamp
            self._substep(h)
            dt -= h

    def _substep(self, h: float) -> None:
        if not self.powered:
            self._unpowered(h)
        elif self.regime is Regime.MULTICOPTER:
            self._multicopter(h)
        elif self.on_ground:
            self._vn = self._ve = self._vd = self._yaw_rate = 0.0
        else:
            self._fixed_wing(h)
        self._n += self._vn * h
        self._e += self._ve * h
        self._h -= self._vd * h
        if self._h <= 0.0:
            self._h = 0.0
            self._vn = self._ve = self._vd = 0.0  # on the ground it stands still

    def _unpowered(self, h: float) -> None:
        self._yaw_rate = 0.0
        if self.on_ground:
            return
        slow = max(0.0, 1.0 - self.limits.mc_accel_m_s2 * h / max(self.speed_m_s, 1e-6))
        self._vn, self._ve = self._vn * slow, self._ve * slow
        self._vd = min(self.limits.fall_m_s, self._vd + GRAVITY_M_S2 * h)

    def _multicopter(self, h: float) -> None:
        limits = self.limits
        self._yaw_rate = 0.0  # no pilot yaw, no weathervaning: the heading stays
        dn, de = self._target[0] - self._n, self._target[1] - self._e
        distance = math.hypot(dn, de)
        speed = self.speed_m_s
        decel = limits.trans_decel_m_s2 if speed > limits.mc_speed_m_s + 0.5 else limits.mc_accel_m_s2
        brake, approach = math.sqrt(2.0 * 0.8 * decel * distance), self.POSITION_GAIN * distance
        want = limits.mc_speed_m_s  # min(the speed, brake, approach)
        want = brake if brake < want else want
        want = approach if approach < want else want
        want_n, want_e = (dn / distance * want, de / distance * want) if distance > 1e-6 else (0.0, 0.0)
        change_n, change_e = want_n - self._vn, want_e - self._ve
        change = math.hypot(change_n, change_e)
        if change > decel * h:
            change_n, change_e = change_n * decel * h / change, change_e * decel * h / change
        self._vn += change_n
        self._ve += change_e
        if self._landing:
            want_down = limits.land_final_m_s if self._h <= limits.land_final_alt_m else limits.descend_m_s
        else:
            error = self._target_h - self._h  # positive: climb
            brake = math.sqrt(2.0 * 0.8 * limits.vertical_accel_m_s2 * abs(error))
            approach, most = self.HEIGHT_GAIN * abs(error), limits.climb_m_s if error > 0 else limits.descend_m_s
            rate = approach if approach < brake else brake  # min(brake, approach, the most)
            rate = most if most < rate else rate
            want_down = -math.copysign(rate, error)
        self._vd += clamp(want_down - self._vd, limits.vertical_accel_m_s2 * h)

    def _fixed_wing(self, h: float) -> None:
        limits = self.limits
        speed = self.speed_m_s
        speed += clamp(limits.cruise_m_s - speed, limits.fw_accel_m_s2 * h)
        course = self._yaw if self._radius <= 0 else self._orbit_course()
        max_rate = GRAVITY_M_S2 * math.tan(math.radians(limits.bank_deg)) / (5.0 if speed < 5.0 else speed)
        self._yaw_rate = clamp(self.HEADING_GAIN * wrap_pi(course - self._yaw), max_rate)
        self._yaw = wrap_pi(self._yaw + self._yaw_rate * h)
        self._vn, self._ve = speed * math.cos(self._yaw), speed * math.sin(self._yaw)
        error = self._target_h - self._h
        want_down = -clamp(self.FW_HEIGHT_GAIN * error, limits.fw_climb_m_s if error > 0 else limits.fw_sink_m_s)
        self._vd += clamp(want_down - self._vd, limits.vertical_accel_m_s2 * h)

    def _orbit_course(self) -> float:
        """The course that takes the aircraft onto its circle and around it."""
        out_n, out_e = self._n - self._target[0], self._e - self._target[1]
        distance = math.hypot(out_n, out_e)
        if distance < 1e-3:
            return self._yaw
        un, ue = out_n / distance, out_e / distance
        along_n, along_e = (ue, -un) if self._ccw else (-ue, un)
        pull = clamp(self.ORBIT_GAIN * (self._radius - distance) / self._radius, 3.0)
        return math.atan2(along_e + pull * ue, along_n + pull * un)
