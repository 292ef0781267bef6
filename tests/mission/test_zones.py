"""The route against the world: keep-out and inclusion zones checked leg by leg, and legs that can only time out."""

from __future__ import annotations

import time

import pytest

from benchmarks.route_check import grid_mission
from executive.mission.errors import MissionError
from executive.mission.lifecycle import MissionState, Refused
from executive.mission.loader import load_mission_text
from executive.mission.rules import cross_field_errors, waits_for_the_vehicle
from executive.mission.zones import Plane, first_leg_problems, route_errors
from executive.world.geo import destination, distance

HOME = (47.3977, 8.5456)


def at(north_m: float, east_m: float) -> tuple[float, float]:
    """A point north and east of HOME, metres."""
    lat, lon = destination(*HOME, 0.0, north_m)
    return destination(lat, lon, 90.0, east_m)


def vertex(north_m: float, east_m: float) -> str:
    lat, lon = at(north_m, east_m)
    return f"{{lat: {lat:.7f}, lon: {lon:.7f}}}"


def mission_text(waypoints: list[tuple[float, float, str]], fence: str, home: bool = True, limits: str = "") -> str:
    """A boat mission: waypoints as (north m, east m, name), the geofence: block given."""
    lines = ["version: 1", "name: lake", "vehicle: boat"]
    if home:
        lines.append(f"home: {vertex(0, 0)}")
    if limits:
        lines.append(f"limits: {limits}")
    lines.append(f"geofence:\n{fence}")
    lines.append("waypoints:")
    for north, east, name in waypoints:
        lat, lon = at(north, east)
        lines.append(f"  - {{lat: {lat:.7f}, lon: {lon:.7f}, name: {name}}}")
    return "\n".join(lines) + "\n"


def pier(north_m: float = 50.0, half_m: float = 5.0) -> str:
    """A 10 m square keep-out zone named pier, centred north_m north of home."""
    corners = ", ".join(vertex(north_m + n, e) for n, e in ((-half_m, -half_m), (half_m, -half_m), (half_m, half_m), (-half_m, half_m)))
    return f"  keep_out:\n    - {{name: pier, polygon: [{corners}]}}"


def errors_of(text: str) -> list[str]:
    with pytest.raises(MissionError) as info:
        load_mission_text(text, "m.yaml")
    return [f"{e.field}: {e.message}" for e in info.value.errors]


LINES = [(0, -30, "line-1-end"), (0, -30, "line-2-start"), (100, -30, "line-2-end")]


def test_a_leg_crossing_a_keep_out_zone_between_two_waypoints_outside_it_is_refused_naming_both():
    # waypoints all outside the pier; the leg from line-2-start north to line-2-end... misses; the one across does not
    route = [(0, -30, "line-1-end"), (0, 30, "line-2-start"), (100, 0, "line-2-end")]
    crossing = [(20, 0, "line-2-start"), (80, 0, "line-2-end")]
    assert load_mission_text(mission_text(route[:2], pier()), "m.yaml")  # nothing near the pier
    errors = errors_of(mission_text([(0, -30, "a"), *crossing], pier()))
    assert errors == [
        "waypoints[2]: waypoints[1] -> waypoints[2] ('line-2-start' -> 'line-2-end'): crosses keep-out zone 'pier' for 10 m "
        "(waypoint 3, 'line-2-end')"
    ]


def test_the_acceptance_radius_is_the_margin_and_the_distance_is_said():
    passing = [(20, 8, "a"), (80, 8, "b")]  # 3 m east of the pier's edge
    assert load_mission_text(mission_text(passing, pier(), limits="{acceptance_radius_m: 2.0}"), "m.yaml")
    errors = errors_of(mission_text(passing, pier(), limits="{acceptance_radius_m: 4.0}"))
    assert errors == ["waypoints[1]: waypoints[0] -> waypoints[1] ('a' -> 'b'): passes 3.0 m from keep-out zone 'pier', "
                      "within the 4 m margin (limits.acceptance_radius_m) (waypoint 2, 'b')"]  # fmt: skip


def test_a_waypoint_inside_a_keep_out_circle_and_the_leg_from_home_are_refused():
    lat, lon = at(50, 0)
    fence = f"  keep_out:\n    - {{circle: {{lat: {lat:.7f}, lon: {lon:.7f}, radius_m: 10}}}}"
    errors = errors_of(mission_text([(50, 0, "buoy")], fence))
    assert errors == [
        "waypoints[0]: 'buoy' is inside keep-out zone geofence.keep_out[0] (waypoint 1, 'buoy')",
        "waypoints[0]: home -> waypoints[0] ('buoy'): crosses keep-out zone geofence.keep_out[0] for 10 m (waypoint 1, 'buoy')",
    ]


