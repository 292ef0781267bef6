"""The way back: from the vehicle to the nearest rally point or home, around the mission's keep-out zones.

A shortest path over a visibility graph: its nodes are the vehicle, the places to return to, and
the corners of each keep-out zone grown by ``limits.acceptance_radius_m`` plus :data:`MARGIN_M`; an
edge is a straight line that does not touch any zone grown by the acceptance radius alone. A node
counts as reached within the acceptance radius, so a vehicle that turns for the next node that far
early still keeps :data:`MARGIN_M` off the zone; the edges keep the acceptance radius off it, as
the route check keeps every leg (:mod:`executive.mission.zones`). The graph is searched by A*
with the straight distance to the nearest place as the heuristic, each node's edges made only when
it is expanded (one vectorised STR-tree query against every other node): a return around 100
zones is planned in milliseconds (``python -m benchmarks --only route``).

A vehicle inside a zone (or within its acceptance radius: a person drove it there, or a hold
stopped it at the edge) first leaves by the shortest way out, to the nearest point of that zone's
grown ring, then goes on by the graph. The plane is the zones' (:class:`~executive.mission.zones.Plane`,
centred on the vehicle).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from executive.mission.model import Mission
from executive.mission.zones import Plane, has_zones
from executive.world.geofence import open_ring

#: How far beyond the acceptance radius the path's corners keep off a keep-out zone, metres: a rover following a straight
#: GUIDED leg keeps within about a metre of the line (ArduRover's L1/position controller; the simulated rover within 0.5 m),
#: and a node reached an acceptance radius early cuts the corner by as much: 2 m covers the rest.
MARGIN_M = 2.0
#: A grown zone's rounding: 2 chords a quarter turn (a circle an 8-gon): few corners, each a node of the graph.
_QUAD_SEGS = 2

LatLon = tuple[float, float]
#: The kinds whose return the executive drives itself (behaviours.returning): they move in the plane the zones are drawn in.
DRIVEN_KINDS = frozenset({"rover", "boat"})


@dataclass(frozen=True)
class ReturnPath:
    """Where a return goes and the way: ``points`` after the vehicle's position, the last one the place returned to."""

    to: str  # "home", "rally point 'slipway'", "rally_points[1]"
    points: tuple[LatLon, ...]
    length_m: float
    #: The straight line from the vehicle to the place touches no zone (grown by the acceptance radius): the firmware's RTL would do.
    straight: bool
    #: The vehicle starts inside a keep-out zone or its margin: the first point is the shortest way out.
    leaves_zone: bool = False

    def describe(self) -> str:
        """``rally point 'slipway', 212 m by 4 legs around the keep-out zones``."""
        legs = len(self.points)
        how = "straight" if self.straight else f"by {legs} legs around the keep-out zones"
        return f"{self.to}, {self.length_m:.0f} m {how}"


def _to_lat_lon(plane: Plane, xy: np.ndarray) -> list[LatLon]:
    """The inverse of ``plane.xy``: a first guess on the sphere, then two Newton steps on the plane's own projection (sub-millimetre)."""
    m_per_deg = 111_320.0
    lats = plane.lat0 + xy[:, 1] / m_per_deg
    lons = plane.lon0 + xy[:, 0] / (m_per_deg * max(math.cos(math.radians(plane.lat0)), 1e-6))
    for _ in range(3):
        error = xy - plane.xy(lats, lons)
        lats = lats + error[:, 1] / m_per_deg
        lons = lons + error[:, 0] / (m_per_deg * max(math.cos(math.radians(plane.lat0)), 1e-6))
    return [(float(a), float(b)) for a, b in zip(lats, lons, strict=True)]


def _places(mission: Mission, home: LatLon | None) -> list[tuple[str, LatLon]]:
    places = [(f"rally point {p.name!r}" if p.name else f"rally_points[{i}]", (p.lat, p.lon)) for i, p in enumerate(mission.rally_points)]
    return places + ([("home", home)] if home is not None else [])


