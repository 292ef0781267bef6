"""Mission Planner's fence and rally files imported with a route: QGC WPL 110 Fence/Rally plans, .fen/.poly points, .rally lines."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.cli import main
from executive.mission.errors import MissionError
from executive.mission.formats.plan_files import import_file

CMAC = Path(__file__).parents[1] / "data" / "plans" / "cmac_rover.waypoints"  # a 25 m square north-east of home -35.363262, 149.165237


def wpl(*rows: tuple[int, float, float, float, float]) -> str:
    """A QGC WPL 110 file as Mission Planner saves a Fence or Rally plan: home first, then (command, param1, lat, lon, alt) rows."""
    lines = ["QGC WPL 110", "0\t1\t0\t16\t0\t0\t0\t0\t-35.363262\t149.165237\t584.09\t1"]
    lines += [f"{i}\t0\t0\t{c}\t{p1:.8f}\t0\t0\t0\t{lat:.8f}\t{lon:.8f}\t{alt:.6f}\t1" for i, (c, p1, lat, lon, alt) in enumerate(rows, start=1)]
    return "\n".join(lines) + "\n"


INCLUSION = [(-35.3636, 149.1648), (-35.3624, 149.1648), (-35.3624, 149.1662), (-35.3636, 149.1662)]
PIER = [(-35.3631, 149.1649), (-35.3630, 149.1649), (-35.3630, 149.1650), (-35.3631, 149.1650)]
FENCE_PLAN = wpl(
    *[(5001, 4, lat, lon, 0) for lat, lon in INCLUSION],
    *[(5002, 4, lat, lon, 0) for lat, lon in PIER],
    (5004, 5, -35.3632, 149.1660, 0),
)
RALLY_PLAN = wpl((5100, 0, -35.3634, 149.1652, 0), (5100, 0, -35.3626, 149.1652, 0))


def write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_mission_planners_fence_and_rally_plans_become_the_missions_zones_and_rally_points(tmp_path: Path) -> None:
    fence, rally = write(tmp_path, "zones.waypoints", FENCE_PLAN), write(tmp_path, "rally.waypoints", RALLY_PLAN)
    mission = import_file(CMAC, vehicle="rover", zone_files=[fence, rally]).mission
    geofence = mission.geofence
    assert geofence is not None
    assert [(v.lat, v.lon) for v in geofence.polygon or []] == INCLUSION
    assert [(v.lat, v.lon) for v in geofence.keep_out[0].polygon or []] == PIER
    circle = geofence.keep_out[1].circle
    assert circle is not None and (circle.lat, circle.lon, circle.radius_m) == (-35.3632, 149.1660, 5)
    assert [(p.lat, p.lon) for p in mission.rally_points] == [(-35.3634, 149.1652), (-35.3626, 149.1652)]
    assert len(mission.waypoints) == 5  # the route is the imported file's


def test_the_older_fen_and_rally_files_with_what_they_cannot_carry_said_where_it_is(tmp_path: Path) -> None:
    corners = [f"{lat} {lon}" for lat, lon in INCLUSION]
    points = ["#saved by Mission Planner 1.3.82", "-35.363262 149.165237", *corners, corners[0]]  # the return point first, closed
    fen = write(tmp_path, "area.fen", "\n".join(points) + "\n")
    ral = write(tmp_path, "home.rally", "RALLY -35.3634 149.1652 20 40 0 0\nRALLY\t-35.3626\t149.1652\t30\t0\t0\t0\n")
    imported = import_file(CMAC, vehicle="rover", zone_files=[fen, ral])
    assert imported.mission.geofence is not None
    assert [(v.lat, v.lon) for v in imported.mission.geofence.polygon or []] == INCLUSION  # the return point and the closing point dropped
    assert [(p.lat, p.lon, p.alt_m) for p in imported.mission.rally_points] == [(-35.3634, 149.1652, 20), (-35.3626, 149.1652, 30)]
    said = {(w.file, w.line): w.message for w in imported.warnings}
    assert said[(fen, 2)] == "the fence's return point is not imported: a return goes to a rally point or home"
    assert said[(ral, 1)].startswith("break altitude, landing direction and flags not imported")


def test_a_polygon_short_of_its_corner_count_is_refused_in_the_fence_file(tmp_path: Path) -> None:
    fence = write(tmp_path, "bad.waypoints", wpl(*[(5002, 4, lat, lon, 0) for lat, lon in PIER[:3]]))
    with pytest.raises(MissionError) as refused:
        import_file(CMAC, vehicle="rover", zone_files=[fence])
    [error] = refused.value.errors
    assert (error.file, error.line, error.field) == (fence, 3, "item[1].param1")
    assert error.message == "a fence polygon of 4 corners (param1) has 3 vertex items here"


def test_executive_import_takes_zone_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fence, out = write(tmp_path, "zones.waypoints", FENCE_PLAN), tmp_path / "m.yaml"
    assert main(["import", str(CMAC), "--vehicle", "rover", "--zones", fence, "-o", str(out)]) == 0
    assert "keep_out:" in out.read_text() and "pier" not in out.read_text()
