"""A crash loses nothing: kill -9 mid-mission, run again with --resume, every sample recorded exactly once."""

from __future__ import annotations

import json
import signal
import subprocess
from pathlib import Path
from typing import Any

import pytest

from executive.cli import main
from executive.cli.run import _resume_text
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.observers.journal import Journal, journal_recorder
from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
from executive.world import blackboard
from executive.world.clock import Clock, ManualClock
from executive.world.state import SamplerState
from tests_support import executive_process, run_in_lockstep

ROOT = Path(__file__).parents[2]
MISSION = ROOT / "missions" / "asv_sampling.yaml"
#: The simulated EKF is ready after 2 s in the lock-step runs, not the firmware's 40: what they check comes once the vehicle moves.
EKF_READY_S = 2.0


#: The ASV mission's first sample point 7 m from home, not 60 m (the run is killed after its sample); the second 60 m on, as in the mission.
NEAR_FIRST_SAMPLE = """\
simulator: {ekf_ready_after_s: 2}
waypoints:
  - {lat: -35.2960000, lon: 149.1130550, name: channel-entry}
  - {lat: -35.2959550, lon: 149.1130550, name: inlet, sample: true}
  - {lat: -35.2959550, lon: 149.1133848, name: channel-bend}
  - {lat: -35.2962254, lon: 149.1133848, name: outlet, sample: true}
"""


def run(mission: Path, *args: str) -> subprocess.Popen:
    """``executive run`` at 40x, its clock held once the first sample is recorded (tests/held_clock.py): the run cannot go on
    before this test has read that status line and killed it, however busy the machine (at 10x unheld, the ~50 s of vehicle time
    left were 5 s of wall time to do it in; at 40x, 1.2 s was too little beside two busy loops)."""
    command = ("run", str(mission), "--speedup", "40", "--socket", "none", *args)
    return executive_process(*command, via=("held_clock.py", "sampled"), stdout=subprocess.PIPE)