def test_a_leg_leaving_every_inclusion_zone_is_refused_though_its_ends_are_inside():
    # two inclusion circles 100 m apart, each 30 m across: the leg between their centres leaves both for 40 m
    near, far = at(0, 0), at(100, 0)
    fence = f"  inclusion:\n    - {{circle: {{lat: {near[0]:.7f}, lon: {near[1]:.7f}, radius_m: 30}}}}\n" + (
        f"    - {{name: bay, circle: {{lat: {far[0]:.7f}, lon: {far[1]:.7f}, radius_m: 30}}}}"
    )
    errors = errors_of(mission_text([(0, 0, "a"), (100, 0, "b"), (200, 0, "c")], fence))
    assert errors == [
        "waypoints[1]: waypoints[0] -> waypoints[1] ('a' -> 'b'): leaves the inclusion zones for 40 m (waypoint 2, 'b')",
        "waypoints[2]: 'c' is outside every inclusion zone (waypoint 3, 'c')",
        "waypoints[2]: waypoints[1] -> waypoints[2] ('b' -> 'c'): leaves the inclusion zones for 70 m (waypoint 3, 'c')",
    ]


def test_a_zone_is_one_shape_and_its_polygon_must_be_usable():
    corners = f"[{vertex(0, 0)}, {vertex(1, 0)}, {vertex(0, 1)}]"
    both = f"  keep_out:\n    - {{circle: {{lat: 47.3, lon: 8.5, radius_m: 10}}, polygon: {corners}}}"
    assert errors_of(mission_text([(0, 0, "a")], both)) == ["geofence.keep_out[0]: a zone is a polygon or a circle: give exactly one"]
    line = f"  keep_out:\n    - {{polygon: [{vertex(0, 0)}, {vertex(1, 0)}, {vertex(2, 0)}]}}"
    assert errors_of(mission_text([(0, 30, "a")], line)) == ["geofence.keep_out[0].polygon[0]: edge 2-0 folds back onto edge 1-2"]


def test_the_start_door_checks_the_leg_from_where_the_vehicle_is():
    mission = load_mission_text(mission_text([(80, 0, "far")], pier(), home=False), "m.yaml")
    assert first_leg_problems(mission, *at(80, -20)) == []
    assert first_leg_problems(mission, *at(0, 0)) == ["the vehicle -> waypoints[0] ('far'): crosses keep-out zone 'pier' for 10 m"]
    assert first_leg_problems(mission, *at(50, 0))[0] == "the vehicle is inside keep-out zone 'pier'"
    state = MissionState()
    with pytest.raises(Refused, match="the vehicle -> waypoints\\[0\\] \\('far'\\): crosses keep-out zone 'pier'"):
        state.upload(mission, vehicle_at=at(0, 0))
    assert state.mission is None  # nothing loaded, nothing sent


def test_a_route_edit_into_a_zone_is_refused_and_the_route_kept():
    mission = load_mission_text(mission_text([(20, -20, "a"), (80, -20, "b")], pier()), "m.yaml")
    state = MissionState()
    state.upload(mission)
    crossing = mission.waypoints[1].model_copy(update={"lon": at(80, 20)[1], "lat": at(80, 20)[0]})
    detour = mission.waypoints[0].model_copy(update={"lon": at(20, 20)[1], "lat": at(20, 20)[0]})
    with pytest.raises(Refused, match="crosses keep-out zone 'pier'"):
        state.set_route([mission.waypoints[0], crossing, detour], reason="test")
    assert state.mission == mission


def test_legs_that_can_only_time_out_are_refused_with_the_figures():
    text = mission_text([(0, 0, "line-start"), (62, 0, "line-end")], pier(north_m=500), limits="{leg_timeout_s: 20, speed_m_s: {min: 0.1, max: 0.5}}")
    assert errors_of(text) == [
        "waypoints[1]: waypoints[0] -> waypoints[1]: 60 m at most 0.5 m/s takes 120 s, over limits.leg_timeout_s 20: it can only time out "
        "(waypoint 2, 'line-end')"
    ]
    ok = mission_text([(0, 0, "line-start"), (62, 0, "line-end")], pier(north_m=500), limits="{leg_timeout_s: 130, speed_m_s: {min: 0.1, max: 0.5}}")
    assert load_mission_text(ok, "m.yaml")


