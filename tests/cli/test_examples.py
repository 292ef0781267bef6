"""``executive examples``: the example missions by name, listed, run and copied out to edit."""

from __future__ import annotations

import json
from pathlib import Path

from executive.cli import main
from executive.cli.examples import fault_file, folder, mission_file

ROOT = Path(__file__).parents[2]


def test_from_a_checkout_the_examples_are_the_missions_folder():
    assert folder() == ROOT / "missions"


def test_every_example_is_listed_with_its_vehicle_and_the_fault_and_event_files(capsys):
    assert main(["examples", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert {m["name"] for m in listed["missions"]} == {p.stem for p in (ROOT / "missions").glob("*.yaml")}
    assert next(m for m in listed["missions"] if m["name"] == "auv_survey")["vehicle"] == "sub"
    assert "rc_loss" in listed["faults"] and "ugv_operator" in listed["events"]


def test_a_name_is_an_example_unless_a_file_of_that_name_is_here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert mission_file("rover_square") == str(ROOT / "missions" / "rover_square.yaml")
    assert fault_file("rc_loss") == str(ROOT / "missions" / "faults" / "rc_loss.yaml")
    assert fault_file("ugv_operator") == str(ROOT / "missions" / "events" / "ugv_operator.yaml")
    (tmp_path / "rover_square").write_text("mine")
    assert mission_file("rover_square") == "rover_square"
    assert mission_file("no_such_mission") == "no_such_mission"  # left for the command to refuse, as any missing file


def test_an_example_by_name_validates_and_an_unknown_name_is_refused_as_a_missing_file(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "boat_survey"]) == 0
    assert main(["validate", "boat_surveyy"]) == 2
    assert "boat_surveyy" in capsys.readouterr().err


def test_copy_writes_the_example_and_its_event_files_to_edit(tmp_path, capsys):
    assert main(["examples", "--copy", "ugv_rc_route", "--to", str(tmp_path)]) == 0
    assert (tmp_path / "ugv_rc_route.yaml").is_file() and (tmp_path / "events" / "ugv_operator.yaml").is_file()
    assert main(["validate", str(tmp_path / "ugv_rc_route.yaml")]) == 0  # its simulator.events found beside it
    assert main(["examples", "--copy", "ugv_rc_route", "--to", str(tmp_path)]) == 2  # never overwritten
    assert main(["examples", "--copy", "nope", "--to", str(tmp_path)]) == 2
    assert "no example 'nope'" in capsys.readouterr().err
