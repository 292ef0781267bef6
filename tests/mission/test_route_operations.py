"""Route operations: their geometry as properties (hypothesis) over routes up to 5 km, and each operation's exact effect and errors."""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from executive.mission.model import Home, Waypoint
from executive.mission.route import (
    Route,
    RouteError,
    add,
    add_after_current,
    add_at_end,
    apply,
    backwards,
    centre,
    clear,
    mirror,
    offset,
    operation_name,
    remove_last,
    scale_rotate,
    set_home,
)
from executive.world import geo

EXACT_M = 1e-6  # "returns the route": within a micrometre
C = (-35.363261, 149.165230)


def near(point: tuple[float, float], bearing_deg: float, distance_m: float, **fields: object) -> Waypoint:
    lat, lon = geo.destination(*point, bearing_deg, distance_m)
    return Waypoint(lat=lat, lon=lon, **fields)  # type: ignore[arg-type]


A, B, D, E = (near(C, 0.0, 100.0 * (i + 1)) for i in range(4))  # 100, 200, 300, 400 m north of C
HOME = Home(lat=C[0], lon=C[1], heading_deg=90.0)


def gap(r1: Route, r2: Route) -> float:
    """The largest distance between corresponding waypoints, metres."""
    assert len(r1) == len(r2)
    return max((geo.distance(a.lat, a.lon, b.lat, b.lon) for a, b in zip(r1.waypoints, r2.waypoints, strict=True)), default=0.0)


# -- strategies ----------------------------------------------------------------------------------

latitudes = st.floats(-80.0, 80.0)  # vehicles, not polar expeditions: near a pole a compass bearing means little
longitudes = st.floats(-180.0, 180.0, exclude_max=True)
bearings = st.floats(0.0, 360.0, exclude_max=True)
speeds_or_none = st.none() | st.floats(0.1, 5.0)


@st.composite
def routes(draw: st.DrawFn, max_radius_m: float = 2500.0, min_size: int = 1) -> Route:
    """1-12 waypoints within ``max_radius_m`` of a random place (so at most 5 km across), heading for any of them, with a home."""
    # each strategy made once per route, not once per point: the same draws (made at every point, they were a tenth of the file's CPU)
    origin, distances = (draw(latitudes), draw(longitudes)), st.floats(0.0, max_radius_m)
    size = draw(st.integers(min_size, 12))
    points = [geo.destination(*origin, draw(bearings), draw(distances)) for _ in range(size)]
    speeds = draw(st.lists(speeds_or_none, min_size=size, max_size=size))
    waypoints = tuple(
        Waypoint(lat=lat, lon=lon, speed_m_s=speed, name=f"wp{i}") for i, ((lat, lon), speed) in enumerate(zip(points, speeds, strict=True))
    )
    return Route(waypoints, draw(st.integers(0, size)), Home(lat=origin[0], lon=origin[1]))


def same_but_positions(before: Route, after: Route) -> None:
    """Only the positions moved: order, other fields, the current waypoint and home are kept."""
    assert (after.current, after.home) == (before.current, before.home)
    for a, b in zip(before.waypoints, after.waypoints, strict=True):
        assert a.model_dump(exclude={"lat", "lon"}) == b.model_dump(exclude={"lat", "lon"})


# -- properties ----------------------------------------------------------------------------------


@given(routes(), bearings)
@settings(deadline=None)
def test_mirroring_twice_about_the_same_axis_is_the_identity(route: Route, bearing: float) -> None:
    about = centre(route)
    once = mirror(route, bearing, about)
    same_but_positions(route, once)
    assert gap(mirror(once, bearing, about), route) <= EXACT_M
    assert gap(mirror(once, bearing + 180.0, about), route) <= EXACT_M  # the same axis


@given(routes(), st.sampled_from([0.0, 180.0]))
@settings(deadline=None)
def test_mirroring_twice_across_the_meridian_of_the_centre_is_the_identity_without_giving_the_centre(route: Route, bearing: float) -> None:
    once = mirror(route, bearing)  # an east-west reflection keeps the latitude/longitude box's centre
    assert centre(once) == pytest.approx(centre(route), abs=1e-9)
    assert gap(mirror(once, bearing), route) <= EXACT_M