def test_a_waypoint_speed_is_the_legs_speed():
    text = mission_text([(0, 0, "a"), (2002, 0, "b")], pier(north_m=-500), limits="{leg_timeout_s: 600, max_goal_distance_m: 5000}")
    text = text.replace("name: b}", "name: b, speed_m_s: 2.0}")
    assert errors_of(text) == [
        "waypoints[1]: waypoints[0] -> waypoints[1]: 2000 m at 2 m/s (waypoints[1].speed_m_s) takes 1000 s, over limits.leg_timeout_s 600: "
        "it can only time out (waypoint 2, 'b')"
    ]


def test_without_home_validate_names_the_checks_that_wait_for_the_vehicle():
    mission = load_mission_text(mission_text([(80, 0, "far")], pier(), home=False), "m.yaml")
    assert waits_for_the_vehicle(mission) == [
        "every waypoint within limits.max_goal_distance_m (5000 m) of the vehicle",
        "the first leg against the keep-out and inclusion zones",
    ]
    with_home = load_mission_text(mission_text([(80, 20, "far")], pier()), "m.yaml")
    assert waits_for_the_vehicle(with_home) == []


@pytest.mark.parametrize("origin", [HOME, (70.0, 8.0), (-35.36, 149.16), (0.0, 179.99)])
def test_the_plane_keeps_the_ellipsoids_distances_within_a_millimetre_over_10_km(origin: tuple[float, float]):
    plane = Plane(origin)
    for bearing in range(0, 360, 30):
        far = destination(*origin, bearing, 10_000.0)
        side = destination(*far, bearing + 100.0, 5000.0)  # a leg nowhere near the origin
        (x0, y0), (x1, y1) = plane.xy([far[0], side[0]], [far[1], side[1]])
        assert abs(((x1 - x0) ** 2 + (y1 - y0) ** 2) ** 0.5 - distance(*far, *side)) < 0.001


def test_1000_waypoints_against_100_zones_are_checked_in_a_route_edits_time():
    mission = grid_mission(1000, 100)
    assert route_errors(mission) == []  # the circles sit between the lines
    worst = 0.0
    for _ in range(3):
        began = time.process_time()
        cross_field_errors(mission)
        worst = max(worst, time.process_time() - began)
    # CPU time, generous: the figure itself is benchmarks/route_check.py's (python -m benchmarks --only route)
    assert worst < 0.5


def test_the_run_time_fence_counts_an_inclusion_zone_as_inside():
    """Validate accepts a waypoint in an inclusion zone outside the polygon: the geofence guard must not call it a breach there."""
    square = "[" + ", ".join(vertex(n, e) for n, e in ((-20, -20), (20, -20), (20, 20), (-20, 20))) + "]"
    bay = at(100, 0)
    fence = f"  polygon: {square}\n  inclusion:\n    - {{name: bay, circle: {{lat: {bay[0]:.7f}, lon: {bay[1]:.7f}, radius_m: 30}}}}"
    text = mission_text([(0, 0, "a"), (10, 0, "b")], fence)
    mission = load_mission_text(text, "m.yaml")
    guard = mission.geofence.fence()
    assert guard.why_outside(*at(110, 0), None) is None  # in the bay
    assert guard.why_outside(*at(0, 0), None) is None  # in the polygon
    assert guard.why_outside(*at(60, 0), None) == "10 m outside the fence polygon and every inclusion zone"


def test_a_route_edit_while_running_checks_the_leg_from_where_the_vehicle_is():
    # a (20 m N, 20 m W) -> b (80 m N, 20 m W); the pier 45-55 m N straddles home's meridian; the vehicle is on the leg to b
    mission = load_mission_text(mission_text([(20, -20, "a"), (80, -20, "b")], pier(), limits="{acceptance_radius_m: 1.0}"), "m.yaml")
    state = MissionState()
    state.upload(mission)
    state.start()
    state.continue_from(1, ())
    lat, lon = at(55, 20)
    moved = mission.waypoints[1].model_copy(update={"lat": lat, "lon": lon})  # a -> b' is clear of the pier (passes 7.5 m south)
    with pytest.raises(Refused, match="the vehicle -> waypoints\\[1\\] \\('b'\\): crosses keep-out zone 'pier'"):
        state.set_route([mission.waypoints[0], moved], reason="ctl route", vehicle_at=at(45, -20))
    assert state.mission == mission
    state.set_route([mission.waypoints[0], moved], reason="ctl route", vehicle_at=at(20, -19))  # from by a: clear
