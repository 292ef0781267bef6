"""A route against the world: every leg, as a segment, against the mission's keep-out and inclusion zones.

A route whose waypoints all lie outside a no-go zone may still cross it between two of them
(PX4-Autopilot issue 22362), so legs are checked, not points. The geometry is shapely's (GEOS, the
engine of PostGIS and QGIS): robust predicates and overlays, an STR-tree so that 1,000 legs
against 100 zones cost a few milliseconds, and polygons with holes or concave corners handled
without code of our own to get wrong.

The plane: metres east and north of an origin (the mission's home, else its first waypoint; at
start the vehicle): the points on the WGS84 ellipsoid seen in its tangent plane (local ENU, the up
dropped). Over a route 10 km across the distances are the ellipsoid's within a millimetre (measured
against geographiclib, tests/mission/test_zones.py), well inside any acceptance radius. A circle becomes a 64-gon drawn outside the circle for a
keep-out zone and inside it for an inclusion zone, so the polygon never lets through what the
circle would not. ``limits.acceptance_radius_m`` is the margin: a vehicle that counts a waypoint
reached that far off may cut a corner by as much, so a keep-out zone is grown by it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from executive.mission.errors import Path
from executive.mission.model import Mission, Zone
from executive.world.geofence import open_ring

if TYPE_CHECKING:  # shapely is imported where zones are checked: only a mission with zones pays its ~3 MB
    import shapely

_A = 6378137.0  # WGS84
_E2 = 6.69437999014e-3
_QUAD_SEGS = 16  # a circle as 64 sides
#: A leg outside the inclusion zones by less than this (metres) is on their edge.
EDGE_M = 0.1

LatLon = tuple[float, float]


def _ecef(lats: np.ndarray, lons: np.ndarray) -> np.ndarray:
    phi, lam = np.radians(lats), np.radians(lons)
    n = _A / np.sqrt(1.0 - _E2 * np.sin(phi) ** 2)
    return np.stack([n * np.cos(phi) * np.cos(lam), n * np.cos(phi) * np.sin(lam), n * (1.0 - _E2) * np.sin(phi)], axis=-1)


def chord_m(lats_a: Sequence[float], lons_a: Sequence[float], lats_b: Sequence[float], lons_b: Sequence[float]) -> np.ndarray:
    """Straight-line distances between points a and b on the ellipsoid, metres: the geodesic's length less d³/24R²
    (8 mm at 20 km, 1 m at 100 km), at numpy's speed (geographiclib takes ~0.3 ms a distance: 1,000 legs in 300 ms)."""
    a = _ecef(np.asarray(lats_a, dtype=float), np.asarray(lons_a, dtype=float))
    b = _ecef(np.asarray(lats_b, dtype=float), np.asarray(lons_b, dtype=float))
    return np.linalg.norm(b - a, axis=-1)


class Plane:
    """Metres east, north of ``origin``: the points on the WGS84 ellipsoid, seen in the tangent plane there (local ENU, up dropped)."""

    def __init__(self, origin: LatLon) -> None:
        self.lat0, self.lon0 = origin
        phi, lam = math.radians(self.lat0), math.radians(self.lon0)
        self._origin = _ecef(np.array([self.lat0]), np.array([self.lon0]))[0]
        east = [-math.sin(lam), math.cos(lam), 0.0]
        north = [-math.sin(phi) * math.cos(lam), -math.sin(phi) * math.sin(lam), math.cos(phi)]
        self._axes = np.array([east, north]).T

    def xy(self, lats: Sequence[float] | np.ndarray, lons: Sequence[float] | np.ndarray) -> np.ndarray:
        """An (n, 2) array of (east, north) for the points."""
        return (_ecef(np.asarray(lats, dtype=float), np.asarray(lons, dtype=float)) - self._origin) @ self._axes


@dataclass(frozen=True)
class Area:
    """A zone in the plane: what messages call it and its shape."""

    label: str
    shape: shapely.Geometry


def _shapes(plane: Plane, zones: Sequence[Zone], keep_out: bool) -> np.ndarray:
    """The zones as shapes in the plane, in order: one projection and one GEOS call for all of them (a route edit's budget)."""
    import shapely

    shapes = np.empty(len(zones), dtype=object)
    circles = [(i, z.circle) for i, z in enumerate(zones) if z.circle is not None]
    if circles:
        centres = plane.xy([c.lat for _, c in circles], [c.lon for _, c in circles])
        radii = np.array([c.radius_m for _, c in circles]) / (math.cos(math.pi / (4 * _QUAD_SEGS)) if keep_out else 1.0)
        shapes[[i for i, _ in circles]] = shapely.buffer(shapely.points(centres), radii, quad_segs=_QUAD_SEGS)
    rings = [(i, open_ring([(v.lat, v.lon) for v in z.polygon])) for i, z in enumerate(zones) if z.circle is None and z.polygon]
    if rings:
        corners = [p for _, ring in rings for p in ring]
        which = np.repeat(np.arange(len(rings)), [len(ring) for _, ring in rings])
        closed = shapely.linearrings(plane.xy([p[0] for p in corners], [p[1] for p in corners]), indices=which)
        shapes[[i for i, _ in rings]] = shapely.polygons(closed)
    return shapes


def _label(kind: str, zones: str, i: int, zone: Zone) -> str:
    return f"{kind} zone {zone.name!r}" if zone.name else f"{kind} zone geofence.{zones}[{i}]"