@given(routes(), st.floats(-5000.0, 5000.0), bearings)
@settings(deadline=None)
def test_an_offset_then_the_reverse_offset_returns_the_route(route: Route, distance: float, bearing: float) -> None:
    moved = offset(route, distance, bearing)
    same_but_positions(route, moved)
    assert gap(offset(moved, distance, bearing + 180.0), route) <= EXACT_M
    assert gap(offset(moved, -distance, bearing), route) <= EXACT_M


@given(routes(), st.floats(0.0, 5000.0), bearings)
@settings(deadline=None)
def test_an_offset_moves_every_waypoint_the_distance_toward_the_bearing(route: Route, distance: float, bearing: float) -> None:
    moved = offset(route, distance, bearing)
    for a, b in zip(route.waypoints, moved.waypoints, strict=True):
        # along the rhumb line: over 5 km as long as the geodesic to 0.1 %, and leaving at the geodesic's bearing but for the
        # meridians' convergence, about distance * tan(latitude) / (2 * earth radius) radians
        along, toward = geo.distance_bearing(a.lat, a.lon, b.lat, b.lon)
        assert along == pytest.approx(distance, rel=1e-3, abs=EXACT_M)
        if distance > 1.0:
            steepest = max(abs(math.tan(math.radians(a.lat))), abs(math.tan(math.radians(b.lat))))
            convergence = math.degrees(distance * steepest / (2 * 6.36e6))
            assert abs((toward - bearing + 180.0) % 360.0 - 180.0) <= 1.1 * convergence + 1e-6


@given(routes(), st.data())
@settings(deadline=None)
def test_an_offset_of_one_waypoint_moves_that_one_only(route: Route, data: st.DataObject) -> None:
    index = data.draw(st.integers(0, len(route) - 1))
    moved = offset(route, 3.0, 90.0, index)
    assert [wp for i, wp in enumerate(moved.waypoints) if i != index] == [wp for i, wp in enumerate(route.waypoints) if i != index]
    wp, new = route.waypoints[index], moved.waypoints[index]
    assert geo.distance(wp.lat, wp.lon, new.lat, new.lon) == pytest.approx(3.0, rel=1e-6)


@given(routes())
@settings(deadline=None)
def test_scale_1_rotate_0_changes_nothing(route: Route) -> None:
    same = scale_rotate(route, 1.0, 0.0)
    same_but_positions(route, same)
    assert gap(same, route) <= EXACT_M


@given(routes(), st.floats(-720.0, 720.0))
@settings(deadline=None)
def test_rotating_by_an_angle_then_back_is_the_identity(route: Route, angle: float) -> None:
    about = centre(route)
    assert gap(scale_rotate(scale_rotate(route, 1.0, angle, about), 1.0, -angle, about), route) <= EXACT_M


@given(routes(max_radius_m=250.0), st.floats(0.05, 20.0))
@settings(deadline=None)
def test_scaling_by_s_then_1_over_s_is_the_identity(route: Route, scale: float) -> None:
    about = centre(route)
    assert gap(scale_rotate(scale_rotate(route, scale, 0.0, about), 1.0 / scale, 0.0, about), route) <= EXACT_M


@st.composite
def scaled_routes(draw: st.DrawFn) -> tuple[Route, float]:
    """A route and a scale factor such that both it and the scaled route are at most 5 km across."""
    scale = draw(st.floats(0.05, 20.0))
    return draw(routes(max_radius_m=2500.0 / max(scale, 1.0), min_size=2)), scale


@given(scaled_routes(), st.floats(-360.0, 360.0))
@settings(max_examples=80, deadline=None)
def test_distances_between_waypoints_scale_by_s_to_a_tenth_of_a_percent(route_and_scale: tuple[Route, float], angle: float) -> None:
    route, scale = route_and_scale
    scaled = scale_rotate(route, scale, angle)
    for (a, b), (a2, b2) in zip(itertools.combinations(route.waypoints, 2), itertools.combinations(scaled.waypoints, 2), strict=True):
        before, after = geo.distance(a.lat, a.lon, b.lat, b.lon), geo.distance(a2.lat, a2.lon, b2.lat, b2.lon)
        assert after == pytest.approx(scale * before, rel=1e-3, abs=EXACT_M)


