"""A plugin tree declares itself as ours do: its vehicle kind, firmware, RC switches and failsafe defaults (tests/gliderplugin).

The held-in plugin ``gliderplugin`` brings tree ``glider_survey`` and vehicle kind ``glider``; installed (a
dist-info naming its entry point), it is validated and listed like a built-in tree; not installed, neither is known.
"""

from __future__ import annotations

import importlib
import json
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from executive import registry
from executive.autopilot.fallbacks import chain
from executive.cli import main
from executive.mission.declaration import declared, plugin_kinds
from executive.mission.loader import load_mission, load_mission_text
from executive.mission.rules import failsafe_policy, rc_switch_channels
from executive.sim.battery import SPECS
from executive.sim.faults import FaultPlan
from executive.testing import Lockstep
from executive.tree.schema import SHIPPED, mission_json_schema, mission_json_schema_text
from executive.world.dialect import mavlink

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


@contextmanager
def installed_glider(site: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """gliderplugin installed: a dist-info in ``site`` on the path naming ``glider_survey = gliderplugin.trees:build`` (the package: tests/')."""
    info = site / "gliderplugin-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: gliderplugin\nVersion: 1.0\n", encoding="utf-8")
    (info / "entry_points.txt").write_text("[executive.trees]\nglider_survey = gliderplugin.trees:build\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(site))
    importlib.invalidate_caches()
    try:
        yield
    finally:
        monkeypatch.undo()
        for name in [n for n in sys.modules if n.split(".")[0] == "gliderplugin"]:
            del sys.modules[name]


@pytest.fixture
def glider(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """gliderplugin installed for the test."""
    with installed_glider(tmp_path / "site", monkeypatch):
        yield


#: A short flight for the built-in simulated vehicle the glider rides (the simulated ArduPlane): launched to 20 m, two legs.
FLIGHT = """\
version: 1
name: ridge
vehicle: glider
tree: glider_survey
auto_arm: true
home: {lat: 47.3977, lon: 8.5456}
limits: {acceptance_radius_m: 100, ekf_wait_s: 10}
simulator: {ekf_ready_after_s: 1}
glider: {launch_alt_m: 20}
waypoints:
  - {lat: 47.4007, lon: 8.5456, alt_m: 40}
  - {lat: 47.4007, lon: 8.5486, alt_m: 40}
"""


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
    assert rc_switch_channels(mission) == {6: "the take-over switch", 7: "the thermal switch"}
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
        f"{path}:4:12: autopilot: drive: auto on PX4 flies a vtol's waypoints so far (proven on PX4's SIH, which has no rover or boat)",
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
        "glider_survey (tree): a sailplane's survey: launched on its lift motors, then each waypoint in GUIDED under guards, then loiter\n"
        "    vehicles: glider\n"
        "    needs: ArduPilot: it soars in ArduPlane's THERMAL mode\n"
        "    reads: glider: (its own: launch_alt_m, thermal_channel)\n"
        "    rc: its own switches\n"
        "    failsafe link_loss: rtl, abort\n"
        "    legs timed\n"
        "    vehicle kind glider: ardupilot, safe mode LOITER, simulated as a vtol\n"
    )
    assert main(["behaviours", "--trees", "--json"]) == 0
    listed = {tree["name"]: tree for tree in json.loads(capsys.readouterr().out)}
    assert sorted(listed) == ["auv_survey", "glider_survey", "goto_sample", "ugv_rc_route", "vtol_transit", "waypoints"]
    assert listed["glider_survey"]["vehicle_kinds"] == ["glider"] and listed["glider_survey"]["needs"]["autopilot"] == "ardupilot"
    assert listed["glider_survey"]["options"] == ["launch_alt_m", "thermal_channel"] and "options" not in listed["waypoints"]


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


def test_a_glider_flies_its_mission_to_completed_on_the_simulated_arduplane_it_rides(glider: None) -> None:
    mission = load_mission_text(FLIGHT, "ridge.yaml")
    modes: list[str] = []
    with Lockstep(mission) as sim:
        sim.observers.append(lambda s: modes.append(s.autopilot.mode) if modes[-1:] != [s.autopilot.mode] else None)
        outcome = sim.run_to_end(limit_s=120)
        assert str(outcome.status) == "COMPLETED", outcome.reason
        assert (type(sim.autopilot).__name__, sim.autopilot.profile.kind) == ("QuadPlaneSim", "glider")
        assert sim.autopilot.profile.mav_type == mavlink.MAV_TYPE_FIXED_WING  # ArduPlane's HEARTBEAT
        assert sim.runtime.mission_state.legs.leg_index == 2
    assert modes[-2:] == ["GUIDED", "LOITER"]  # flown in GUIDED, left in the glider's safe mode


def test_a_glider_failsafe_commands_the_glider_kinds_own_reaction_then_resumes(glider: None) -> None:
    mission = load_mission_text(FLIGHT, "ridge.yaml")
    events = FaultPlan.model_validate({"version": 1, "faults": [{"kind": "ekf_degradation", "at_s": 25, "for_s": 6}]}).faults
    modes: list[str] = []
    with Lockstep(mission, events=events) as sim:
        sim.observers.append(lambda s: modes.append(s.autopilot.mode) if modes[-1:] != [s.autopilot.mode] else None)
        outcome = sim.run_to_end(limit_s=120)
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert modes[-4:] == ["GUIDED", "LOITER", "GUIDED", "LOITER"]  # ekf_loss: hold, the glider's LOITER (a vtol's: QLOITER), resumed


def test_a_plugin_trees_own_options_section_is_validated_with_located_errors_and_read_by_the_tree(
    glider: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, GLIDER + "glider:\n  launch_alt_m: 5\n  thermal: 3\n")
    assert main(["validate", path]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:10:17: glider.launch_alt_m: 5: Input should be greater than or equal to 20",
        f"{path}:11:3: glider.thermal: unknown field (did you mean thermal_channel? allowed: launch_alt_m, thermal_channel)",
    ]
    mission = load_mission(write(tmp_path, GLIDER + "glider: {thermal_channel: 9}\n"))
    assert rc_switch_channels(mission) == {6: "the take-over switch", 9: "the thermal switch"}
    assert declared("glider_survey").options_of(mission).launch_alt_m == 40.0  # the section's default
    path = write(tmp_path, GLIDER.replace("vehicle: glider", "vehicle: rover").replace("glider_survey", "waypoints") + "glider: {}\n")
    assert main(["validate", path]) == 2
    assert f"{path}:9:1: glider: unknown field" in capsys.readouterr().err  # another tree's mission has no glider: section


def test_the_schema_lists_the_plugin_kind_and_its_section_when_installed(glider: None) -> None:
    schema = mission_json_schema()
    assert schema["properties"]["vehicle"]["enum"] == ["rover", "boat", "sub", "vtol", "glider"]
    assert schema["properties"]["glider"]["anyOf"][0] == {"$ref": "#/$defs/GliderOptions"}
    assert schema["$defs"]["GliderOptions"]["properties"]["launch_alt_m"]["minimum"] == 20.0


def test_without_the_plugin_the_schema_is_the_shipped_one() -> None:
    assert mission_json_schema_text() == SHIPPED.read_text(encoding="utf-8")


def test_entry_points_are_read_once_until_the_path_changes_and_a_plugin_installed_later_is_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    reads: list[str] = []
    real = registry.entry_points
    monkeypatch.setattr(registry, "entry_points", lambda group: reads.append(group) or real(group=group))
    assert "glider" not in plugin_kinds()
    reads.clear()
    for _ in range(3):
        assert "glider" not in plugin_kinds()
    assert reads == []  # cached: the path has not changed
    with pytest.MonkeyPatch.context() as later, installed_glider(tmp_path / "site", later):  # installed now, in this long-lived process
        assert "glider" in plugin_kinds()
        assert "glider" in plugin_kinds()
        assert reads == [registry.TREES]  # read again once: the path changed
    assert "glider" not in plugin_kinds()  # uninstalled: the path changed back


def test_a_glider_switch_on_arduplanes_mode_switch_channel_is_refused_before_arming(glider: None) -> None:
    mission = load_mission_text(FLIGHT.replace("glider: {launch_alt_m: 20}", "glider: {launch_alt_m: 20, thermal_channel: 8}"), "ridge.yaml")
    with Lockstep(mission) as sim:
        outcome = sim.run_to_end(limit_s=60)
        assert not sim.autopilot.armed
    assert str(outcome.status) == "ABORTED" and "FLTMODE_CH" in outcome.reason, outcome.reason


def test_a_glider_is_known_by_the_firmware_it_flies_on_the_simulated_arduplane(glider: None) -> None:
    mission = load_mission_text(FLIGHT, "ridge.yaml")
    with Lockstep(mission) as sim:
        assert sim.autopilot.battery.spec == SPECS["vtol"]  # the simulated QuadPlane's pack, not a rover's
    assert list(chain("ardupilot", "glider", "LOITER")) == ["LOITER", "CIRCLE"]  # ArduPlane's own failsafe's next step
    assert list(chain("ardupilot", "glider", "RTL")) == ["RTL", "CIRCLE"]


def test_executive_sim_serves_the_simulated_vehicle_a_plugin_kind_rides(glider: None, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim", "--help"]) == 0
    assert "{boat,bunker,rover,sub,vtol,glider}" in capsys.readouterr().out


def test_a_plugin_section_named_as_a_field_of_every_mission_is_refused_at_the_tree_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "site").mkdir()
    (tmp_path / "site" / "vtoltree.py").write_text(
        "from pydantic import BaseModel\n\nfrom executive.mission.declaration import TreeDeclaration\n"
        "from executive.trees.waypoints import build\n\n\nclass Mine(BaseModel):\n    speed: float = 1.0\n\n\n"
        'DECLARATION = TreeDeclaration(section="vtol", options=Mine)\n',
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    monkeypatch.delitem(sys.modules, "vtoltree", raising=False)
    path = write(tmp_path, GLIDER.replace("vehicle: glider", "vehicle: rover").replace("tree: glider_survey", "tree: vtoltree:build"))
    assert main(["validate", path]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:4:7: tree: tree vtoltree:build declares an options section of its own named vtol, a field of every mission"
    ]