def zone_shape_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Each zone is one polygon or one circle."""
    config = mission.geofence
    errors: list[tuple[Path, str]] = []
    for zones in ("inclusion", "keep_out"):
        for i, zone in enumerate(getattr(config, zones) if config else ()):
            if (zone.polygon is None) == (zone.circle is None):
                errors.append((("geofence", zones, i), "a zone is a polygon or a circle: give exactly one"))
    return errors


class Zones:
    """A mission's zones in one plane, ready to check legs against (build once per check: a route edit builds anew)."""

    def __init__(self, mission: Mission, plane: Plane) -> None:
        import shapely

        config = mission.geofence
        assert config is not None
        self.plane = plane
        self.margin = mission.limits.acceptance_radius_m
        shapes = _shapes(plane, config.keep_out, True)
        self.keep_out = [Area(_label("keep-out", "keep_out", i, z), shapes[i]) for i, z in enumerate(config.keep_out)]
        inclusion = list(_shapes(plane, [*config.inclusion, *([Zone(polygon=config.polygon)] if config.polygon else [])], False))
        self.allowed = shapely.union_all(inclusion) if config.inclusion else None  # None: the polygon alone, checked by the geofence rule
        self._grown = shapely.buffer(shapes, self.margin, quad_segs=_QUAD_SEGS)
        self._tree = shapely.STRtree(self._grown)

    def point_problems(self, xy: np.ndarray) -> list[tuple[int, str]]:
        """(index, why) of each point inside a keep-out zone (or its margin), or outside every inclusion zone."""
        import shapely

        found: list[tuple[int, str]] = []
        points = shapely.points(xy)
        for p, z in zip(*self._tree.query(points, predicate="intersects"), strict=True):
            area, gap = self.keep_out[z], float(shapely.distance(points[p], self.keep_out[z].shape))
            why = f"inside {area.label}" if gap == 0.0 else f"{gap:.1f} m from {area.label}, within the {self.margin:g} m margin"
            found.append((int(p), why + ("" if gap == 0.0 else " (limits.acceptance_radius_m)")))
        if self.allowed is not None:
            out = ~shapely.intersects(points, self.allowed)
            found += [(int(p), "outside every inclusion zone") for p in np.flatnonzero(out)]
        return sorted(found)

    def leg_problems(self, starts: np.ndarray, ends: np.ndarray) -> list[tuple[int, str]]:
        """(leg index, why) of each leg (starts[i] -> ends[i]) that crosses a keep-out zone or its margin, or leaves the inclusion zones."""
        import shapely

        found: list[tuple[int, str]] = []
        legs = shapely.linestrings(np.stack([starts, ends], axis=1))
        for leg, z in zip(*self._tree.query(legs, predicate="intersects"), strict=True):
            area = self.keep_out[z]
            inside = float(shapely.length(shapely.intersection(legs[leg], area.shape)))
            if inside > 0.0:
                why = f"crosses {area.label} for {inside:.0f} m"
            else:
                gap = float(shapely.distance(legs[leg], area.shape))
                why = f"passes {gap:.1f} m from {area.label}, within the {self.margin:g} m margin (limits.acceptance_radius_m)"
            found.append((int(leg), why))
        if self.allowed is not None:
            outside = shapely.length(shapely.difference(legs, self.allowed))
            found += [(int(leg), f"leaves the inclusion zones for {outside[leg]:.0f} m") for leg in np.flatnonzero(outside > EDGE_M)]
        return sorted(found)


def _name(mission: Mission, i: int) -> str:
    name = mission.waypoints[i].name
    return repr(name) if name else "-"


def _origin(mission: Mission) -> LatLon:
    if mission.home is not None:
        return mission.home.lat, mission.home.lon
    if mission.waypoints:
        return mission.waypoints[0].lat, mission.waypoints[0].lon
    return 0.0, 0.0


def has_zones(mission: Mission) -> bool:
    """The mission has keep-out or inclusion zones the legs are checked against."""
    return mission.geofence is not None and bool(mission.geofence.keep_out or mission.geofence.inclusion)


def route_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Every waypoint and leg (from home, where the mission has one, then waypoint to waypoint) against the zones, located at the leg's end."""
    if not has_zones(mission) or not mission.waypoints:
        return []
    zones = Zones(mission, Plane(_origin(mission)))
    wps = mission.waypoints
    xy = zones.plane.xy([w.lat for w in wps], [w.lon for w in wps])
    errors: list[tuple[Path, str]] = []
    for i, why in zones.point_problems(xy):
        errors.append((("waypoints", i), f"{_name(mission, i)} is {why}" if wps[i].name else why))
    starts, first = xy[:-1], 1
    if mission.home is not None:
        starts, first = np.vstack([zones.plane.xy([mission.home.lat], [mission.home.lon]), starts]), 0
    for leg, why in zones.leg_problems(starts, xy[first:]):
        end = leg + first
        if end == 0:
            errors.append((("waypoints", 0), f"home -> waypoints[0] ({_name(mission, 0)}): {why}"))
        else:
            names = f"({_name(mission, end - 1)} -> {_name(mission, end)})"
            errors.append((("waypoints", end), f"waypoints[{end - 1}] -> waypoints[{end}] {names}: {why}"))
    return errors


def first_leg_problems(mission: Mission, lat: float, lon: float, *, first: int = 0) -> list[str]:
    """The leg from the vehicle at (lat, lon) to ``waypoints[first]`` against the zones: where it starts inside one, or crosses one."""
    if not has_zones(mission) or first >= len(mission.waypoints):
        return []
    zones = Zones(mission, Plane((lat, lon)))
    wp = mission.waypoints[first]
    here, there = zones.plane.xy([lat, wp.lat], [lon, wp.lon])
    found = [f"the vehicle is {why}" for _, why in zones.point_problems(here[None, :]) if not why.startswith("outside")]
    leg = f"the vehicle -> waypoints[{first}] ({_name(mission, first)})"
    found += [f"{leg}: {why}" for _, why in zones.leg_problems(here[None, :], there[None, :])]
    return found
