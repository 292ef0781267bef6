"""Geofences: inside/outside convex and concave polygons, the distance from home, unusable input."""

from __future__ import annotations

import pytest

from executive.world.geo import destination, distance_bearing
from executive.world.geofence import Geofence, polygon_problems

ORIGIN = (47.397742, 8.545594)


def at(east_m: float, north_m: float, origin: tuple[float, float] = ORIGIN) -> tuple[float, float]:
    """The point ``east_m`` east and ``north_m`` north of ``origin`` (small offsets)."""
    lat, lon = destination(*origin, 0.0, north_m)
    return destination(lat, lon, 90.0, east_m)


SQUARE = Geofence(tuple(at(e, n) for e, n in [(0, 0), (0, 100), (100, 100), (100, 0)]))
# A U opening north: the notch x in (40, 60), y in (20, 100) is outside.
U_SHAPE = Geofence(tuple(at(e, n) for e, n in [(0, 0), (100, 0), (100, 100), (60, 100), (60, 20), (40, 20), (40, 100), (0, 100)]))


@pytest.mark.parametrize(
    ("fence", "point", "outside_m"),
    [
        (SQUARE, (50, 50), 0.0),
        (SQUARE, (0.5, 99.5), 0.0),
        (SQUARE, (50, 100), 0.0),  # on an edge counts as inside
        (SQUARE, (100, 100), 0.0),  # on a vertex too
        (SQUARE, (150, 50), 50.0),
        (SQUARE, (-10, 50), 10.0),
        (SQUARE, (50, -0.5), 0.5),
        (SQUARE, (103, 104), 5.0),  # nearest is the corner
        (U_SHAPE, (20, 80), 0.0),  # left arm
        (U_SHAPE, (80, 80), 0.0),  # right arm
        (U_SHAPE, (50, 10), 0.0),  # the base
        (U_SHAPE, (50, 80), 10.0),  # in the notch: outside, 10 m from either arm
        (U_SHAPE, (50, 25), 5.0),  # in the notch just above the base
        (U_SHAPE, (50, 120), 22.36),  # north of the notch: nearest are the tips of the arms
    ],
)
def test_polygon_inclusion(fence: Geofence, point: tuple[float, float], outside_m: float) -> None:
    lat, lon = at(*point)
    assert fence.outside_polygon_m(lat, lon) == pytest.approx(outside_m, abs=0.01)
    assert fence.contains(lat, lon, None) is (outside_m == 0.0)
    expected = None if outside_m == 0.0 else f"{outside_m:.0f} m outside the fence polygon"
    assert fence.why_outside(lat, lon, None) == expected


def test_either_direction_of_the_vertices_is_the_same_fence() -> None:
    reversed_u = Geofence(tuple(reversed(U_SHAPE.polygon)))
    for point in [(20, 80), (50, 80), (50, 10), (150, 50)]:
        lat, lon = at(*point)
        assert reversed_u.contains(lat, lon, None) == U_SHAPE.contains(lat, lon, None)


@pytest.mark.parametrize(
    ("point", "home", "why"),
    [
        ((0, 99), ORIGIN, None),
        ((0, 101), ORIGIN, "101 m from home, over the fence's 100 m"),
        ((70, 80), ORIGIN, "106 m from home, over the fence's 100 m"),
        ((0, 101), at(0, 50), None),  # measured from wherever home is
        ((0, 10), None, "no home to measure the distance from"),
    ],
)
def test_max_distance_from_home(point, home, why) -> None:
    fence = Geofence(max_distance_m=100.0)
    lat, lon = at(*point)
    assert fence.why_outside(lat, lon, home) == why
    assert fence.contains(lat, lon, home) is (why is None)


def test_polygon_and_distance_together_polygon_first() -> None:
    fence = Geofence(SQUARE.polygon, max_distance_m=60.0)
    assert fence.why_outside(*at(50, 50), ORIGIN) == "71 m from home, over the fence's 60 m"
    assert fence.why_outside(*at(150, 50), ORIGIN) == "50 m outside the fence polygon"
    assert fence.why_outside(*at(30, 30), ORIGIN) is None


