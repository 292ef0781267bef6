"""The run's last lines, its exit code and the journal's report speak of the mission that ran, with its own outcome.

Issue 28: ``run --wait``, a mission started and COMPLETED, another uploaded (READY), Ctrl-C: the last
line said ``mission 'yard-loop' COMPLETED: every waypoint reached``, of a mission that never ran,
and the report of the run that did carried the other's upload among its state changes.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from executive.autopilot_link.link import NOTHING_TO_MAKE_SAFE
from executive.cli import EXIT_OK, main
from executive.cli.run import exit_code, last_words
from executive.mission.lifecycle import MissionStatus
from executive.observers.journal import Journal, journal_recorder
from executive.world.clock import Clock
from tests_support import line_mission, mission_text

YARD = mission_text("yard-loop", "{lat: -35.3629906, lon: 149.1652300}")


def report(db: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    assert main(["report", str(db), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_a_mission_loaded_after_the_one_that_ran_is_named_as_never_started(tmp_path: Path, lockstep, capsys) -> None:
    db = tmp_path / "journal.db"
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(db, clock))
        return {"plugs": [journal_recorder(journals[-1])]}

    mission = line_mission("first-run", waypoints=line_mission("x").model_dump()["waypoints"][:1])
    sim = lockstep(mission, options_for_clock=journal_plug)
    operator = sim.runtime.operator
    sim.at(1.0, lambda s: operator.request("start", source="ctl"))
    assert sim.run(300, serve=True, until=lambda: sim.status is MissionStatus.COMPLETED) is None
    uploaded = operator.request("upload", source="ctl", filename="yard.yaml", text=YARD)
    assert (uploaded.ok, uploaded.state) == (True, "READY"), uploaded.reason
    sim.runtime.request_stop("SIGINT")  # Ctrl-C with yard-loop loaded, never started
    outcome = sim.run(60, serve=True)
    assert outcome is not None
    assert (outcome.mission, outcome.status, outcome.reason) == ("first-run", MissionStatus.COMPLETED, "every waypoint reached")
    assert exit_code(outcome) == EXIT_OK
    assert last_words(outcome, sim.runtime.mission_state) == [
        "mission 'yard-loop' READY: loaded, never started",
        "the vehicle made safe: HOLD (already in it)",  # the mission ended in HOLD; Ctrl-C makes sure, and says so
        f"mission 'first-run' COMPLETED: every waypoint reached ({outcome.ticks} ticks)",
    ]
    journals[0].close()
    run = report(db, capsys)
    assert (run["id"], run["mission"], run["outcome"]) == (1, "first-run", "COMPLETED")
    assert [(t["before"], t["after"]) for t in run["transitions"]] == [("READY", "RUNNING"), ("RUNNING", "COMPLETED")]
    assert not any("yard-loop" in t["reason"] for t in run["transitions"])


def test_stopped_before_any_mission_ran_it_says_so_and_exits_0(lockstep) -> None:
    sim = lockstep(line_mission("waiting"))
    sim.at(2.0, lambda s: s.runtime.request_stop("SIGTERM"))
    outcome = sim.run(60, serve=True)
    assert outcome is not None and outcome.mission is None
    said = last_words(outcome, sim.runtime.mission_state)
    assert said == [
        NOTHING_TO_MAKE_SAFE,  # the mission never started: nothing was commanded, nothing is (issue 34), and it says so
        f"mission 'waiting' READY: loaded, never started; no mission ran ({outcome.ticks} ticks)",
    ]
    assert exit_code(outcome) == EXIT_OK  # nothing aborted, nothing failed: 1 would say a mission did
