"""``autopilot:`` in a mission and ``run --autopilot``: what the chosen firmware cannot fly is refused with the reason, before anything starts."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest

from executive.cli import main
from tests_support import executive_process

SUB_ON = """version: 1
name: sub
vehicle: sub
autopilot: {autopilot}
waypoints:
  - {{lat: 47.0, lon: 8.0, depth_m: 2}}
"""


def test_validate_refuses_a_sub_on_px4_naming_the_field(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "sub.yaml"
    path.write_text(SUB_ON.format(autopilot="px4"), encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    assert capsys.readouterr().err == f"{path}:4:12: autopilot: px4 drives rover, vtol here, not a sub\n"


def test_validate_refuses_the_rc_route_tree_on_px4(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "route.yaml"
    path.write_text("version: 1\nname: r\nvehicle: rover\nautopilot: px4\ntree: ugv_rc_route\nrc_route: {}\nwaypoints: []\n", encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    assert "autopilot: tree ugv_rc_route needs ArduPilot" in capsys.readouterr().err


def test_validate_takes_a_vtol_on_px4(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (Path(__file__).parents[2] / "missions" / "vtol_transit.yaml").read_text(encoding="utf-8")
    path = tmp_path / "vtol.yaml"
    path.write_text(text.replace("vehicle: vtol\n", "vehicle: vtol\nautopilot: px4\n"), encoding="utf-8")
    assert main(["validate", str(path)]) == 0


def test_run_with_autopilot_px4_refuses_a_sub_before_starting_a_vehicle(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "sub.yaml"
    path.write_text(SUB_ON.format(autopilot="ardupilot"), encoding="utf-8")
    assert main(["run", str(path), "--autopilot", "px4", "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "--autopilot px4: px4 drives rover, vtol here, not a sub" in err
    assert "simulated" not in err  # no vehicle was started


def test_run_with_autopilot_px4_refuses_drive_auto_before_starting_a_vehicle(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "rover.yaml"
    path.write_text("version: 1\nname: r\nvehicle: rover\ndrive: auto\nwaypoints:\n  - {lat: 47.0, lon: 8.0}\n", encoding="utf-8")
    assert main(["validate", str(path)]) == 0
    assert main(["validate", "--autopilot", "px4", str(path)]) == 2
    assert "drive: auto on PX4 flies a vtol's waypoints so far" in capsys.readouterr().err
    assert main(["run", str(path), "--autopilot", "px4", "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "--autopilot px4: drive: auto on PX4 flies a vtol's waypoints so far" in err
    assert "simulated" not in err  # no vehicle was started


def test_run_refuses_drive_auto_of_a_leg_it_cannot_drive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """auv_survey's altitude leg: ArduSub's AUTO holds a height above the seabed only from the sonar (its terrain failsafe)."""
    text = (Path(__file__).parents[2] / "missions" / "auv_survey.yaml").read_text(encoding="utf-8")
    path = tmp_path / "auv.yaml"
    path.write_text(text.replace("tree: auv_survey\n", "tree: auv_survey\ndrive: auto\n"), encoding="utf-8")
    assert main(["run", str(path), "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "auv.yaml:36:78: waypoints[2].control_mode: drive: auto flies a sub's waypoints at their depths" in err
    assert "use control_mode depth, or drive: guided (waypoint 3, 'north-over-seabed')" in err and "simulated" not in err


def test_run_with_autopilot_px4_flies_the_simulated_px4_and_ctrl_c_in_the_take_off_lands_it() -> None:
    """No --mavlink: the built-in simulator runs PX4 (HEARTBEAT autopilot 12, type 22); the tree's GUIDED is OFFBOARD there.

    Ctrl-C as the take-off begins (low, under MPC_LAND_ALT2): made safe in AUTO.LAND, landed and disarmed (issue 44; it hovered
    in AUTO.LOITER before)."""
    # 5x, not 20x: the simulated PX4 is paced by the wall clock beside the executive, and a setpoint gap over COM_OF_LOSS_T (1 s of
    # the vehicle's) is its offboard failsafe: 50 ms of a loaded machine at 20x (it went OFFBOARD -> POSCTL once), 200 ms at 5x
    proc = executive_process(
        "run", "missions/vtol_transit.yaml", "--autopilot", "px4", "--speedup", "5", "--socket", "none", "-v", stdout=subprocess.PIPE
    )
    modes: list[str] = []
    deadline = time.monotonic() + 300
    assert proc.stdout is not None
    while time.monotonic() < deadline and "AUTO.TAKEOFF" not in modes:
        line = proc.stdout.readline()
        if not line:
            break
        mode = json.loads(line).get("mode")
        if mode and (not modes or modes[-1] != mode):
            modes.append(mode)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert modes[:3] == ["AUTO.LOITER", "OFFBOARD", "AUTO.TAKEOFF"], err
    assert "simulated vtol (px4)" in err and "(MAV_TYPE 22)" in err
    assert "vehicle in AUTO.LAND" in err and "executive: the vehicle made safe: landed, disarmed (AUTO.LAND (confirmed)" in err
