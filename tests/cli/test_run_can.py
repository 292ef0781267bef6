"""`executive run --can`: the base's bus read and driven during a run, and recorded with --can-log."""

from __future__ import annotations

import can

from executive.cli import main
from tests_support import mission_text, run_in_lockstep

MISSION = mission_text("short", "{lat: -35.3631710, lon: 149.1652300}", simulator="{model: bunker, ekf_ready_after_s: 2}")


def test_the_drive_bridge_talks_to_the_base_and_the_bus_is_recorded(tmp_path, capsys, monkeypatch):
    """In this process: what it checks is on the bus and in the log, nothing a process of its own would show."""
    mission, log = tmp_path / "short.yaml", tmp_path / "bus.log"
    mission.write_text(MISSION)
    argv = ["run", str(mission), "--speedup", "10", "--socket", "none", "--can", "virtual:run-can", "--can-log", str(log)]
    run_in_lockstep(monkeypatch)
    assert main(argv) == 0, capsys.readouterr().err
    frames = list(can.LogReader(str(log)))
    ids = {f.arbitration_id for f in frames}
    assert {0x421, 0x111} <= ids  # control-mode select and motion commands, as the base wants them
    commands = [f for f in frames if f.arbitration_id == 0x111]
    moving = [f for f in commands if any(f.data[:4])]
    assert moving, "the bridge forwarded the autopilot's skid-steer outputs while driving"
    selects = [f for f in frames if f.arbitration_id == 0x421]
    assert len(selects) == len(commands)  # each command goes with its control-mode select
    # the 50 Hz of vehicle time is proven in lock-step (test_can_closed_loop): here the wall clock would judge the machine's load


def test_bad_can_arguments_are_refused(tmp_path, capsys):
    mission = tmp_path / "short.yaml"
    mission.write_text(MISSION)
    assert main(["run", str(mission), "--socket", "none", "--can", "nonsense"]) == 2
    assert "--can:" in capsys.readouterr().err
    assert main(["run", str(mission), "--socket", "none", "--can-log", str(tmp_path / "x.log")]) == 2
    assert "--can-log needs --can" in capsys.readouterr().err