class ReturnPlanner:
    """A mission's return: :meth:`plan` from where the vehicle is to the nearest (by the way) rally point or home."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission

    @property
    def needed(self) -> bool:
        """The mission has keep-out zones or rally points: a return is the executive's to plan (else the firmware's RTL goes home)."""
        return bool(self.mission.rally_points) or (self.mission.geofence is not None and bool(self.mission.geofence.keep_out))

    def plan(self, lat: float, lon: float, home: LatLon | None) -> ReturnPath | None:
        """The shortest way from (lat, lon) to a rally point or ``home``, around the keep-out zones; None: no place, or none reachable."""
        places = _places(self.mission, home)
        if not places:
            return None
        plane = Plane((lat, lon))
        targets = plane.xy([p[1][0] for p in places], [p[1][1] for p in places])
        if not (has_zones(self.mission) and self.mission.geofence and self.mission.geofence.keep_out):
            lengths = np.hypot(targets[:, 0], targets[:, 1])
            best = int(np.argmin(lengths))
            return ReturnPath(places[best][0], (places[best][1],), float(lengths[best]), straight=True)
        return _Graph(self.mission, plane).search(places, targets)


def _grown(plane: Plane, mission: Mission, by_m: float) -> np.ndarray:
    """The keep-out zones grown by ``by_m``, drawn with few corners and never inside the true shape: a circle as an 8-gon round
    the circle of its radius plus ``by_m``, a polygon's corners rounded by two chords, each at least ``by_m`` off the corner."""
    import shapely

    assert mission.geofence is not None
    zones = mission.geofence.keep_out
    out = 1.0 / math.cos(math.pi / (4 * _QUAD_SEGS))  # a chord of the rounding stays outside the true distance
    shapes = np.empty(len(zones), dtype=object)
    circles = [(i, z.circle) for i, z in enumerate(zones) if z.circle is not None]
    if circles:
        centres = plane.xy([c.lat for _, c in circles], [c.lon for _, c in circles])
        radii = (np.array([c.radius_m for _, c in circles]) + by_m) * out
        shapes[[i for i, _ in circles]] = shapely.buffer(shapely.points(centres), radii, quad_segs=_QUAD_SEGS)
    rings = [(i, open_ring([(v.lat, v.lon) for v in z.polygon])) for i, z in enumerate(zones) if z.circle is None and z.polygon]
    for i, ring in rings:
        polygon = shapely.polygons(plane.xy([p[0] for p in ring], [p[1] for p in ring]))
        shapes[i] = shapely.buffer(polygon, by_m * out, quad_segs=_QUAD_SEGS)
    return shapes