@given(routes(), st.floats(-360.0, 360.0))
@settings(deadline=None)
def test_rotation_keeps_the_distance_to_the_centre_and_turns_the_bearing(route: Route, angle: float) -> None:
    about = centre(route)
    turned = scale_rotate(route, 1.0, angle)
    for wp, new in zip(route.waypoints, turned.waypoints, strict=True):
        distance, bearing = geo.distance_bearing(*about, wp.lat, wp.lon)
        distance2, bearing2 = geo.distance_bearing(*about, new.lat, new.lon)
        assert distance2 == pytest.approx(distance, rel=1e-3, abs=EXACT_M)
        if distance > 1.0:
            assert abs((bearing2 - bearing - angle + 180.0) % 360.0 - 180.0) < 1e-6


@given(routes(), bearings)
@settings(deadline=None)
def test_a_mirror_keeps_distances_to_the_centre_and_points_on_the_axis(route: Route, bearing: float) -> None:
    about = centre(route)
    mirrored = mirror(route, bearing)
    for wp, new in zip(route.waypoints, mirrored.waypoints, strict=True):
        assert geo.distance(*about, new.lat, new.lon) == pytest.approx(geo.distance(*about, wp.lat, wp.lon), rel=1e-9, abs=EXACT_M)
    on_axis = Route((near(about, bearing, 1000.0), near(about, bearing + 180.0, 1000.0)))
    assert gap(mirror(on_axis, bearing, about), on_axis) <= EXACT_M


@given(routes())
@settings(deadline=None)
def test_backwards_twice_is_the_identity(route: Route) -> None:
    once = backwards(route)
    assert once.waypoints == route.waypoints[::-1] and once.home == route.home
    assert backwards(once) == route


@given(routes(), st.data())
@settings(deadline=None)
def test_the_vehicle_heads_for_the_same_waypoint_after_an_add(route: Route, data: st.DataObject) -> None:
    assume(not route.finished)
    after = data.draw(st.integers(-1, len(route) - 1))
    new = add(route, Waypoint(lat=0.0, lon=0.0), after)
    heading_for = new.waypoints[new.current]
    assert heading_for is route.waypoints[route.current] or (after + 1 == route.current and heading_for.lat == 0.0)


# -- each operation's exact effect ---------------------------------------------------------------


def test_set_home_moves_the_home_only_and_keeps_its_heading() -> None:
    route = Route((A, B), 1, HOME)
    moved = set_home(route, -35.0, 149.0)
    assert moved == Route((A, B), 1, Home(lat=-35.0, lon=149.0, heading_deg=90.0))
    assert set_home(Route((A,)), 1.0, 2.0).home == Home(lat=1.0, lon=2.0)
    assert route.home == HOME  # the argument is left alone


X = Waypoint(lat=-35.0, lon=149.0)


@pytest.mark.parametrize(
    ("route", "after", "expected"),
    [
        (Route((A, B, D), 1), None, Route((A, B, D, X), 1)),  # at the end
        (Route((A, B, D), 1), 1, Route((A, B, X, D), 1)),  # after the current: driven after it
        (Route((A, B, D), 1), 0, Route((A, X, B, D), 1)),  # in the leg being driven: heading for it now
        (Route((A, B, D), 2), 0, Route((A, X, B, D), 3)),  # behind the vehicle: still heading for D
        (Route((A, B, D), 1), -1, Route((X, A, B, D), 2)),  # first, behind the vehicle
        (Route((A, B), 2), 1, Route((A, B, X), 2)),  # a finished route gets a leg to drive again
        (Route(), None, Route((X,), 0)),
        (Route(home=HOME), -1, Route((X,), 0, HOME)),
    ],
)
def test_add(route: Route, after: int | None, expected: Route) -> None:
    assert add(route, X, after) == expected


def test_add_after_current_and_at_end() -> None:
    assert add_after_current(Route((A, B, D), 0), X) == Route((A, X, B, D), 0)
    assert add_after_current(Route((A, B), 2), X) == Route((A, B, X), 2)  # finished: after the last
    assert add_after_current(Route(), X) == Route((X,), 0)
    assert add_at_end(Route((A,), 0, HOME), X) == Route((A, X), 0, HOME)


@pytest.mark.parametrize(("after", "message"), [(3, "no waypoint 4 to add after: the route has 3"), (-2, "no waypoint -1 to add after")])
def test_add_outside_the_route_is_refused(after: int, message: str) -> None:
    with pytest.raises(RouteError, match=message):
        add(Route((A, B, D)), X, after)


