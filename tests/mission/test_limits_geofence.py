"""The battery limits and the geofence section: defaults, ranges, a usable polygon, a route inside the fence."""

from __future__ import annotations

import pytest

from executive.mission.errors import MissionError
from executive.mission.loader import load_mission_text
from executive.mission.model import Mission
from executive.world.geo import destination
from executive.world.geofence import Geofence

HOME = (47.397742, 8.545594)
HEAD = f"version: 1\nname: m\nvehicle: rover\nhome: {{lat: {HOME[0]}, lon: {HOME[1]}}}\n"  # the body starts on line 5
WP = "waypoints:\n  - {lat: 47.3978, lon: 8.5456}\n"  # 6.5 m from home


def at(north_m: float, east_m: float) -> str:
    lat, lon = destination(*destination(*HOME, 0.0, north_m), 90.0, east_m)
    return f"{{lat: {lat:.7f}, lon: {lon:.7f}}}"


# a 200 m square centred on home
SQUARE = "[" + ", ".join(at(n, e) for n, e in [(-100, -100), (100, -100), (100, 100), (-100, 100)]) + "]"


def load(text: str) -> Mission:
    return load_mission_text(text, "m.yaml")


def errors_of(text: str) -> list[str]:
    try:
        load(text)
    except MissionError as exc:
        return [str(e) for e in exc.errors]
    return []


def test_battery_limits_default_to_20_percent_and_no_voltage() -> None:
    limits = load(HEAD + WP).limits
    assert (limits.battery_min_pct, limits.battery_min_v) == (20.0, None)


def test_a_sub_takes_the_auv_seeds_limits_by_default() -> None:
    """Issue 13: a sub's default speed limit was 5 m/s; the AUV seed says 0.1-1 m/s, depth 0-100 m, altitude 2-100 m, waypoints within 1 km."""
    sub = load(HEAD.replace("vehicle: rover", "vehicle: sub") + WP).limits
    assert (sub.speed_m_s.min, sub.speed_m_s.max, sub.max_goal_distance_m) == (0.1, 1.0, 1000.0)
    assert (sub.depth_m.min, sub.depth_m.max, sub.altitude_m.min, sub.altitude_m.max) == (0.0, 100.0, 2.0, 100.0)
    rover = load(HEAD + WP).limits
    assert (rover.speed_m_s.max, rover.max_goal_distance_m) == (5.0, 5000.0)
    fast = HEAD.replace("vehicle: rover", "vehicle: sub") + "waypoints:\n  - {lat: 47.3978, lon: 8.5456, speed_m_s: 1.5}\n"
    assert errors_of(fast) == ["m.yaml:6:44: waypoints[0].speed_m_s: 1.5 m/s is outside limits.speed_m_s [0.1, 1.0] (waypoint 1)"]
    own = load(HEAD.replace("vehicle: rover", "vehicle: sub") + "limits: {speed_m_s: {min: 0.2, max: 1.5}}\n" + WP).limits
    assert (own.speed_m_s.max, own.max_goal_distance_m) == (1.5, 1000.0)  # a field the file sets wins; the others keep the sub's


def test_battery_limits_can_be_switched_off_or_set() -> None:
    limits = load(HEAD + "limits: {battery_min_pct: null, battery_min_v: 10.5}\n" + WP).limits
    assert (limits.battery_min_pct, limits.battery_min_v) == (None, 10.5)


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (
            "limits: {battery_min_pct: 120, battery_min_v: 0}\n",
            [
                "m.yaml:5:27: limits.battery_min_pct: 120: Input should be less than or equal to 100",
                "m.yaml:5:47: limits.battery_min_v: 0: Input should be greater than 0",
            ],
        ),
        ("limits: {battery_min_pct: -1}\n", ["m.yaml:5:27: limits.battery_min_pct: -1: Input should be greater than or equal to 0"]),
        ("limits: {battery_min_pct: '20'}\n", ["m.yaml:5:27: limits.battery_min_pct: expected a number, got string '20'"]),
    ],
)
def test_battery_limits_are_validated(body: str, expected: list[str]) -> None:
    assert errors_of(HEAD + body + WP) == expected


def test_no_geofence_by_default() -> None:
    assert load(HEAD + WP).geofence is None


def test_a_geofence_becomes_the_guards_fence() -> None:
    mission = load(HEAD + f"geofence: {{polygon: {SQUARE}, max_distance_from_home_m: 120}}\n" + WP)
    assert mission.geofence is not None
    fence = mission.geofence.fence()
    assert isinstance(fence, Geofence)
    assert (len(fence.polygon), fence.max_distance_m) == (4, 120.0)
    assert fence.contains(*HOME, HOME)


