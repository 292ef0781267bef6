"""``executive import`` and ``executive export``: a ground-station plan imported, validated, run in the simulator, exported back."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission

ROOT = Path(__file__).parents[2]
PLANS = ROOT / "tests" / "data" / "plans"
ROVER_BLOCK = PLANS / "rover_block.plan"  # a ~100 m block for a rover, with a fence and a rally point
CMAC = PLANS / "cmac_rover.waypoints"


def route(plan: dict[str, Any]) -> list[tuple[float, float, float, float | None]]:
    """Each waypoint of a plan (lat, lon, alt, speed in force)."""
    out, speed = [], None
    for item in plan["mission"]["items"]:
        if item["command"] == 178:
            speed = item["params"][1]
        elif item["command"] == 16:
            out.append((*item["params"][4:7], speed))
    return out


def test_a_plan_imported_validates_runs_to_completed_and_exports_back_equal(tmp_path, capsys, lockstep):
    mission = tmp_path / "block.yaml"
    assert main(["import", str(ROVER_BLOCK), "-o", str(mission), "--auto-arm"]) == 0
    err = capsys.readouterr().err
    assert f"{ROVER_BLOCK}:111:13: mission.items[4]: not imported: NAV_RETURN_TO_LAUNCH (20)" in err  # said where, not dropped
    assert "rallyPoints" not in err  # the rally point is the mission's now
    assert main(["validate", str(mission)]) == 0
    assert capsys.readouterr().out == f"{mission}: ok (3 waypoints, vehicle rover, tree waypoints)\n"

    outcome = lockstep(load_mission(mission), mission_dir=mission.parent).run_to_end(limit_s=900)  # the simulator `run` starts
    assert (outcome.status, outcome.reason) == (MissionStatus.COMPLETED, "every waypoint reached")

    exported = tmp_path / "block.plan"
    assert main(["export", str(mission), "-o", str(exported)]) == 0  # the format from the suffix
    assert capsys.readouterr().err == ""  # nothing this mission holds is lost on the way
    original, again = json.loads(ROVER_BLOCK.read_text()), json.loads(exported.read_text())
    assert route(again) == route(original)  # exactly: JSON, YAML and back keep every bit of a float
    assert again["mission"]["plannedHomePosition"][:2] == original["mission"]["plannedHomePosition"][:2]
    assert again["mission"]["vehicleType"] == original["mission"]["vehicleType"] == 10
    assert again["geoFence"]["polygons"] == original["geoFence"]["polygons"]
    assert again["rallyPoints"] == original["rallyPoints"]  # as QGroundControl wrote it, both ways


def test_a_waypoints_file_needs_the_vehicle_and_prints_the_mission_without_o(capsys):
    assert main(["import", str(CMAC)]) == 2
    assert capsys.readouterr().err == f"{CMAC}:1:1: (header): a .waypoints file does not say which vehicle it is for: pass --vehicle\n"
    assert main(["import", str(CMAC), "--vehicle", "rover", "--name", "cmac loop"]) == 0
    out, err = capsys.readouterr()
    assert "\nname: cmac loop\nvehicle: rover\n" in out
    assert f"{CMAC}:8:1: item[6]: not imported: DO_SET_SERVO (183)" in err and err.count("(warning)") == 2


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("broken.plan", '{\n    "fileType": "Plan"\n    "mission": {}\n}\n', "broken.plan:3:5: (json): Expecting ',' delimiter"),
        ("old.waypoints", "QGC WPL 100\n", "old.waypoints:1:1: (header): expected 'QGC WPL 110' on the first line"),
        (
            "bad.waypoints",
            "QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t-35.36\t149.16\t584\t1\n1\t0\t3\t16\t0\t0\t0\t0\tnorth\t149.16\t0\t1\n",
            "bad.waypoints:3:18: item[1].latitude: expected a number, got 'north'",
        ),
    ],
)
def test_bad_input_is_located_and_exits_2(tmp_path, capsys, name, text, expected):
    path = tmp_path / name
    path.write_text(text)
    assert main(["import", str(path), "--vehicle", "rover", "-o", str(tmp_path / "out.yaml")]) == 2
    assert capsys.readouterr().err.startswith(f"{tmp_path}/{expected}")
    assert not (tmp_path / "out.yaml").exists()


def test_export_says_what_the_format_cannot_carry_where_the_mission_has_it(tmp_path, capsys):
    mission = tmp_path / "fenced.yaml"
    mission.write_text(
        "version: 1\nname: fenced\nvehicle: rover\nhome: {lat: 47.0, lon: 8.0}\n"
        "geofence:\n  max_distance_from_home_m: 300\n"
        "waypoints:\n  - {lat: 47.001, lon: 8.0, name: gate}\n"
    )
    assert main(["export", str(mission), "--format", "waypoints"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("QGC WPL 110\n0\t1\t0\t16\t")
    assert err.splitlines() == [
        f"{mission}:6:3: geofence: not exported: a .waypoints file has no geofence (warning)",
        f"{mission}:8:35: waypoints[0].name: not exported: a mission item has no name (warning)",
    ]


def test_what_a_plan_cannot_hold_is_said_once_for_every_waypoint_it_concerns(capsys):
    """Issue 28: the project's own boat_survey.yaml exported as a .plan printed nine warnings, one per waypoint name and the heading."""
    survey = str(ROOT / "missions" / "boat_survey.yaml")
    assert main(["export", survey, "--format", "plan"]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"{survey}:10:57: home.heading_deg: not exported: a planned home has no heading (warning)",
        f"{survey}:18:48: waypoints[0].name: not exported: a mission item has no name; the same for 7 more (waypoints[1-7].name) (warning)",
    ]