def test_remove_last_and_clear_keep_the_home() -> None:
    assert remove_last(Route((A, B, D), 2, HOME)) == Route((A, B), 2, HOME)  # heading for the removed last: the route is done
    assert remove_last(Route((A, B, D), 1, HOME)) == Route((A, B), 1, HOME)
    assert clear(Route((A, B), 1, HOME)) == Route((), 0, HOME)
    with pytest.raises(RouteError, match="the route is empty: no waypoint to remove"):
        remove_last(Route(home=HOME))


@pytest.mark.parametrize(
    ("route", "expected"),
    [
        (Route((A, B, D), 1), Route((D, B, A), 1)),  # heading for B, then back to A
        (Route((A, B, D), 0), Route((D, B, A), 2)),  # heading for A: then done
        (Route((A, B, D), 2), Route((D, B, A), 0)),  # heading for D (the last): then B, A
        (Route((A, B, D), 3), Route((D, B, A), 3)),  # finished stays finished
        (Route((A,), 0, HOME), Route((A,), 0, HOME)),
    ],
)
def test_backwards(route: Route, expected: Route) -> None:
    assert backwards(route) == expected


def test_an_offset_east_on_the_equator_is_exact_and_north_follows_the_meridian() -> None:
    degree_m = 6378137.0 * math.pi / 180.0  # a degree of the equator
    [moved] = offset(Route((Waypoint(lat=0.0, lon=10.0),)), degree_m, 90.0).waypoints
    assert (moved.lat, moved.lon) == pytest.approx((0.0, 11.0), abs=1e-12)
    [north] = offset(Route((A,)), 1234.5, 0.0).waypoints
    assert (north.lat, north.lon) == pytest.approx(geo.destination(A.lat, A.lon, 0.0, 1234.5), abs=1e-12)
    [west] = offset(Route((Waypoint(lat=0.0, lon=-179.99999),)), 10.0, 270.0).waypoints  # across the antimeridian
    assert west.lon == pytest.approx(-179.99999 - 10.0 / degree_m + 360.0, abs=1e-12)


def test_an_offset_keeps_every_other_field() -> None:
    wp = Waypoint(lat=-35.0, lon=149.0, alt_m=12.0, name="gate", speed_m_s=1.5, sample=True)
    [moved] = offset(Route((wp,)), 5.0, 45.0).waypoints
    assert moved.model_dump(exclude={"lat", "lon"}) == wp.model_dump(exclude={"lat", "lon"})


def square(about: tuple[float, float], radius_m: float, first_bearing: float = 45.0) -> Route:
    """Four corners at ``radius_m`` from ``about``, bearings 45, 135, 225, 315 (geodesic polar coordinates)."""
    return Route(tuple(near(about, first_bearing + 90.0 * k, radius_m) for k in range(4)))


def test_scale_rotate_turns_clockwise_about_the_centre_and_scales_distances_from_it() -> None:
    corners = square(C, 100.0)
    turned = scale_rotate(corners, 1.0, 90.0, C)
    assert gap(turned, Route(corners.waypoints[1:] + corners.waypoints[:1])) <= EXACT_M  # each corner to the next, clockwise
    doubled = scale_rotate(corners, 2.0, 0.0, C)
    assert gap(doubled, square(C, 200.0)) <= EXACT_M


def test_mirror_across_a_north_south_axis_swaps_east_and_west() -> None:
    route = Route((near(C, 90.0, 100.0), near(C, 60.0, 50.0)))
    mirrored = mirror(route, 0.0, C)
    assert gap(mirrored, Route((near(C, 270.0, 100.0), near(C, 300.0, 50.0)))) <= EXACT_M
    assert mirrored.waypoints[0].lat == pytest.approx(route.waypoints[0].lat, abs=1e-12)


def test_the_centre_is_that_of_the_latitude_longitude_box_even_across_the_antimeridian() -> None:
    route = Route((Waypoint(lat=1.0, lon=10.0), Waypoint(lat=3.0, lon=10.5), Waypoint(lat=2.0, lon=12.0)))
    assert centre(route) == pytest.approx((2.0, 11.0))
    across = Route((Waypoint(lat=0.0, lon=179.999), Waypoint(lat=0.001, lon=-179.997)))
    assert centre(across) == pytest.approx((0.0005, -179.999))
    assert scale_rotate(across, 1.0, 0.0).waypoints[1].lon == pytest.approx(-179.997, abs=1e-9)