def test_a_closed_ring_is_accepted() -> None:
    closed = SQUARE[:-1] + ", " + at(-100, -100) + "]"
    mission = load(HEAD + f"geofence: {{polygon: {closed}}}\n" + WP)
    assert mission.geofence is not None
    assert len(mission.geofence.fence().polygon) == 4


def test_a_distance_alone_is_a_fence_without_a_mission_home() -> None:
    mission = load("version: 1\nname: m\nvehicle: rover\ngeofence: {max_distance_from_home_m: 1}\nwaypoints:\n  - {lat: 10.0, lon: 10.0}\n")
    assert mission.geofence is not None  # the autopilot's home is only known at run time
    assert mission.geofence.fence() == Geofence(max_distance_m=1.0)


BOW_TIE = """geofence:
  polygon:
    - {lat: 47.39, lon: 8.54}
    - {lat: 47.40, lon: 8.55}
    - {lat: 47.40, lon: 8.54}
    - {lat: 47.39, lon: 8.55}
"""


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("geofence: {}\n" + WP, ["m.yaml:5:11: geofence: a geofence needs a polygon, max_distance_from_home_m, inclusion or keep_out zones"]),
        (
            "geofence: {polygon: null, max_distance_from_home_m: null}\n" + WP,
            ["m.yaml:5:11: geofence: a geofence needs a polygon, max_distance_from_home_m, inclusion or keep_out zones"],
        ),
        (
            "geofence: {polygon: [{lat: 47.39, lon: 8.54}, {lat: 47.40, lon: 8.54}]}\n" + WP,
            ["m.yaml:5:21: geofence.polygon: List should have at least 3 items after validation, not 2"],
        ),
        (
            "geofence: {polygon: [{lat: 47.39, lon: 8.54}, {lat: 47.40, lon: 8.54}, {lat: 91, lon: 8.55}]}\n" + WP,
            ["m.yaml:5:78: geofence.polygon[2].lat: 91: Input should be less than or equal to 90"],
        ),
        (
            "geofence: {polygon: [{lat: 47.39, lon: 8.54}, {lat: 47.40, lon: 8.54}, {lat: 47.40, lon: 8.54}]}\n" + WP,
            ["m.yaml:5:72: geofence.polygon[2]: vertex 2 repeats vertex 1"],
        ),
        (BOW_TIE + WP, ["m.yaml:9:7: geofence.polygon[2]: edge 2-3 touches or crosses edge 0-1: the polygon intersects itself"]),
        ("geofence: {max_distance_from_home_m: 0}\n" + WP, ["m.yaml:5:38: geofence.max_distance_from_home_m: 0: Input should be greater than 0"]),
        (
            "geofence: {max_distance_from_home_m: 10, radius: 5}\n" + WP,
            ["m.yaml:5:42: geofence.radius: unknown field (allowed: polygon, max_distance_from_home_m, inclusion, keep_out, autopilot)"],
        ),
    ],
)
def test_geofence_is_validated(body: str, expected: list[str]) -> None:
    assert errors_of(HEAD + body) == expected


@pytest.mark.parametrize(
    ("fence", "route", "expected"),
    [
        (f"{{polygon: {SQUARE}}}", [(50, 50), (-90, 90)], []),
        (
            f"{{polygon: {SQUARE}}}",
            [(50, 50), (50, 150), (-130, 0)],
            [
                "m.yaml:8:5: waypoints[1]: outside the geofence: 50 m outside the fence polygon (waypoint 2)",
                "m.yaml:9:5: waypoints[2]: outside the geofence: 30 m outside the fence polygon (waypoint 3)",
            ],
        ),
        (
            "{max_distance_from_home_m: 100}",
            [(50, 50), (0, 101)],
            ["m.yaml:8:5: waypoints[1]: outside the geofence: 101 m from home, over the fence's 100 m (waypoint 2)"],
        ),
        (
            f"{{polygon: {SQUARE}, max_distance_from_home_m: 100}}",
            [(90, 90)],
            ["m.yaml:7:5: waypoints[0]: outside the geofence: 127 m from home, over the fence's 100 m (waypoint 1)"],
        ),
    ],
)
def test_every_waypoint_must_be_inside_the_fence(fence: str, route: list[tuple[float, float]], expected: list[str]) -> None:
    waypoints = "waypoints:\n" + "".join(f"  - {at(n, e)}\n" for n, e in route)
    assert errors_of(HEAD + f"geofence: {fence}\n" + waypoints) == expected


def test_home_must_be_inside_the_fence() -> None:
    away = "[" + ", ".join(at(n, e) for n, e in [(100, -100), (300, -100), (300, 100), (100, 100)]) + "]"
    text = HEAD + f"geofence: {{polygon: {away}}}\nwaypoints:\n  - {at(200, 0)}\n"
    assert errors_of(text) == ["m.yaml:4:7: home: outside the geofence: 100 m outside the fence polygon"]
