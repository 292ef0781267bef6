"""``executive validate DIRECTORY``: a directory of mission files (the AUV mission manager's mission list) stands for its ``*.yaml`` files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from executive.cli import main

ROOT = Path(__file__).parents[2]


@pytest.fixture
def mission_list(tmp_path: Path, minimal_yaml: str) -> Path:
    """b.yaml and a.yaml (good), c.yaml (a latitude out of range), and what is not a mission file of the list."""
    folder = tmp_path / "mission_list"
    (folder / "nested").mkdir(parents=True)
    (folder / "b.yaml").write_text(minimal_yaml, encoding="utf-8")
    (folder / "a.yaml").write_text(minimal_yaml, encoding="utf-8")
    (folder / "c.yaml").write_text(minimal_yaml.replace("lat: 47.397742", "lat: 95.0"), encoding="utf-8")
    (folder / "notes.txt").write_text("not a mission", encoding="utf-8")
    (folder / "d.yml").write_text("not: [a mission", encoding="utf-8")
    (folder / "nested" / "e.yaml").write_text("not: [a mission", encoding="utf-8")
    return folder


def test_every_yaml_file_of_a_directory_in_name_order_and_nothing_else(mission_list: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (mission_list / "c.yaml").unlink()
    assert main(["validate", str(mission_list)]) == 0
    out, err = capsys.readouterr()
    assert [line for line in err.splitlines() if ": warning: no home:" not in line] == []  # issue 40: the homeless are told so
    assert out.splitlines() == [f"{mission_list / name}: ok (1 waypoint, vehicle rover, tree waypoints)" for name in ("a.yaml", "b.yaml")]


def test_a_bad_file_of_the_directory_is_reported_with_its_location_and_exits_2(mission_list: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(mission_list)]) == 2
    out, err = capsys.readouterr()
    assert len(out.splitlines()) == 2  # a.yaml and b.yaml are still checked and reported
    errors = [line for line in err.splitlines() if ": warning: no home:" not in line]  # issue 40: the homeless are told so
    assert errors == [f"{mission_list / 'c.yaml'}:6:11: waypoints[0].lat: 95.0: Input should be less than or equal to 90 (waypoint 1)"]


def test_a_directory_without_mission_files_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "readme.txt").write_text("nothing here", encoding="utf-8")
    assert main(["validate", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert (out, err) == ("", f"{tmp_path}:1:1: (directory): no mission files (*.yaml) in this directory\n")


def test_directories_and_files_mix_and_json_lists_each_file(mission_list: Path, minimal_mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "--json", str(minimal_mission), str(mission_list)]) == 2
    out, err = capsys.readouterr()
    assert err == ""
    results = json.loads(out)
    assert [(Path(r["file"]).name, r["ok"]) for r in results] == [
        ("minimal_mission.yaml", True), ("a.yaml", True), ("b.yaml", True), ("c.yaml", False),
    ]  # fmt: skip
    assert results[3]["errors"][0]["field"] == "waypoints[0].lat"


def test_the_example_missions_directory_validates(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(ROOT / "missions")]) == 0
    out, _ = capsys.readouterr()
    names = [line.split(":")[0] for line in out.splitlines()]
    assert names == [str(p) for p in sorted((ROOT / "missions").glob("*.yaml"))]
    assert f"{ROOT / 'missions' / 'auv_survey.yaml'}: ok (4 waypoints, vehicle sub, tree auv_survey)" in out.splitlines()
