"""The route check every door runs (issue 40): 1,000 waypoints against 100 keep-out zones, the worst of several runs; and the
planner of a return around 100 zones (a failsafe's return is planned in the tick the failsafe starts).

It runs at validate, start, ``ctl upload`` and after every route edit, so it has a route edit's budget: 50 ms.
"""

from __future__ import annotations

import math
import time

from benchmarks.common import HOME, Row
from executive.mission.model import Mission
from executive.mission.return_path import ReturnPlanner
from executive.mission.rules import cross_field_errors
from executive.mission.zones import route_errors
from executive.world.geo import destination

TARGET_S = 0.050
#: A return is planned once, in the tick its failsafe starts: one tick at the executive's 10 Hz.
PLAN_TARGET_S = 0.100


def at(north_m: float, east_m: float) -> tuple[float, float]:
    lat, lon = destination(HOME[0], HOME[1], 0.0, north_m)
    return destination(lat, lon, 90.0, east_m)


def grid_mission(legs: int = 1000, zones: int = 100) -> Mission:
    """A lawnmower of ``legs`` legs (1 km lines 10 m apart) with ``zones`` keep-out circles between its lines: no leg crosses one."""
    waypoints = []
    for i in range(legs + 1):
        lat, lon = at(10.0 * (i // 2), 1000.0 * ((i // 2 + i) % 2))
        waypoints.append({"lat": lat, "lon": lon})
    keep_out = []
    for k in range(zones):
        lat, lon = at(10.0 * (k % 500) + 5.0, 50.0 + 9.0 * (k // 500))
        keep_out.append({"circle": {"lat": lat, "lon": lon, "radius_m": 1.0}})
    doc = {"version": 1, "name": "grid", "vehicle": "boat", "home": {"lat": HOME[0], "lon": HOME[1]}, "geofence": {"keep_out": keep_out}}
    return Mission.model_validate(doc | {"waypoints": waypoints, "limits": {"acceptance_radius_m": 0.5}})


def _worst(check: object, mission: Mission, repeats: int) -> float:
    """The worst CPU time of ``repeats`` runs: on a shared 2-core bench the wall clock measures the neighbours (the load column)."""
    worst = 0.0
    for _ in range(repeats):
        t0 = time.process_time()
        check(mission)  # type: ignore[operator]
        worst = max(worst, time.process_time() - t0)
    return worst


def run(legs: int = 1000, zones: int = 100, repeats: int = 20) -> list[Row]:
    """The zones check alone and every rule of the mission file, each the worst of ``repeats``."""
    mission = grid_mission(legs, zones)
    if route_errors(mission):
        raise RuntimeError("the benchmark route crosses its own zones")
    target = f"<= {TARGET_S * 1000:g} ms"
    zones_s, all_s = _worst(route_errors, mission, repeats), _worst(cross_field_errors, mission, repeats)
    what = f"{legs} legs x {zones} keep-out zones, worst CPU time of {repeats}"
    return [
        Row("route", "route check: legs x zones (shapely)", round(zones_s * 1000, 1), "ms", target, zones_s <= TARGET_S, what),
        Row(
            "route",
            "route check: every mission rule",
            round(all_s * 1000, 1),
            "ms",
            target,
            all_s <= TARGET_S,
            what + "; the rules a route edit runs",
        ),
        return_plan_row(zones, repeats),
    ]


def scattered_mission(zones: int = 100) -> Mission:
    """``zones`` keep-out circles (8 m) on a square grid 40 m apart between home and a vehicle at the far corner, one rally point."""
    side = math.ceil(math.sqrt(zones))
    keep_out = []
    for k in range(zones):
        lat, lon = at(20.0 + 40.0 * (k // side), 20.0 + 40.0 * (k % side) + (10.0 if (k // side) % 2 else 0.0))
        keep_out.append({"circle": {"lat": lat, "lon": lon, "radius_m": 8.0}})
    rally_lat, rally_lon = at(-30.0, 20.0 * side)
    doc = {"version": 1, "name": "scattered", "vehicle": "boat", "home": {"lat": HOME[0], "lon": HOME[1]}, "geofence": {"keep_out": keep_out}}
    return Mission.model_validate(doc | {"waypoints": [{"lat": HOME[0], "lon": HOME[1]}], "rally_points": [{"lat": rally_lat, "lon": rally_lon}]})


def return_plan_row(zones: int = 100, repeats: int = 20) -> Row:
    """The planner's time for a return from the far corner of :func:`scattered_mission`, around its zones: the worst of ``repeats``."""
    mission = scattered_mission(zones)
    side = math.ceil(math.sqrt(zones))
    lat, lon = at(40.0 * side + 20.0, 40.0 * side + 20.0)
    planner = ReturnPlanner(mission)
    worst, path = 0.0, None
    for _ in range(repeats):
        t0 = time.process_time()
        path = planner.plan(lat, lon, HOME)
        worst = max(worst, time.process_time() - t0)
    if path is None or (path.straight and zones >= 100):
        raise RuntimeError("the benchmark return goes around nothing")
    what = f"around {zones} keep-out circles to the nearest of home and a rally point, {path.describe()}; worst CPU time of {repeats}"
    return Row(
        "route",
        "return path around the zones (A*, visibility graph)",
        round(worst * 1000, 1),
        "ms",
        f"<= {PLAN_TARGET_S * 1000:g} ms",
        worst <= PLAN_TARGET_S,
        what,
    )
