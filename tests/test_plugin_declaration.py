"""A plugin tree declares itself as ours do: its vehicle kind, firmware, RC switches and failsafe defaults (tests/gliderplugin).

The held-in plugin ``gliderplugin`` brings tree ``glider_survey`` and vehicle kind ``glider``; installed (a
dist-info naming its entry point), it is validated and listed like a built-in tree; not installed, neither is known.
"""

from __future__ import annotations

import importlib
import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.cli import main
from executive.mission.declaration import declared
from executive.mission.loader import load_mission
from executive.mission.rules import failsafe_policy, rc_switch_channels

GLIDER = """\
version: 1
name: ridge
vehicle: glider
tree: glider_survey
home: {lat: 47.3977, lon: 8.5456}
waypoints:
  - {lat: 47.3987, lon: 8.5456}
  - {lat: 47.3987, lon: 8.5476}
"""


@pytest.fixture
def glider(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """gliderplugin installed: a dist-info on the path naming ``glider_survey = gliderplugin.trees:build`` (the package is tests/')."""
    info = tmp_path / "site" / "gliderplugin-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: gliderplugin\nVersion: 1.0\n", encoding="utf-8")
    (info / "entry_points.txt").write_text("[executive.trees]\nglider_survey = gliderplugin.trees:build\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    importlib.invalidate_caches()
    yield
    for name in [n for n in sys.modules if n.split(".")[0] == "gliderplugin"]:
        del sys.modules[name]


def write(tmp_path: Path, text: str) -> str:
    path = tmp_path / "ridge.yaml"
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_a_glider_mission_is_valid_with_the_plugin_and_its_declaration_is_what_the_rules_read(
    glider: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, GLIDER)
    assert main(["validate", path]) == 0, capsys.readouterr().err
    assert capsys.readouterr().out == f"{path}: ok (2 waypoints, vehicle glider, tree glider_survey)\n"
    mission = load_mission(path)
    assert rc_switch_channels(mission) == {6: "the take-over switch", 8: "the thermal switch"}
    policy = failsafe_policy(mission)
    assert (policy["link_loss"].reaction, policy["link_loss"].recovery) == ("rtl", "abort")  # the tree's default
    assert (policy["rc_loss"].reaction, policy["rc_loss"].recovery) == ("loiter", "resume")  # the glider kind's


def test_a_glider_mission_against_the_declaration_gets_located_errors(glider: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = GLIDER.replace("vehicle: glider", "vehicle: glider\nautopilot: px4\ndrive: auto\nfailsafe:\n  battery_low: {reaction: surface}")
    path = write(tmp_path, text)
    assert main(["validate", path]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:4:12: autopilot: px4 drives rover, vtol here, not a glider",
        f"{path}:4:12: autopilot: tree glider_survey needs ArduPilot: it soars in ArduPlane's THERMAL mode",
        f"{path}:4:12: autopilot: drive: auto needs ArduPilot so far "
        "(its partial mission writes hold the horizon; PX4's AUTO.MISSION is not done yet)",
        f"{path}:5:8: drive: tree glider_survey is not known to be driven in AUTO; use drive: guided",
        f"{path}:7:27: failsafe.battery_low.reaction: surface: not for a glider (a glider cannot surface)",
    ]
    path = write(tmp_path, GLIDER.replace("vehicle: glider", "vehicle: rover"))
    assert main(["validate", path]) == 2
    assert f"{path}:4:7: tree: tree glider_survey drives glider, not a rover" in capsys.readouterr().err.splitlines()


def test_the_glider_kind_is_the_plugins(glider: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, GLIDER.replace("vehicle: glider", "vehicle: kite"))
    assert main(["validate", path]) == 2
    assert f"{path}:3:10: vehicle: 'kite': Input should be 'rover', 'boat', 'sub', 'vtol' or 'glider'" in capsys.readouterr().err


def test_without_the_plugin_neither_the_tree_nor_its_kind_is_known(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, GLIDER)
    assert main(["validate", path]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"{path}:3:10: vehicle: 'glider': Input should be 'rover', 'boat', 'sub' or 'vtol'"
    assert declared("glider_survey").vehicles is None  # not installed: declares nothing


def test_behaviours_trees_lists_the_plugin_tree_with_its_declaration(glider: None, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["behaviours", "--trees", "glider_survey"]) == 0
    assert capsys.readouterr().out == (
        "glider_survey (tree): a sailplane's survey: each waypoint in GUIDED under guards, then loiter\n"
        "    vehicles: glider\n"
        "    needs: ArduPilot: it soars in ArduPlane's THERMAL mode\n"
        "    rc: its own switches\n"
        "    failsafe link_loss: rtl, abort\n"
        "    legs timed\n"
        "    vehicle kind glider: ardupilot, safe mode LOITER\n"
    )
    assert main(["behaviours", "--trees", "--json"]) == 0
    listed = {tree["name"]: tree for tree in json.loads(capsys.readouterr().out)}
    assert sorted(listed) == ["auv_survey", "glider_survey", "goto_sample", "ugv_rc_route", "vtol_transit", "waypoints"]
    assert listed["glider_survey"]["vehicle_kinds"] == ["glider"] and listed["glider_survey"]["needs"]["autopilot"] == "ardupilot"


def test_a_declaration_that_is_not_one_is_said_at_the_tree_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "site").mkdir()
    (tmp_path / "site" / "loosetree.py").write_text(
        'from executive.trees.waypoints import build\n\nDECLARATION = {"vehicles": ["rover"]}\n', encoding="utf-8"
    )
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    monkeypatch.delitem(sys.modules, "loosetree", raising=False)
    path = write(tmp_path, GLIDER.replace("vehicle: glider", "vehicle: rover").replace("tree: glider_survey", "tree: loosetree:build"))
    assert main(["validate", path]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"{path}:4:7: tree: plugin 'loosetree:build': DECLARATION {{'vehicles': ['rover']}} is not a TreeDeclaration (executive.mission.declaration)"
    )
