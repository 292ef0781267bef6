"""``executive validate``: exit codes, ``FILE:LINE:COL: FIELD: message`` on stderr, ``--json``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from executive.cli import main

BROKEN = Path(__file__).parents[1] / "data" / "broken_missions"


#: What validate says of a mission without ``home:`` (issue 40: never silence about the checks left to the vehicle).
NO_HOME = "no home: checked only at start, against the vehicle's position: every waypoint within limits.max_goal_distance_m (5000 m) of the vehicle"


def test_a_good_mission(minimal_mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(minimal_mission)]) == 0
    out, err = capsys.readouterr()
    assert (out, err) == (f"{minimal_mission}: ok (1 waypoint, vehicle rover, tree waypoints)\n", f"{minimal_mission}: warning: {NO_HOME}\n")


def test_a_mission_with_home_is_ok_without_a_warning(minimal_mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    homed = tmp_path / "homed.yaml"
    homed.write_text(minimal_mission.read_text().replace("waypoints:", "home: {lat: 47.3977, lon: 8.5455}\nwaypoints:"), encoding="utf-8")
    assert main(["validate", str(homed)]) == 0
    assert capsys.readouterr() == (f"{homed}: ok (1 waypoint, vehicle rover, tree waypoints)\n", "")


def test_a_bad_mission(capsys: pytest.CaptureFixture[str]) -> None:
    path = BROKEN / "duplicate_key.yaml"
    assert main(["validate", str(path)]) == 2
    out, err = capsys.readouterr()
    assert (out, err) == ("", f"{path}:9:5: waypoints[1].lat: duplicate key (an earlier one is ignored) (waypoint 2)\n")


def test_every_error_of_every_file_and_ok_for_the_good_ones(minimal_mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(minimal_mission.read_text().replace("lat: 47.397742", "lat: 95.0").replace("rover", "car"), encoding="utf-8")
    assert main(["validate", str(bad), str(minimal_mission), str(tmp_path / "missing.yaml")]) == 2
    out, err = capsys.readouterr()
    assert out == f"{minimal_mission}: ok (1 waypoint, vehicle rover, tree waypoints)\n"
    assert err.splitlines() == [
        f"{bad}:3:10: vehicle: 'car': Input should be 'rover', 'boat', 'sub' or 'vtol'",
        f"{bad}:6:11: waypoints[0].lat: 95.0: Input should be less than or equal to 90 (waypoint 1)",
        f"{minimal_mission}: warning: {NO_HOME}",
        f"{tmp_path / 'missing.yaml'}:1:1: (file): No such file or directory",
    ]


def test_each_broken_mission_reports_its_expected_first_error(capsys: pytest.CaptureFixture[str]) -> None:
    paths = sorted(BROKEN.glob("*.yaml"))
    assert main(["validate", *map(str, paths)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    for path in paths:
        line, column, field = re.fullmatch(r"# expect: (\d+):(\d+) (\S+)", path.read_text().splitlines()[0]).groups()
        first = next(e for e in err.splitlines() if e.startswith(f"{path}:"))
        assert first.startswith(f"{path}:{line}:{column}: {field}: ")


def test_json_lists_a_result_per_file(minimal_mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = BROKEN / "lat_out_of_range.yaml"
    assert main(["validate", "--json", str(minimal_mission), str(bad)]) == 2
    out, err = capsys.readouterr()
    assert err == ""
    assert json.loads(out) == [
        {"file": str(minimal_mission), "ok": True, "waypoints": 1, "vehicle": "rover", "tree": "waypoints", "warnings": [NO_HOME]},
        {
            "file": str(bad),
            "ok": False,
            "errors": [
                {
                    "file": str(bad),
                    "line": 7,
                    "column": 11,
                    "field": "waypoints[0].lat",
                    "message": "95.0: Input should be less than or equal to 90 (waypoint 1)",
                }
            ],
        },
    ]


def test_json_exit_0_when_all_are_good(minimal_mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "--json", str(minimal_mission), str(minimal_mission)]) == 0
    assert [r["ok"] for r in json.loads(capsys.readouterr().out)] == [True, True]


def test_no_mission_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate"]) == 2
    assert "the following arguments are required: MISSION" in capsys.readouterr().err


def test_a_waypoint_out_of_reach_of_home_is_refused_with_its_distance(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 28: 10 km from home passed `validate` and was driven toward; the rule (5 km, a sub's 1 km) holds against `home:`."""
    far = tmp_path / "far.yaml"
    far.write_text(
        "version: 1\nname: far\nvehicle: rover\nhome: {lat: -35.363261, lon: 149.165230}\nlimits: {leg_timeout_s: 3000}\nwaypoints:\n"
        "  - {lat: -35.3629906, lon: 149.1652300}\n  - {lat: -35.2730000, lon: 149.1652300, name: town}\n",
        encoding="utf-8",
    )
    sub = tmp_path / "sub.yaml"
    sub.write_text(
        "version: 1\nname: deep\nvehicle: sub\nhome: {lat: 44.095, lon: 9.863}\nlimits: {leg_timeout_s: 3000}\n"
        "waypoints:\n  - {lat: 44.1085, lon: 9.863}\n"
    )
    near = tmp_path / "near.yaml"  # no home: nothing to measure against until the vehicle's position (at upload, at start)
    near.write_text(far.read_text().replace("home: {lat: -35.363261, lon: 149.165230}\n", ""), encoding="utf-8")
    assert main(["validate", str(far), str(sub), str(near)]) == 2
    out, err = capsys.readouterr()
    assert err.splitlines() == [
        f"{far}:8:5: waypoints[1]: 10014 m from home, over limits.max_goal_distance_m (5000 m): refused at start with the vehicle at home"
        " (waypoint 2, 'town')",
        f"{sub}:7:5: waypoints[0]: 1500 m from home, over limits.max_goal_distance_m (1000 m): refused at start with the vehicle at home"
        " (waypoint 1)",
        f"{near}: warning: {NO_HOME}",
    ]
    assert out == f"{near}: ok (2 waypoints, vehicle rover, tree waypoints)\n"