def test_the_operations_leave_their_argument_alone() -> None:
    route = Route((A, B, D), 1, HOME)
    snapshot = (route.waypoints, route.current, route.home)
    for edit in (backwards, clear, remove_last, lambda r: offset(r, 5, 90), lambda r: scale_rotate(r, 2, 30), lambda r: mirror(r, 10)):
        edit(route)
    assert (route.waypoints, route.current, route.home) == snapshot


# -- errors --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda: backwards(Route()), "the route is empty: nothing to reverse"),
        (lambda: offset(Route(), 5, 90), "the route is empty: nothing to offset"),
        (lambda: scale_rotate(Route(), 2, 0), "the route is empty: nothing to scale or rotate"),
        (lambda: mirror(Route(), 0), "the route is empty: nothing to mirror"),
        (lambda: centre(Route()), "the route is empty: it has no centre"),
        (lambda: offset(Route((A, B)), 5, 90, 2), "no waypoint 3 to offset: the route has 2"),
        (lambda: offset(Route((A,)), math.nan, 90), "distance_m must be a finite number"),
        (lambda: offset(Route((A,)), 5, math.inf), "bearing_deg must be a finite number"),
        (lambda: offset(Route((A,)), 2e6, 90), "an offset of 2000 km is over 1000 km"),
        (lambda: offset(Route((Waypoint(lat=89.99, lon=0.0),)), 5000, 0), "waypoint 1: 5000 m toward 0° from latitude 89.99 passes a pole"),
        (lambda: offset(Route((Waypoint(lat=90.0, lon=0.0),)), 5, 0), "waypoint 1: latitude 90: no compass bearing at a pole"),
        (lambda: scale_rotate(Route((A,)), 0, 0), "scale 0: must be greater than 0"),
        (lambda: scale_rotate(Route((A,)), -2, 0), "scale -2: must be greater than 0"),
        (lambda: scale_rotate(Route((A, D)), 2e4, 0), "waypoint 1 would be 2000 km from the centre: over 1000 km"),
        (lambda: mirror(Route((A,)), 0, (95.0, 0.0)), "centre latitude 95 is outside"),
        (lambda: mirror(Route((A,)), 0, (1.0,)), r"centre must be \[lat, lon\]"),
        (lambda: set_home(Route(), 91.0, 0.0), "no home at 91.0, 0.0: lat: Input should be less than or equal to 90"),
    ],
)
def test_impossible_requests_say_why(edit, message: str) -> None:
    with pytest.raises(RouteError, match=message):
        edit()


def test_a_route_error_is_a_value_error() -> None:
    assert issubclass(RouteError, ValueError)


# -- an operator's request -----------------------------------------------------------------------


def here() -> tuple[float, float]:
    return (-35.1, 149.1)


def nowhere() -> tuple[float, float]:
    raise RouteError("no position")