def test_export_needs_a_format_and_a_valid_mission(tmp_path, capsys, minimal_mission):
    assert main(["export", str(minimal_mission)]) == 2
    assert "--format plan|waypoints|btcpp is needed" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nname: x\nvehicle: rover\nwaypoints:\n  - {lat: 95.0, lon: 8.5}\n")
    assert main(["export", str(bad), "--format", "plan"]) == 2
    assert f"{bad}:5:11: waypoints[0].lat:" in capsys.readouterr().err


def test_an_import_without_auto_arm_says_the_mission_will_wait_for_arming_on_stderr_and_in_its_header(tmp_path, capsys):
    mission = tmp_path / "cmac.yaml"
    assert main(["import", str(CMAC), "--vehicle", "rover", "-o", str(mission)]) == 0
    note = f"{CMAC}: The mission waits for a person to arm the vehicle (`executive ctl arm`, a ground station); import with --auto-arm"
    assert note in capsys.readouterr().err
    header = [line for line in mission.read_text().splitlines() if line.startswith("#")]
    assert any("waits for a person to arm the vehicle" in line for line in header), header
    assert main(["import", str(CMAC), "--vehicle", "rover", "-o", str(mission), "--auto-arm"]) == 0
    assert "arm the vehicle" not in capsys.readouterr().err and "arm the vehicle" not in mission.read_text()


def test_a_file_of_another_kind_is_named_for_what_import_takes(tmp_path, capsys):
    """Issue 43: `executive import lake.yaml` said `(json): Expecting value`."""
    lake = tmp_path / "lake.yaml"
    lake.write_text("version: 1\nname: lake\nvehicle: boat\nwaypoints: []\n")
    assert main(["import", str(lake)]) == 2
    assert capsys.readouterr().err == (
        f"{lake}:1:1: (file): not a file import reads: it takes a QGroundControl .plan (JSON), a Mission Planner .waypoints "
        "(QGC WPL 110; .txt, .mission) or a BehaviorTree.CPP / Groot2 tree (.xml)\n"
    )