def test_validate_says_what_it_can_of_the_energy_without_a_vehicle(minimal_mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # about 860 m from its waypoint: a leg_timeout_s that 860 m at 5 m/s fits (issue 40 refuses a leg that can only time out)
    text = minimal_mission.read_text() + "home: {lat: 47.39, lon: 8.5456}\nlimits: {leg_timeout_s: 300}\n"
    judged, fits, short = (tmp_path / f"{name}.yaml" for name in ("judged", "fits", "short"))
    judged.write_text(text + "energy: {nominal_v: 11.1}\n", encoding="utf-8")
    fits.write_text(text + "energy: {capacity_wh: 100}\n", encoding="utf-8")
    short.write_text(text + "energy: {capacity_wh: 100, wh_per_km: 100000}\n", encoding="utf-8")
    assert main(["validate", str(judged), str(fits)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith("; energy: judged on the vehicle (its capacity from the autopilot's BATT_CAPACITY or BAT1_CAPACITY)")
    assert re.search(r"; energy: needs [0-9.]+ Wh \+ [0-9.]+ Wh home \(\+/- [0-9.]+\), has 80 Wh above the 20 % reserve on a full pack", out[1])
    assert main(["validate", str(short)]) == 2
    assert re.match(rf"{re.escape(str(short))}:\d+:\d+: energy: the route and the way home do not fit a full pack: needs ", capsys.readouterr().err)


def test_a_leg_across_a_keep_out_zone_is_refused_exit_2_named_and_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 40: both waypoints outside the pier, the leg between them across it (PX4-Autopilot issue 22362's hole)."""
    lake = tmp_path / "lake.yaml"
    lake.write_text(
        "version: 1\nname: lake\nvehicle: boat\nhome: {lat: 47.3977, lon: 8.5456}\ngeofence:\n  keep_out:\n"
        "    - {name: pier, circle: {lat: 47.3985, lon: 8.5456, radius_m: 8}}\nwaypoints:\n"
        "  - {lat: 47.3978, lon: 8.5456, name: line-2-start}\n  - {lat: 47.3992, lon: 8.5456, name: line-2-end}\n",
        encoding="utf-8",
    )
    assert main(["validate", str(lake)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    leg = "waypoints[0] -> waypoints[1] ('line-2-start' -> 'line-2-end')"
    assert err == f"{lake}:10:5: waypoints[1]: {leg}: crosses keep-out zone 'pier' for 16 m (waypoint 2, 'line-2-end')\n"


def test_one_waypoint_is_said_in_the_singular(minimal_mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(minimal_mission)]) == 0
    assert capsys.readouterr().out == f"{minimal_mission}: ok (1 waypoint, vehicle rover, tree waypoints)\n"