@pytest.mark.parametrize(
    ("operation", "args", "expected", "words"),
    [
        (
            "set_home",
            {},
            Route((A, B), 1, Home(lat=-35.1, lon=149.1, heading_deg=90.0)),
            "home set to -35.1000000, 149.1000000 (the vehicle's position)",
        ),
        (
            "SET_HOME",
            {"lat": -35.2, "lon": 149.2},
            Route((A, B), 1, Home(lat=-35.2, lon=149.2, heading_deg=90.0)),
            "home set to -35.2000000, 149.2000000",
        ),
        (
            "add",
            {},
            Route((A, B, Waypoint(lat=-35.1, lon=149.1)), 1, HOME),
            "waypoint 3/3 added at -35.1000000, 149.1000000 (the vehicle's position)",
        ),
        ("ADD_WP", {"after": "current", "lat": -35.0, "lon": 149.0}, Route((A, B, X), 1, HOME), "waypoint 3/3 added at -35.0000000, 149.0000000"),
        ("add", {"after": 0, "lat": -35.0, "lon": 149.0}, Route((X, A, B), 2, HOME), "waypoint 1/3 added"),
        (
            "add",
            {"after": "1", "lat": -35.0, "lon": 149.0, "alt_m": 30},
            Route((A, X.model_copy(update={"alt_m": 30.0}), B), 1, HOME),
            "waypoint 2/3",
        ),
        ("remove", {"waypoint": "last"}, Route((A,), 1, HOME), "waypoint 2/2 removed"),
        ("REMOVE_WP", {"waypoint": "current"}, Route((A,), 1, HOME), "waypoint 2/2 removed"),
        ("remove", {"waypoint": 1}, Route((B,), 0, HOME), "waypoint 1/2 removed"),
        ("clear-mission", {}, Route((), 0, HOME), "route cleared (2 waypoints removed)"),
        ("backwards", {}, Route((B, A), 0, HOME), "route reversed (2 waypoints)"),
        ("offset", {"distance_m": 0, "bearing_deg": 450}, Route((A, B), 1, HOME), "2 waypoints offset 0 m toward 090.0°"),
        ("offset", {"distance_m": 0, "bearing_deg": 90, "waypoint": 2}, Route((A, B), 1, HOME), "waypoint 2 offset 0 m toward 090.0°"),
        (
            "scale-rotate",
            {"scale": 1, "angle_deg": 0, "centre": [-35.0, 149.0]},
            Route((A, B), 1, HOME),
            "2 waypoints scaled by 1 and rotated 0° about",
        ),
        ("MIRROR_MISSION", {"bearing_deg": 0}, Route((A, B), 1, HOME), "2 waypoints mirrored across the 000.0° axis through"),
    ],
)
def test_apply_a_request(operation: str, args: dict, expected: Route, words: str) -> None:
    new, said = apply(Route((A, B), 1, HOME), operation, args, here)
    assert said.startswith(words)
    assert gap(new, expected) <= EXACT_M and (new.current, new.home) == (expected.current, expected.home)
    assert [wp.alt_m for wp in new.waypoints] == [wp.alt_m for wp in expected.waypoints]


@pytest.mark.parametrize(
    ("operation", "args", "message"),
    [
        ("warp", {}, "unknown route operation 'warp' \\(known: set_home, add, remove"),
        ("clear", {"now": True}, "clear takes no arguments, not now"),
        ("offset", {"distance_m": 5, "bearing": 90}, "offset takes distance_m, bearing_deg, waypoint, not bearing"),
        ("offset", {"distance_m": 5}, "bearing_deg is needed"),
        ("offset", {"distance_m": "5", "bearing_deg": 90}, "distance_m must be a finite number, not '5'"),
        ("offset", {"distance_m": 5, "bearing_deg": 90, "waypoint": 0}, 'waypoint must be "last", "current" or a waypoint number from 1, not 0'),
        ("remove", {}, "waypoint must be"),
        ("remove", {"waypoint": 3}, "no waypoint 3 to remove: the route has 2"),
        ("remove", {"waypoint": True}, "waypoint must be"),
        ("add", {"after": "middle", "lat": 0, "lon": 0}, 'after must be "end", "current" or a waypoint number from 0'),
        ("add", {"after": 3, "lat": 0, "lon": 0}, "no waypoint 3 to add after: the route has 2"),
        ("add", {"lat": 0}, "lon is needed"),
        ("add", {"lat": 100, "lon": 0}, "no waypoint at 100.0, 0.0: lat"),
        ("add", {}, "no position"),
        ("set_home", {}, "no position"),
        ("scale_rotate", {"scale": 2, "angle_deg": 0, "centre": "here"}, r"centre must be \[lat, lon\], not 'here'"),
    ],
)
def test_a_request_that_cannot_apply_says_why(operation: str, args: dict, message: str) -> None:
    with pytest.raises(RouteError, match=message):
        apply(Route((A, B), 1, HOME), operation, args, nowhere)


def test_remove_from_an_empty_route_is_refused_whichever_waypoint() -> None:
    for which in ("last", "current", 1):
        with pytest.raises(RouteError, match=r"the route is empty|no waypoint 1 to remove: the route has 0"):
            apply(Route(), "remove", {"waypoint": which}, here)


def test_operation_names() -> None:
    assert [operation_name(n) for n in ("SCALE_ROTATE_MISSION", "scale-rotate", " Offset ", "BACKWARDS_MISSION")] == [
        "scale_rotate", "scale_rotate", "offset", "backwards",
    ]  # fmt: skip