def test_no_polygon_and_no_distance_contains_everything() -> None:
    assert Geofence().contains(-80.0, 170.0, None)


def test_a_closed_ring_is_the_same_polygon() -> None:
    closed = Geofence((*SQUARE.polygon, SQUARE.polygon[0]))
    assert closed.polygon == SQUARE.polygon
    assert closed == SQUARE


def test_a_fence_tens_of_km_across_is_exact_to_a_metre() -> None:
    """The far edge of a 30 km square: 1 m either side of its geodesic midpoint is told apart."""
    corners = (ORIGIN, destination(*ORIGIN, 0.0, 30_000), destination(*destination(*ORIGIN, 0.0, 30_000), 90.0, 30_000))
    corners = (*corners, destination(*ORIGIN, 90.0, 30_000))
    fence = Geofence(corners)
    length, bearing = distance_bearing(*corners[2], *corners[3])  # the east edge, far from vertex 0
    middle = destination(*corners[2], bearing, length / 2)
    assert fence.contains(*destination(*middle, bearing + 90.0, 1.0), None)  # west of a southbound edge: inside
    assert not fence.contains(*destination(*middle, bearing - 90.0, 1.0), None)
    assert fence.outside_polygon_m(*destination(*middle, bearing - 90.0, 1.0)) == pytest.approx(1.0, abs=0.1)


def test_a_fence_across_the_antimeridian() -> None:
    fence = Geofence(((-0.001, 179.999), (0.001, 179.999), (0.001, -179.999), (-0.001, -179.999)))
    assert fence.contains(0.0, 179.9995, None)
    assert fence.contains(0.0, -179.9995, None)
    assert fence.contains(0.0, 180.0, None)
    assert not fence.contains(0.0, 179.99, None)
    assert not fence.contains(0.0, 0.0, None)


@pytest.mark.parametrize(
    ("vertices", "problems"),
    [
        ([], [(0, "a polygon needs at least 3 vertices, not 0")]),
        ([(0, 0), (0, 100)], [(1, "a polygon needs at least 3 vertices, not 2")]),
        ([(0, 0), (0, 100), (0, 100), (100, 0)], [(2, "vertex 2 repeats vertex 1")]),
        ([(0, 0), (0, 100), (100, 0), (0, 0.001)], [(3, "vertex 3 repeats vertex 0")]),
        ([(0, 0), (0, 50), (0, 100)], [(0, "edge 2-0 folds back onto edge 1-2")]),  # on one line
        ([(0, 0), (100, 100), (100, 0), (0, 100)], [(2, "edge 2-3 touches or crosses edge 0-1: the polygon intersects itself")]),  # a bow tie
        ([(0, 0), (0, 100), (100, 100), (100, 0), (50, 100)], [(3, "edge 3-4 touches or crosses edge 1-2: the polygon intersects itself")]),
        ([(0, 0), (0, 100), (0, 50), (100, 0)], [(2, "edge 1-2 folds back onto edge 0-1")]),  # a spike
        ([(0, 0), (0.1, 0), (0, 0.1)], [(0, "the polygon has no area")]),  # 10 cm across
        ([(0, 0), (0, 100), (100, 100), (100, 0)], []),
        ([(e, n) for e, n in [(0, 0), (100, 0), (100, 100), (60, 100), (60, 20), (40, 20), (40, 100), (0, 100)]], []),
    ],
)
def test_polygon_problems(vertices, problems) -> None:
    ring = [at(e, n) for e, n in vertices]
    assert polygon_problems(ring) == problems
    if problems and ring:  # no vertices at all is no polygon: a fence of distance only
        with pytest.raises(ValueError, match=problems[0][1]):
            Geofence(tuple(ring))


@pytest.mark.parametrize("max_distance_m", [0.0, -5.0, float("nan")])
def test_a_distance_must_be_positive(max_distance_m: float) -> None:
    with pytest.raises(ValueError, match="max_distance_m must be > 0"):
        Geofence(max_distance_m=max_distance_m)
