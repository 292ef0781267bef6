"""Reading a mission (executive.mission) apart from checking it can run: its tree, plugins, instrument (executive.admission.checks).

``executive validate`` refuses what ``executive run`` refuses of a mission, in the same words.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from executive import trees
from executive.admission import checks as admission
from executive.cli import main
from executive.mission import loader
from executive.mission.errors import MissionError

ROOT = Path(__file__).parents[2]
WAYPOINT = "{lat: 47.397742, lon: 8.545594}"


@pytest.fixture
def waypoints_tree_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Missions may name exactly one tree here, whatever trees/ holds today, so messages stay stable."""
    monkeypatch.setattr(trees, "available", lambda: ["waypoints"])


def errors_of(text: str) -> list[str]:
    """Every error admission reports for ``text`` (as file ``m.yaml``), as printed."""
    with pytest.raises(MissionError) as info:
        admission.load_mission_text(text, "m.yaml")
    return [str(e) for e in info.value.errors]


def test_the_mission_reader_alone_reads_the_file_and_does_not_look_for_its_tree(minimal_yaml: str, waypoints_tree_only: None) -> None:
    text = minimal_yaml.replace("tree: waypoints", "tree: nope")
    assert loader.load_mission_text(text, "m.yaml").tree == "nope"  # the file is well formed: what runs it is admission's to find
    assert errors_of(text) == ["m.yaml:4:7: tree: unknown tree 'nope' (available: waypoints; or module:function)"]


def test_unknown_tree_lists_the_available_ones(minimal_yaml: str, waypoints_tree_only: None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trees, "available", lambda: ["patrol", "survey"])
    assert errors_of(minimal_yaml) == ["m.yaml:4:7: tree: unknown tree 'waypoints' (available: patrol, survey; or module:function)"]


def test_a_defaulted_unknown_tree_is_located_at_the_mission(minimal_yaml: str, waypoints_tree_only: None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trees, "available", lambda: [])
    unknown = "m.yaml:1:1: tree: unknown tree 'waypoints' (available: none; or module:function)"
    assert errors_of(minimal_yaml.replace("tree: waypoints\n", "")) == [unknown]


def test_cross_field_and_tree_errors_are_reported_together(minimal_yaml: str, waypoints_tree_only: None) -> None:
    text = minimal_yaml.replace("tree: waypoints", "tree: nope").replace(WAYPOINT, "{lat: 47.0, lon: 8.0, speed_m_s: 9.0, depth_m: 3.0}")
    assert errors_of(text) == [
        "m.yaml:4:7: tree: unknown tree 'nope' (available: waypoints; or module:function)",
        "m.yaml:6:38: waypoints[0].speed_m_s: 9.0 m/s is outside limits.speed_m_s [0.1, 5.0] (waypoint 1)",
        "m.yaml:6:52: waypoints[0].depth_m: only a sub has depth_m (vehicle is rover) (waypoint 1)",
    ]


# -- validate refuses what run refuses, in its words ----------------------------------------------------------------


def refusals(capsys: pytest.CaptureFixture[str], run: list[str], validate: list[str]) -> tuple[str, str]:
    """What ``run`` and ``validate`` say on stderr refusing a mission (both exit 2)."""
    capsys.readouterr()
    assert main(["run", *run]) == 2
    said_by_run = capsys.readouterr().err
    assert main(["validate", *validate]) == 2
    return said_by_run, capsys.readouterr().err


def test_a_sampling_mission_with_no_instrument_is_refused_against_a_real_vehicle_by_both(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = str(tmp_path / "asv.yaml")
    shutil.copy(ROOT / "missions" / "asv_sampling.yaml", path)
    (tmp_path / "events").mkdir()
    shutil.copy(ROOT / "missions" / "events" / "asv_ekf_dropout.yaml", tmp_path / "events")
    by_run, by_validate = refusals(capsys, [path, "--mavlink", "udpin:127.0.0.1:0"], [path, "--real-vehicle"])
    why = "sampling.instrument: the mission takes samples and names no instrument; against a real vehicle the samples must come from one"
    assert by_run.startswith(f"executive: run: {why}") and by_run.endswith("built-in simulator\n")
    assert by_validate == f"{path}: {by_run.removeprefix('executive: run: ')}"
    assert main(["validate", path]) == 0  # on the built-in simulator, its simulated instrument takes them


def test_a_sub_is_refused_on_px4_by_both(capsys: pytest.CaptureFixture[str]) -> None:
    path = str(ROOT / "missions" / "auv_survey.yaml")
    by_run, by_validate = refusals(capsys, [path, "--autopilot", "px4"], [path, "--autopilot", "px4"])
    assert by_run == "executive: run: --autopilot px4: px4 drives rover, vtol here, not a sub\n"
    assert by_validate == f"{path}: --autopilot px4: px4 drives rover, vtol here, not a sub\n"


def test_a_broken_simulator_event_file_is_refused_by_both_at_its_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """validate used to say ok of a mission whose event file run refuses (exit 2, nothing started)."""
    path = str(tmp_path / "asv.yaml")
    shutil.copy(ROOT / "missions" / "asv_sampling.yaml", path)
    (tmp_path / "events").mkdir()
    (tmp_path / "events" / "asv_ekf_dropout.yaml").write_text("version: 1\nfaults:\n  - {kind: ekf_degradation, at_s: soon}\n", encoding="utf-8")
    by_run, by_validate = refusals(capsys, [path], [path])
    located = [line for line in by_run.splitlines() if not line.startswith("executive: run: ")]
    assert located and all(line.startswith(str(tmp_path / "events" / "asv_ekf_dropout.yaml") + ":3:") for line in located)
    assert by_validate.splitlines() == located
    assert main(["validate", path, "--real-vehicle", "--json"]) == 2  # against a real vehicle: no event file, but samples need an instrument


def test_a_refused_vehicle_does_not_hide_an_unknown_tree() -> None:
    """Issue 43: `vehicle: boats` with `tree: waypoint` reported the vehicle only; an error whatever the vehicle is also said."""
    text = "version: 1\nname: x\nvehicle: boats\ntree: waypoint\nwaypoints:\n  - {lat: 1.0, lon: 2.0, speed_m_s: 3.0}\n"
    with pytest.raises(MissionError) as info:
        admission.load_mission_text(text, "m.yaml")
    assert [str(e) for e in info.value.errors] == [
        "m.yaml:3:10: vehicle: 'boats': Input should be 'rover', 'boat', 'sub' or 'vtol'",
        "m.yaml:4:7: tree: unknown tree 'waypoint' (available: auv_survey, goto_sample, ugv_rc_route, vtol_transit, waypoints; or module:function)",
    ]  # not the speed: 3 m/s is over a sub's limit only, and the vehicle is not known