class _Graph:
    """The visibility graph of one plan: the zones grown, their corners, the edges made as A* expands a node."""

    def __init__(self, mission: Mission, plane: Plane) -> None:
        import shapely

        self.plane = plane
        reach = mission.limits.acceptance_radius_m
        self.blocking = _grown(plane, mission, reach)  # what an edge must not touch
        shapely.prepare(self.blocking)  # prepared: an expansion's ~800 lines against them in a few milliseconds
        self.tree = shapely.STRtree(self.blocking)
        self.rings = _grown(plane, mission, reach + MARGIN_M)
        corners, before, after = [], [], []
        for ring in self.rings:
            xy = np.asarray(shapely.get_coordinates(shapely.get_exterior_ring(ring)))[:-1]
            corners.append(xy)
            before.append(np.roll(xy, 1, axis=0))
            after.append(np.roll(xy, -1, axis=0))
        xy = np.vstack(corners) if corners else np.empty((0, 2))
        inside = np.unique(self.tree.query(shapely.points(xy), predicate="intersects")[0])  # inside another zone: no way through it
        keep = np.setdiff1d(np.arange(len(xy)), inside)
        self.corners = xy[keep]
        # each corner's neighbours on its ring: a shortest path only turns at a corner it touches as a tangent
        self.before = (np.vstack(before) if before else np.empty((0, 2)))[keep]
        self.after = (np.vstack(after) if after else np.empty((0, 2)))[keep]

    def _blocked(self, origin: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """For each end, whether the straight line from ``origin`` to it touches a zone (the zones, prepared, queried against the lines)."""
        import shapely

        lines = shapely.linestrings(np.stack([np.broadcast_to(origin, ends.shape), ends], axis=1))
        blocked = np.zeros(len(ends), dtype=bool)
        blocked[np.unique(shapely.STRtree(lines).query(self.blocking, predicate="intersects")[1])] = True
        return blocked

    def _tangent(self, origin: np.ndarray, corners: np.ndarray) -> np.ndarray:
        """For each corner (an index into :attr:`corners`), whether the line from ``origin`` touches its ring there without entering it."""
        ray = self.corners[corners] - origin
        left = ray[:, 0] * (self.before[corners] - origin)[:, 1] - ray[:, 1] * (self.before[corners] - origin)[:, 0]
        right = ray[:, 0] * (self.after[corners] - origin)[:, 1] - ray[:, 1] * (self.after[corners] - origin)[:, 0]
        along = np.minimum(np.abs(left), np.abs(right)) <= 1e-6 * np.einsum("ij,ij->i", ray, ray)  # on the ring's edge: a way out
        return (left * right >= 0.0) | along

    def _way_out(self, start: np.ndarray) -> np.ndarray | None:
        """The nearest point of the grown ring of the zone(s) the vehicle is in; None when it is in none."""
        import shapely

        point = shapely.points(start)
        inside = self.tree.query(point, predicate="intersects")
        if len(inside) == 0:
            return None
        ring = shapely.union_all(self.rings[inside]).exterior if len(inside) > 1 else shapely.get_exterior_ring(self.rings[inside[0]])
        exit_point = shapely.line_interpolate_point(ring, shapely.line_locate_point(ring, point))
        return np.asarray(shapely.get_coordinates(exit_point))[0]

    def search(self, places: list[tuple[str, LatLon]], targets: np.ndarray) -> ReturnPath | None:
        start = np.zeros(2)
        out = self._way_out(start)
        first = out if out is not None else start
        nodes = np.vstack([first[None, :], targets, self.corners])
        n_targets = len(targets)
        is_target = np.zeros(len(nodes), dtype=bool)
        is_target[1 : 1 + n_targets] = True

        def heuristic(i: int) -> float:
            return float(np.min(np.hypot(*(targets - nodes[i]).T)))

        cost = np.full(len(nodes), np.inf)
        came = np.full(len(nodes), -1)
        cost[0] = 0.0
        done = np.zeros(len(nodes), dtype=bool)
        queue = [(heuristic(0), 0)]
        reached = None
        while queue:
            _, i = heapq.heappop(queue)
            if done[i]:
                continue
            done[i] = True
            if is_target[i]:
                reached = i
                break
            open_ = np.flatnonzero(~done)
            steps = np.hypot(*(nodes[open_] - nodes[i]).T)
            better = cost[i] + steps < cost[open_]
            candidates = open_[better]
            corner = candidates > n_targets
            candidates[corner] = np.where(self._tangent(nodes[i], candidates[corner] - 1 - n_targets), candidates[corner], -1)
            keep = candidates >= 0
            candidates, better_steps = candidates[keep], steps[better][keep]
            if len(candidates) == 0:
                continue
            free = ~self._blocked(nodes[i], nodes[candidates])
            for j, step in zip(candidates[free], better_steps[free], strict=True):
                cost[j] = cost[i] + step
                came[j] = i
                heapq.heappush(queue, (cost[j] + heuristic(int(j)), int(j)))
        if reached is None:
            return None
        order = [reached]
        while order[-1] != 0:
            order.append(int(came[order[-1]]))
        way = nodes[order[::-1]]
        if out is None:
            way = way[1:]
        length = float(cost[reached]) + (float(np.hypot(*out)) if out is not None else 0.0)
        place, where = places[reached - 1]
        straight = out is None and not self._blocked(start, targets[reached - 1][None, :])[0]
        points = [*_to_lat_lon(self.plane, way[:-1]), where] if len(way) > 1 else [where]
        return ReturnPath(place, tuple(points), length, straight=straight, leaves_zone=out is not None)
