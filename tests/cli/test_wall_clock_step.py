"""The wall clock jumps by decades mid-run (a Raspberry Pi without a real-time clock boots in 1970, then NTP or GPS time arrives).

Ticks, timeouts and legs run on the monotonic clock: the step changes none of them (in lock-step, a wall
clock jumping at every read leaves every tick and every byte sent as it was). The log and the journal
keep the run's own clock (``t``) beside the UTC one, so ``executive report`` orders the run right
across the step: under a real ``executive run`` (tests/stepped_wall_clock.py), stepped on the
vehicle's second leg, whatever the machine's speed.
"""

from __future__ import annotations

import re
import sqlite3
import subprocess
import time
from pathlib import Path

import pytest

from executive.cli import main
from tests_support import LINE_HOME, executive_process, line_mission, mission_text, run_recording

ROOT = Path(__file__).parents[2]
YEARS_40_S = 40 * 365.25 * 86400
LEGS = ("{lat: -35.36308, lon: 149.16523}", "{lat: -35.36308, lon: 149.16545}", "{lat: -35.36326, lon: 149.16545}")
RECORD = re.compile(r"^(\d{4})-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z t=(\d+\.\d{3}) executive ", re.MULTILINE)


def test_a_computer_booted_in_1970_gets_its_time_mid_run_and_the_journal_and_log_stay_in_order(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    booted_offset_s, stepped_offset_s = -time.time(), 0.0  # 1970 until NTP (or GPS) time arrives on the second leg
    mission = tmp_path / "m.yaml"
    mission.write_text(mission_text("clock-step", *LEGS))
    step = tmp_path / "step"
    args = ["run", str(mission), "--speedup", "20", "--socket", "none", "--journal", str(tmp_path / "j.db"), "-v"]
    via = ("stepped_wall_clock.py", str(step), str(booted_offset_s))
    with executive_process(*args, via=via, cwd=tmp_path, stdout=subprocess.PIPE) as run:
        assert run.stdout is not None
        for line in run.stdout:  # the status lines (JSON): the step on the way to waypoint 2
            if '"leg": 2' in line and '"state": "RUNNING"' in line and not step.exists():
                step.write_text(str(stepped_offset_s))
        err = run.stderr.read() if run.stderr else ""
        code = run.wait(timeout=120)
    assert step.exists(), "the run never drove its second leg"
    assert code == 0 and err.splitlines()[-1].startswith("executive: mission 'clock-step' COMPLETED: every waypoint reached"), err
    assert "Traceback" not in err
    records = [(int(year), float(t)) for year, t in RECORD.findall(err)]
    years = [year for year, _ in records]
    assert len(set(years)) == 2 and years == sorted(years, reverse=stepped_offset_s < booted_offset_s)  # the UTC stamps jump once
    assert [t for _, t in records] == sorted(t for _, t in records)  # t= keeps the order
    db = sqlite3.connect(tmp_path / "j.db")
    legs = db.execute("SELECT t, wall, leg FROM legs ORDER BY rowid").fetchall()
    assert [leg for _, _, leg in legs] == [0, 1, 2, 3] and [t for t, _, _ in legs] == sorted(t for t, _, _ in legs)
    walls = [wall for _, wall, _ in legs]
    assert abs(walls[2] - walls[0]) > 30 * 365 * 86400  # the journal's UTC jumped between them; its t did not
    assert main(["report", str(tmp_path / "j.db")]) == 0  # the journal read back in this process: its stepped clock is the run's alone
    said = [line.strip() for line in capsys.readouterr().out.splitlines() if "heading for waypoint" in line]
    assert [line.split("] ")[1] for line in said] == [f"heading for waypoint {n} of 3" for n in (1, 2, 3)]


def test_in_lock_step_a_wall_clock_jumping_at_every_read_changes_no_tick_and_no_byte_sent(monkeypatch: pytest.MonkeyPatch) -> None:
    line = line_mission("clock-step")
    mission, boots_at = line_mission("clock-step", waypoints=line.waypoints[:2]), (*LINE_HOME, 0.0)  # two legs: a whole run, shorter
    steady_outcome, _sim, steady = run_recording(mission, boots_at)
    real = time.time
    reads = iter(range(10**9))
    monkeypatch.setattr(time, "time", lambda: real() + (-real(), YEARS_40_S, -YEARS_40_S)[next(reads) % 3])  # 1970, 2066, 1986...
    stepped_outcome, _sim, stepped = run_recording(mission, boots_at)
    assert next(reads) > 10  # the wall clock was read (the log, the journal...) and jumped each time
    assert (stepped_outcome.status, stepped_outcome.reason, stepped_outcome.ticks) == (
        steady_outcome.status,
        steady_outcome.reason,
        steady_outcome.ticks,
    )
    assert [m.to_dict() for m in stepped] == [m.to_dict() for m in steady]
