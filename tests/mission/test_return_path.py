"""The way back around the keep-out zones: to the nearest rally point or home, never through a zone."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from benchmarks.route_check import at as bench_at
from benchmarks.route_check import scattered_mission
from executive.mission.loader import load_mission_text
from executive.mission.model import Mission
from executive.mission.return_path import MARGIN_M, ReturnPlanner
from executive.mission.zones import Plane, Zones
from executive.world.geo import destination, distance

HOME = (47.3977, 8.5456)


def at(north_m: float, east_m: float) -> tuple[float, float]:
    lat, lon = destination(*HOME, 0.0, north_m)
    return destination(lat, lon, 90.0, east_m)


def lake(keep_out: str, rally: str = "") -> Mission:
    """A boat mission at HOME (acceptance radius 2 m) with the zones and rally points given (YAML flow items)."""
    lat, lon = at(0, -30)  # west of home: clear of every zone
    text = f"version: 1\nname: lake\nvehicle: boat\nhome: {{lat: {HOME[0]}, lon: {HOME[1]}}}\nlimits: {{acceptance_radius_m: 2}}\n"
    text += f"geofence:\n  keep_out:\n{keep_out}" + (f"rally_points:\n{rally}" if rally else "")
    return load_mission_text(text + f"waypoints:\n  - {{lat: {lat:.7f}, lon: {lon:.7f}}}\n", "m.yaml")


def circle(name: str, north_m: float, east_m: float, radius_m: float) -> str:
    lat, lon = at(north_m, east_m)
    return f"    - {{name: {name}, circle: {{lat: {lat:.7f}, lon: {lon:.7f}, radius_m: {radius_m}}}}}\n"


def clearance_m(mission: Mission, start: tuple[float, float], points: tuple[tuple[float, float], ...]) -> float:
    """The closest the path from ``start`` through ``points`` comes to any keep-out zone, metres (exact 64-gons)."""
    zones = Zones(mission, Plane(HOME))
    xy = zones.plane.xy([p[0] for p in (start, *points)], [p[1] for p in (start, *points)])
    line = shapely.linestrings(xy)
    return min(float(shapely.distance(line, a.shape)) for a in zones.keep_out)


def test_a_return_blocked_by_an_island_goes_round_it_at_the_acceptance_radius_at_least():
    mission = lake(circle("island", 50, 0, 15))
    path = ReturnPlanner(mission).plan(*at(100, 0), HOME)
    assert path is not None and path.to == "home" and not path.straight
    assert len(path.points) >= 2 and distance(*path.points[-1], *HOME) < 0.01
    assert clearance_m(mission, at(100, 0), path.points) >= 2.0  # the acceptance radius: a node is reached that far early
    assert 100.0 < path.length_m < 100.0 * 1.2  # round, not far round


def test_a_clear_line_home_is_straight_and_the_firmwares_rtl_would_do():
    path = ReturnPlanner(lake(circle("island", 50, 60, 10))).plan(*at(100, 0), HOME)
    assert path is not None and path.straight and path.points == (HOME,)


def test_the_nearest_place_by_the_way_wins_a_rally_point_or_home():
    rally_lat, rally_lon = at(100, 60)
    rally = f"  - {{name: slipway, lat: {rally_lat:.7f}, lon: {rally_lon:.7f}}}\n"
    # from (100, 0): home 100 m south in a straight line; the slipway 60 m east, round a rock between: ~68 m
    mission = lake(circle("rock", 100, 30, 10), rally)
    path = ReturnPlanner(mission).plan(*at(100, 0), HOME)
    assert path is not None and path.to == "rally point 'slipway'" and not path.straight
    assert 60.0 < path.length_m < 75.0
    assert clearance_m(mission, at(100, 0), path.points) >= 2.0
    # an island there instead: round it is further than home
    path = ReturnPlanner(lake(circle("island", 100, 30, 25), rally)).plan(*at(100, 0), HOME)
    assert path is not None and path.to == "home" and path.straight


def test_a_vehicle_inside_a_zone_leaves_by_the_nearest_way_out_first():
    mission = lake(circle("pier", 50, 0, 10))
    start = at(55, 0)  # 5 m inside, 5 m from the north edge
    path = ReturnPlanner(mission).plan(*start, HOME)
    assert path is not None and path.leaves_zone
    out = path.points[0]
    assert distance(*at(50, 0), *out) == pytest.approx(10 + 2 + MARGIN_M, abs=0.3)  # on the grown ring
    assert distance(*start, *out) < 10.0  # north, the near side: not round the far side
    assert clearance_m(mission, out, path.points[1:]) >= 2.0


def test_no_way_home_is_none():
    ring = "".join(circle(f"rock-{k}", 100 + 30 * np.sin(k * np.pi / 8), 30 * np.cos(k * np.pi / 8), 8) for k in range(16))
    assert ReturnPlanner(lake(ring)).plan(*at(100, 0), HOME) is None  # walled in by rocks


def test_the_benchmarks_return_round_100_zones_keeps_clear_of_every_one():
    mission = scattered_mission(100)
    start = bench_at(420.0, 420.0)
    path = ReturnPlanner(mission).plan(*start, (mission.home.lat, mission.home.lon))
    assert path is not None and not path.straight
    zones = Zones(mission, Plane(start))
    xy = zones.plane.xy([p[0] for p in (start, *path.points)], [p[1] for p in (start, *path.points)])
    gap = min(float(shapely.distance(shapely.linestrings(xy), a.shape)) for a in zones.keep_out)
    assert gap >= mission.limits.acceptance_radius_m - 0.01
