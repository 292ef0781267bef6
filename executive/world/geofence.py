"""Geofences: a polygon the vehicle must stay inside and a maximum distance from home.

The polygon test runs in a local tangent plane: the vertices are projected once, azimuthal
equidistant about the first vertex (east, north in metres from the geodesic distance and bearing of
:mod:`executive.world.geo`). Over a fence tens of km across that projection is off by well under a metre
(its scale error grows as (d/R)²/6), so the plane answers as the ellipsoid would. A point on the
boundary (within 1 cm) counts as inside. Distances from home are geodesic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from executive.world.geo import distance, distance_bearing

LatLon = tuple[float, float]
Point = tuple[float, float]  # east, north, metres

#: Closer than this to an edge counts as on it; vertices closer than this are the same vertex.
ON_EDGE_M = 0.01


def project(origin: LatLon, lat: float, lon: float) -> Point:
    """(east, north) metres of (lat, lon) from ``origin``, azimuthal equidistant."""
    d, bearing = distance_bearing(origin[0], origin[1], lat, lon)
    b = math.radians(bearing)
    return d * math.sin(b), d * math.cos(b)


def _cross(o: Point, a: Point, b: Point) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _point_segment_distance(p: Point, a: Point, b: Point) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def _segments_meet(a: Point, b: Point, c: Point, d: Point) -> bool:
    """Segments ab and cd cross or touch (an end within ON_EDGE_M of the other segment)."""
    if (
        max(a[0], b[0]) + ON_EDGE_M < min(c[0], d[0])
        or max(c[0], d[0]) + ON_EDGE_M < min(a[0], b[0])
        or max(a[1], b[1]) + ON_EDGE_M < min(c[1], d[1])
        or max(c[1], d[1]) + ON_EDGE_M < min(a[1], b[1])
    ):
        return False  # bounding boxes apart: the common case, cheaply
    d1, d2, d3, d4 = _cross(c, d, a), _cross(c, d, b), _cross(a, b, c), _cross(a, b, d)
    if (d1 > 0) != (d2 > 0) and (d3 > 0) != (d4 > 0) and 0.0 not in (d1, d2, d3, d4):
        return True
    ends = ((a, c, d), (b, c, d), (c, a, b), (d, a, b))
    return min(_point_segment_distance(*end) for end in ends) <= ON_EDGE_M


def _edges(plane: Sequence[Point]) -> list[tuple[Point, Point]]:
    return [(plane[i], plane[(i + 1) % len(plane)]) for i in range(len(plane))]


def open_ring(vertices: Sequence[LatLon]) -> tuple[LatLon, ...]:
    """The vertices without a closing vertex that repeats the first (GeoJSON-style rings)."""
    ring = tuple((float(lat), float(lon)) for lat, lon in vertices)
    return ring[:-1] if len(ring) > 3 and ring[0] == ring[-1] else ring


def polygon_problems(vertices: Sequence[LatLon]) -> list[tuple[int, str]]:
    """Why ``vertices`` (an open ring) is not a usable fence polygon: (vertex index, why) each; [] if it is.

    Checked in order, the first kind found is reported: at least 3 vertices; no vertex repeating
    the one before; no edge folding back onto the one before; no two edges touching or crossing
    (the first pair only); some area.
    """
    if len(vertices) < 3:
        return [(max(len(vertices) - 1, 0), f"a polygon needs at least 3 vertices, not {len(vertices)}")]
    plane = [project(vertices[0], lat, lon) for lat, lon in vertices]
    n = len(plane)
    problems = [(i, f"vertex {i} repeats vertex {i - 1}") for i in range(1, n) if math.dist(plane[i], plane[i - 1]) <= ON_EDGE_M]
    if math.dist(plane[0], plane[-1]) <= ON_EDGE_M:
        problems.append((n - 1, f"vertex {n - 1} repeats vertex 0"))
    if problems:
        return problems
    edges = _edges(plane)
    for i in range(n):
        (a, b), (_, c) = edges[i], edges[(i + 1) % n]
        turn, ahead = _cross(a, b, c), (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1])
        if ahead < 0 and abs(turn) <= ON_EDGE_M * math.dist(a, b):
            j = (i + 1) % n
            return [((i + 2) % n, f"edge {j}-{(j + 1) % n} folds back onto edge {i}-{j}")]
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # adjacent through vertex 0
            if _segments_meet(*edges[i], *edges[j]):
                return [(j, f"edge {j}-{(j + 1) % n} touches or crosses edge {i}-{i + 1}: the polygon intersects itself")]
    if abs(_area(plane)) < ON_EDGE_M:
        return [(0, "the polygon has no area")]
    return []


def _area(plane: Sequence[Point]) -> float:
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in _edges(plane))


@dataclass(frozen=True)
class Geofence:
    """Where the vehicle may be: inside ``polygon`` (if any) and within ``max_distance_m`` of home (if set).

    ``polygon`` is a sequence of (lat, lon) in order, either direction; a closing vertex repeating
    the first is dropped. Raises ValueError for an unusable polygon (see :func:`polygon_problems`)
    or a distance that is not positive.
    """

    polygon: tuple[LatLon, ...] = ()
    max_distance_m: float | None = None
    #: More areas the vehicle may be in besides ``polygon`` (a mission's ``geofence.inclusion``): polygons, and circles as
    #: (lat, lon, radius m). With any, the vehicle must be inside ``polygon`` or one of them.
    inclusion_polygons: tuple[tuple[LatLon, ...], ...] = ()
    inclusion_circles: tuple[tuple[float, float, float], ...] = ()
    _plane: tuple[Point, ...] = field(init=False, repr=False, compare=False)
    _others: tuple[Geofence, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ring = open_ring(self.polygon)
        if ring:
            problems = polygon_problems(ring)
            if problems:
                raise ValueError("; ".join(why for _, why in problems))
        if self.max_distance_m is not None and not self.max_distance_m > 0.0:
            raise ValueError(f"max_distance_m must be > 0, not {self.max_distance_m}")
        object.__setattr__(self, "polygon", ring)
        object.__setattr__(self, "_plane", tuple(project(ring[0], lat, lon) for lat, lon in ring) if ring else ())
        object.__setattr__(self, "_others", tuple(Geofence(tuple(p)) for p in self.inclusion_polygons))

    def outside_polygon_m(self, lat: float, lon: float) -> float:
        """How far (lat, lon) is outside the polygon (or the nearest inclusion zone), metres; 0.0 inside one, on a boundary, or with none."""
        if not self._others and not self.inclusion_circles:
            return self._outside_own(lat, lon)
        own = self._outside_own(lat, lon) if self._plane else math.inf
        others = [g._outside_own(lat, lon) for g in self._others]
        others += [max(0.0, distance(c_lat, c_lon, lat, lon) - radius) for c_lat, c_lon, radius in self.inclusion_circles]
        return min(own, *others)

    def _outside_own(self, lat: float, lon: float) -> float:
        if not self._plane:
            return 0.0
        p = project(self.polygon[0], lat, lon)
        edges = _edges(self._plane)
        nearest = min(_point_segment_distance(p, a, b) for a, b in edges)
        if nearest <= ON_EDGE_M:
            return 0.0
        inside = False
        for a, b in edges:  # crossing number of a ray toward +east
            if (a[1] > p[1]) != (b[1] > p[1]) and p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]):
                inside = not inside
        return 0.0 if inside else nearest

    def why_outside(self, lat: float, lon: float, home: LatLon | None) -> str | None:
        """``None`` when (lat, lon) is inside the fence, else why not.

        Without a ``home`` the distance rule cannot be judged and counts as broken.
        """
        outside = self.outside_polygon_m(lat, lon)
        if outside > 0.0:
            return f"{outside:.0f} m outside the fence polygon" + (" and every inclusion zone" if self._others or self.inclusion_circles else "")
        if self.max_distance_m is None:
            return None
        if home is None:
            return "no home to measure the distance from"
        from_home = distance(home[0], home[1], lat, lon)
        if from_home > self.max_distance_m:
            return f"{from_home:.0f} m from home, over the fence's {self.max_distance_m:g} m"
        return None

    def contains(self, lat: float, lon: float, home: LatLon | None) -> bool:
        """(lat, lon) is inside the polygon and within the maximum distance of ``home``."""
        return self.why_outside(lat, lon, home) is None
