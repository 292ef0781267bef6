"""Guards of where the vehicle is and how it moves: its position known, the target and route within reach, its speed,
depth and height above the seabed within limits, the rangefinder reaching the seabed, inside the geofence.

The debounce and the rules for unknown and stale readings are the guards' (:mod:`executive.behaviours.guards`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from executive.behaviours.guards import Guard
from executive.mission.model import Mission, Range, Waypoint, waypoint_label
from executive.world.geo import distance
from executive.world.geofence import Geofence
from executive.world.state import GlobalPosition, HomePosition, Rangefinder

#: What a guard of the vehicle's position does without one, or with an old one (its ``unknown_or_stale``).
POSITION_RULE = (
    "no position yet: fails; an old position: judged as it is: GLOBAL_POSITION_INT carries the EKF's estimate, and EKF ok? "
    "fails when the EKF's reports stop or lose the position"
)


class _HasLatLon(Protocol):
    lat: float
    lon: float


class TargetWithin(Guard):
    """The current leg's target (/mission/target) is within ``max_distance_m`` of the vehicle (go-to refusal, 5 km).

    Debounce: none (0 s, 0 s): a refusal of the target, not a reading to filter.
    """

    reads = ("/mission/target", "/vehicle/position")
    from_mission = {"max_distance_m": "limits.max_goal_distance_m"}
    unknown_or_stale = POSITION_RULE

    def __init__(self, max_distance_m: float, name: str | None = None) -> None:
        super().__init__(name or f"Target within {max_distance_m:g} m?")
        self.max_distance_m = max_distance_m

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        target: _HasLatLon | None = self.get("/mission/target")
        if position is None:
            return "no position"
        if target is None:
            return "no target: no leg is active"
        d = distance(position.lat, position.lon, target.lat, target.lon)
        return f"target is {d:.0f} m away, over {self.max_distance_m:g} m" if d > self.max_distance_m else None


class PositionKnown(Guard):
    """The autopilot reports where the vehicle is (/vehicle/position: a GLOBAL_POSITION_INT with a fix).

    Debounce: none (0 s, 0 s): used to wait for the first position.
    """

    reads = ("/vehicle/position",)
    unknown_or_stale = POSITION_RULE

    def __init__(self, name: str = "Position known?") -> None:
        super().__init__(name)

    def awaits(self) -> str | None:
        return "a position (GLOBAL_POSITION_INT)" if self.get("/vehicle/position") is None else None

    def check(self) -> str | None:
        return None if self.get("/vehicle/position") is not None else "no position"


class AllWaypointsWithin(Guard):
    """Every waypoint is within ``max_distance_m`` of the vehicle's live position (the AUV's 1 km rule).

    Debounce: none (0 s, 0 s): judged once, to accept or refuse the mission.

    Each verdict is remembered with the position it was computed at: while every waypoint was
    within ``max_distance_m - moved`` there, the triangle inequality says they still are, and
    the waypoints are not measured again (a long route costs one distance per tick).
    """

    reads = ("/vehicle/position",)
    from_mission = {"waypoints": "waypoints", "max_distance_m": "limits.max_goal_distance_m"}
    unknown_or_stale = POSITION_RULE

    def __init__(self, waypoints: Sequence[_HasLatLon], max_distance_m: float, name: str | None = None) -> None:
        super().__init__(name or f"All waypoints within {max_distance_m:g} m?")
        self.waypoints = tuple(waypoints)
        self.max_distance_m = max_distance_m
        self._measured: tuple[float, float, float] | None = None  # lat, lon, farthest waypoint there

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        if self._measured is not None:
            lat, lon, farthest = self._measured
            if farthest + distance(lat, lon, position.lat, position.lon) <= self.max_distance_m:
                return None
        self._measured = None
        farthest = 0.0
        for i, wp in enumerate(self.waypoints):
            d = distance(position.lat, position.lon, wp.lat, wp.lon)
            if d > self.max_distance_m:
                return f"{waypoint_label(i, getattr(wp, 'name', None))} is {d:.0f} m away, over {self.max_distance_m:g} m"
            farthest = max(farthest, d)
        self._measured = (position.lat, position.lon, farthest)
        return None


class RangefinderReaches(Guard):
    """The downward rangefinder can measure every altitude leg's height above the seabed (a mission's pre-flight check).

    Its range is what the autopilot reports in DISTANCE_SENSOR (min/max_distance: ArduPilot's
    RNGFND1_MIN and RNGFND1_MAX). An altitude leg is flown from the measured height
    (:mod:`executive.world.seabed`), so each ``altitude_m`` must lie ``margin_m`` inside that range;
    otherwise it fails naming the waypoint, the parameter and the value it needs. No downward
    rangefinder reported fails too. A route without altitude legs passes.

    Debounce: none (0 s, 0 s): judged once, to accept or refuse the mission.
    """

    reads = ("/vehicle/rangefinder",)
    from_mission = {"waypoints": "waypoints"}
    unknown_or_stale = (
        "no downward DISTANCE_SENSOR yet: fails (with an altitude leg); any age is fine: the range it checks is the sensor's "
        "configuration (RNGFND1_MIN/MAX), which does not age"
    )
    param_docs = {"margin_m": "how far inside the rangefinder's range each altitude leg's height must be"}

    def __init__(self, waypoints: Sequence[Waypoint], margin_m: float = 1.0, name: str = "Rangefinder reaches the altitude legs?") -> None:
        super().__init__(name)
        self.legs = [(i, wp) for i, wp in enumerate(waypoints) if wp.control_mode == "altitude" and wp.altitude_m is not None]
        self.margin_m = margin_m

    def check(self) -> str | None:
        if not self.legs:
            self.note = "no altitude leg"
            return None
        reading: Rangefinder | None = self.get("/vehicle/rangefinder")
        if reading is None:
            return "no downward rangefinder reported (DISTANCE_SENSOR, PITCH_270): an altitude leg needs one (RNGFND1_TYPE, RNGFND1_ORIENT 25)"
        for i, wp in self.legs:
            assert wp.altitude_m is not None
            named = f"{waypoint_label(i, wp.name)} keeps {wp.altitude_m:g} m above the seabed"
            if wp.altitude_m + self.margin_m > reading.max_m:
                return f"{named}: the rangefinder reads to {reading.max_m:g} m: set RNGFND1_MAX to at least {wp.altitude_m + self.margin_m:g} m"
            if wp.altitude_m - self.margin_m < reading.min_m:
                return f"{named}: the rangefinder reads from {reading.min_m:g} m: set RNGFND1_MIN to at most {wp.altitude_m - self.margin_m:g} m"
        return None


def _speed(position: GlobalPosition | None, ground_speed: float | None) -> float | None:
    return position.ground_speed_m_s if position is not None else ground_speed


class SpeedWithin(Guard):
    """The vehicle is not faster than the mission allows.

    Debounce: fails after 2 s over the limit (a current, a wave or a settling speed controller
    overshoots briefly); passes after 2 s within it.

    Rule: FAILURE when the ground speed exceeds ``limit.max`` by more than
    ``max(tolerance_m_s, tolerance_fraction * limit.max)`` (an autopilot overshoots a little while
    settling on a speed). ``limit.min`` is never enforced: a vehicle is slower while accelerating,
    turning, holding or at a waypoint. The speed is the EKF's (/vehicle/position, horizontal),
    else VFR_HUD's (/vehicle/ground_speed_m_s); neither reported fails.
    """

    reads = ("/vehicle/position", "/vehicle/ground_speed_m_s")
    unknown_or_stale = (
        "no speed yet (no GLOBAL_POSITION_INT, no VFR_HUD): fails; an old one: judged as it is (the EKF's estimate: EKF ok? fails "
        "when its reports stop or lose the position)"
    )
    hold_after_s = 2.0
    resume_after_s = 2.0
    from_mission = {"limit": "limits.speed_m_s"}
    param_units = {"limit": "m/s"}
    param_docs = {
        "limit": "allowed speeds {min, max}: only max is enforced",
        "tolerance_m_s": "overshoot allowed over max, at least",
        "tolerance_fraction": "overshoot allowed over max, as a fraction of it, at least",
    }

    def __init__(self, limit: Range, tolerance_m_s: float = 0.3, tolerance_fraction: float = 0.1, name: str | None = None) -> None:
        super().__init__(name or f"Speed within {limit.max:g} m/s?")
        self.limit = limit
        self.allowed_m_s = limit.max + max(tolerance_m_s, tolerance_fraction * limit.max)

    def check(self) -> str | None:
        speed = _speed(self.get("/vehicle/position"), self.get("/vehicle/ground_speed_m_s"))
        if speed is None:
            return "speed not reported yet (no GLOBAL_POSITION_INT, no VFR_HUD)"
        if speed > self.allowed_m_s:
            return f"speed {speed:.1f} m/s over the limit {self.limit.max:g} m/s"
        return None


def _outside(value: float, limit: Range, tolerance: float) -> bool:
    return not limit.min - tolerance <= value <= limit.max + tolerance


class DepthWithin(Guard):
    """A sub's depth (-/vehicle/position.alt_rel_m) is in ``limit``, give or take ``tolerance_m`` (waves, sensor noise).

    Debounce: fails after 1 s outside (a wave, a pressure spike); passes after 2 s inside.
    """

    hold_after_s = 1.0
    resume_after_s = 2.0
    unknown_or_stale = POSITION_RULE

    reads = ("/vehicle/position",)
    from_mission = {"limit": "limits.depth_m"}
    param_units = {"limit": "m"}

    def __init__(self, limit: Range, tolerance_m: float = 0.5, name: str | None = None) -> None:
        super().__init__(name or f"Depth within [{limit.min:g}, {limit.max:g}] m?")
        self.limit = limit
        self.tolerance_m = tolerance_m

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        depth = -position.alt_rel_m
        if _outside(depth, self.limit, self.tolerance_m):
            return f"depth {depth:.1f} m outside [{self.limit.min:g}, {self.limit.max:g}] m"
        return None


class AltitudeWithin(Guard):
    """A sub's height above the seabed (/vehicle/altitude_above_bottom_m) is in ``limit``, give or take ``tolerance_m``.

    Debounce: fails after 2 s without a good reading or outside (an echo sounder drops single
    pings over weed, fish or a steep slope); passes after 2 s of good readings inside.

    No valid rangefinder reading (none yet, too close, invalid) fails: the guard cannot tell the
    seabed is far enough. A seabed beyond the rangefinder's maximum (/vehicle/rangefinder too_far)
    is at least that far: it passes with a note when that maximum is within the limit (the
    sub dives to its altitude from there), and fails when the maximum is over the limit's top.
    ``altitude_legs_only``: judged only while the current leg (/mission/target) has control_mode
    ``altitude``; on other legs it passes with a note. A reading older than ``stale_after_s`` while
    the autopilot is heard fails too: the height it gave is no longer known.
    """

    reads = (
        "/vehicle/altitude_above_bottom_m",
        "/vehicle/rangefinder",
        "/vehicle/altitude_last_update",
        "/mission/target",
        "/link/last_heartbeat",
        "/link/up_since",
    )
    hold_after_s = 2.0
    resume_after_s = 2.0
    #: DISTANCE_SENSOR is asked at 5 Hz for a sub (ten missed); ArduSub streams it at 3 Hz by default (SRn_EXTRA3).
    stale_after_s = 2.0
    unknown_or_stale = (
        "no valid rangefinder reading yet: fails (the seabed beyond the sonar's range is a reading: at least that far); one older "
        "than 2 s while the autopilot is heard: fails (DISTANCE_SENSOR asked at 5 Hz)"
    )
    from_mission = {"limit": "limits.altitude_m"}
    param_units = {"limit": "m"}
    param_docs = {"altitude_legs_only": "judged only on legs with control_mode altitude (others pass with a note)"}

    def __init__(self, limit: Range, tolerance_m: float = 0.5, name: str | None = None, altitude_legs_only: bool = False) -> None:
        default = f"Altitude within [{limit.min:g}, {limit.max:g}] m{' on altitude legs' if altitude_legs_only else ''}?"
        super().__init__(name or default)
        self.limit = limit
        self.tolerance_m = tolerance_m
        self.altitude_legs_only = altitude_legs_only

    def check(self) -> str | None:
        if self.altitude_legs_only:
            target: Waypoint | None = self.get("/mission/target")
            if target is None or target.control_mode != "altitude":
                self.note = "not an altitude leg"
                return None
        old = self.stale(self.get("/vehicle/altitude_last_update"), self.stale_after_s, "the rangefinder reading is")
        if old is not None:
            return old
        altitude: float | None = self.get("/vehicle/altitude_above_bottom_m")
        reading: Rangefinder | None = self.get("/vehicle/rangefinder")
        if altitude is None and reading is not None and reading.status == "too_far":
            if reading.max_m > self.limit.max + self.tolerance_m:
                return f"the seabed is beyond the rangefinder's {reading.max_m:g} m: over {self.limit.max:g} m below"
            if reading.max_m >= self.limit.min - self.tolerance_m:
                self.note = f"the seabed is beyond the rangefinder's {reading.max_m:g} m: at least that far"
                return None
        if altitude is None:
            return "no altitude above the seabed (no valid rangefinder reading)"
        if _outside(altitude, self.limit, self.tolerance_m):
            return f"altitude {altitude:.1f} m above the seabed outside [{self.limit.min:g}, {self.limit.max:g}] m"
        return None


class InsideGeofence(Guard):
    """The vehicle is inside ``fence``: its polygon, and its maximum distance from home.

    Debounce: fails at once (the EKF's position is filtered already, and outside is outside);
    passes after 2 s inside.

    Home is the autopilot's (/vehicle/home: where RTL goes and what its own fence measures from),
    else ``mission_home`` until the autopilot reports one; with neither, a fence with a maximum
    distance fails ("no home to measure the distance from").
    """

    reads = ("/vehicle/position", "/vehicle/home")
    resume_after_s = 2.0
    from_mission = {"fence": "geofence", "mission_home": "home"}
    unknown_or_stale = POSITION_RULE + "; no home (the autopilot's or the mission's) with a maximum distance: fails"
    param_docs = {"fence": "the mission's geofence: section", "mission_home": "the mission's home, until the autopilot reports one"}

    def __init__(self, fence: Geofence, mission_home: tuple[float, float] | None = None, name: str = "Inside geofence?") -> None:
        super().__init__(name)
        self.fence = fence
        self.mission_home = mission_home

    def awaits(self) -> str | None:
        return "a position (GLOBAL_POSITION_INT)" if self.get("/vehicle/position") is None else None

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        home: HomePosition | None = self.get("/vehicle/home")
        return self.fence.why_outside(position.lat, position.lon, (home.lat, home.lon) if home else self.mission_home)


def inside_geofence(mission: Mission, name: str = "Inside geofence?") -> InsideGeofence | None:
    """The :class:`InsideGeofence` guard for a mission's ``geofence:`` section; None without one."""
    if mission.geofence is None:
        return None
    home = (mission.home.lat, mission.home.lon) if mission.home else None
    return InsideGeofence(mission.geofence.fence(), home, name)