def report(db: Path, run_id: int, capsys) -> dict:
    assert main(["report", str(db), "--run", str(run_id), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_kill_9_then_resume_finishes_with_every_sample_recorded_once(tmp_path, capsys, monkeypatch):
    """From the command line: a real SIGKILL after the first sample, then ``run --resume`` (each crash moment: the lock-step test below)."""
    db, snapshots, mission = tmp_path / "journal.db", tmp_path / "run.snap", tmp_path / "asv.yaml"
    # the ASV mission with an EKF ready after 2 s (not 40), no EKF dropout and its first sample point near: the crash is what this test is about
    text = MISSION.read_text()
    mission.write_text(text[: text.index("simulator:\n")] + NEAR_FIRST_SAMPLE)
    first = run(mission, "--journal", str(db), "--snapshots", str(snapshots))
    assert first.stdout is not None
    for line in first.stdout:  # killed as soon as the first sample is on the disk: the run must not reach its end first
        if json.loads(line)["samples"] == 1:
            break
    else:
        pytest.fail("no sample was taken")
    first.send_signal(signal.SIGKILL)
    first.communicate(timeout=30)
    assert first.returncode == -signal.SIGKILL

    crashed = report(db, 1, capsys)
    assert crashed["outcome"] is None  # it never ended
    assert len(crashed["samples"]) in (1, 2)

    # the resumed run in this process (what is resumed is in the journal; nothing here needs a process of its own), lock-step
    run_in_lockstep(monkeypatch)
    code = main(["run", str(mission), "--speedup", "40", "--socket", "none", "--journal", str(db), "--resume"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "resuming run 1 at waypoint" in err
    assert "2 samples recorded" in err

    resumed = report(db, 2, capsys)
    assert (resumed["resumed_from"], resumed["outcome"]) == (1, "COMPLETED")
    waypoints = [s["waypoint"] for s in crashed["samples"]] + [s["waypoint"] for s in resumed["samples"]]
    assert sorted(waypoints) == [2, 4]  # each sample point exactly once, across the crash
    assert all(len(s["reads"]) == 40 for s in crashed["samples"] + resumed["samples"])  # 10 s x 1 Hz x 4 sensors


@pytest.mark.parametrize(
    ("samples_before", "after_s"),
    [(0, 3.0), (1, 0.0), (1, 20.0)],
    ids=["during the first sample", "at the first sample", "20 s after it"],
)
def test_a_crash_at_any_moment_then_resume_records_every_sample_once(tmp_path, capsys, lockstep, samples_before, after_s):
    """The run stops dead (never ticked again, its journal never closed) ``after_s`` of vehicle time after its
    ``samples_before``-th sample (0: after the sonde started its first reads); a second run resumes from the journal."""
    db, mission = tmp_path / "journal.db", load_mission(MISSION)
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(db, clock))
        return {"plugs": [journal_recorder(journals[-1])]}

    first = lockstep(mission, mission_dir=MISSION.parent, options_for_clock=journal_plug, ekf_ready_after_s=EKF_READY_S)
    state = first.runtime.mission_state
    moment: list[float] = []

    def crash_now() -> bool:
        sampler = blackboard.value("/sampler/status")
        sampling = sampler is not None and sampler.state is SamplerState.SAMPLING
        reached = len(state.sample_log.taken) >= samples_before and (samples_before > 0 or sampling)
        if reached and not moment:
            moment.append(first.clock.now())
        return bool(moment) and first.clock.now() >= moment[0] + after_s

    assert first.run(limit_s=600, until=crash_now) is None
    crashed = report(db, 1, capsys)
    assert crashed["outcome"] is None and len(crashed["samples"]) == samples_before

    second = lockstep(mission, mission_dir=MISSION.parent, options_for_clock=journal_plug, ekf_ready_after_s=EKF_READY_S)
    resume = journals[1].resume_point(mission)
    assert resume is not None and resume.run == 1
    assert _resume_text(resume).startswith(f"resuming run 1 at waypoint {resume.leg_index + 1} with {samples_before} sample(s) already taken")
    outcome = second.run(limit_s=600, resume=resume)
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED
    journals[1].close()

    resumed = report(db, 2, capsys)
    assert (resumed["resumed_from"], resumed["outcome"]) == (1, "COMPLETED")
    first = resumed["transitions"][0]  # issue 43: it said "started from the first waypoint"
    assert (first["after"], first["reason"]) == ("RUNNING", f"resumed at waypoint {resume.leg_index + 1} of 4 (run 1 was unfinished)")
    waypoints = [s["waypoint"] for s in crashed["samples"]] + [s["waypoint"] for s in resumed["samples"]]
    assert sorted(waypoints) == [2, 4]  # each sample point exactly once, across the crash
    assert all(len(s["reads"]) == 40 for s in crashed["samples"] + resumed["samples"])  # 10 s x 1 Hz x 4 sensors


def test_resume_without_an_unfinished_run_starts_from_the_first_waypoint(tmp_path, lockstep):
    asv = load_mission(MISSION)
    mission = asv.model_copy(update={"waypoints": asv.waypoints[:2]})  # to its first sample point: a whole run, shorter
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(tmp_path / "journal.db", clock))
        return {"plugs": [journal_recorder(journals[0])]}

    sim = lockstep(mission, mission_dir=MISSION.parent, options_for_clock=journal_plug, ekf_ready_after_s=EKF_READY_S)
    resume = journals[0].resume_point(mission)
    assert "nothing to resume" in _resume_text(resume)  # what `run --resume` says before it starts
    outcome = sim.run_to_end(limit_s=3600)
    journals[0].close()
    assert outcome.status is MissionStatus.COMPLETED


def test_resume_needs_a_journal(capsys):
    assert main(["run", str(MISSION), "--resume"]) == 2
    assert "--resume needs --journal DB" in capsys.readouterr().err


def test_report_of_a_missing_or_broken_journal_is_bad_input(tmp_path, capsys):
    """A database has no line and column to point at (issue 28: `/tmp/nonexist.db:1:1: (file): no such journal`)."""
    assert main(["report", str(tmp_path / "none.db")]) == 2
    assert capsys.readouterr().err == f"executive: report: {tmp_path / 'none.db'}: no such journal\n"
    broken = tmp_path / "broken.db"
    broken.write_bytes(b"this is not sqlite" * 100)
    assert main(["report", str(broken)]) == 2
    assert capsys.readouterr().err == f"executive: report: {broken}: not a journal: file is not a database\n"
    empty = tmp_path / "empty.db"
    Journal(empty, ManualClock()).close()
    assert main(["report", str(empty)]) == 2
    assert capsys.readouterr().err == f"executive: report: {empty}: no run recorded\n"


def test_replay_shows_the_recorded_tree(tmp_path, capsys, lockstep):
    snapshots = tmp_path / "run.snap"
    recorder = SnapshotRecorder(snapshots)
    sim = lockstep(load_mission(ROOT / "missions/rover_square.yaml"), plugs=[snapshot_recorder(recorder)], ekf_ready_after_s=EKF_READY_S)
    assert sim.run_to_end(limit_s=600).status is MissionStatus.COMPLETED
    recorder.close()
    assert main(["replay", str(snapshots), "--tick", "500"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("tick 500 at")
    assert "Go to waypoint -- leg" in out  # the leg being driven at that tick, with its distance
    assert main(["replay", str(snapshots)]) == 0  # the last tick: the run as it ended (issue 28: it showed RUNNING)
    last = capsys.readouterr().out.splitlines()
    assert last[1] == "✓ Mission" and "✓ Hold at the end" in "\n".join(last)
    assert "  /mission/state: 'COMPLETED'" in last and "  /mission/reason: 'every waypoint reached'" in last


def test_a_route_edited_before_a_crash_is_the_route_resumed(tmp_path, capsys, lockstep):
    db = tmp_path / "journal.db"
    square = load_mission(ROOT / "missions" / "rover_square.yaml")
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(db, clock))
        return {"plugs": [journal_recorder(journals[-1])]}

    first = lockstep(square, options_for_clock=journal_plug, ekf_ready_after_s=EKF_READY_S)
    assert first.run(limit_s=600, until=lambda: first.runtime.mission_state.legs.leg_index >= 1) is None  # heading for waypoint 2 of 4
    assert first.runtime.operator.request("route", source="ctl", operation="remove", waypoint=3).ok  # on the disk before the reply
    # the crash: the first run is never ticked again and never ends

    second = lockstep(square, options_for_clock=journal_plug, ekf_ready_after_s=EKF_READY_S)
    resume = journals[1].resume_point(square)
    assert _resume_text(resume) == "resuming run 1 at waypoint 2 with 0 sample(s) already taken, on its route as last edited (3 waypoints)"
    outcome = second.run(limit_s=600, resume=resume)
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED
    journals[1].close()
    crashed, resumed = report(db, 1, capsys), report(db, 2, capsys)
    assert [r["waypoints"] for r in crashed["routes"]] == [3]
    assert [r["waypoints"] for r in resumed["routes"]] == [3]  # restored, and recorded again for the next crash
    assert resumed["outcome"] == "COMPLETED"
    assert [(leg["waypoint"], leg["waypoints"]) for leg in resumed["legs"]] == [(2, 3), (3, 3), (None, 3)]  # 2 and 3 of the edited route, done
