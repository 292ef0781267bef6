"""Plugins: a package on the path adds a tree and a guard (entry points) that validate, show and run use; ``tree: module:function``."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import py_trees
import pytest

from executive import trees
from executive.admission import checks as admission
from executive.behaviours.base import ExecutiveBehaviour
from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.testing import Lockstep
from executive.tree.catalogue import Catalogue, catalogue, load_behaviours
from executive.world import blackboard
from tests_support import acting, executive_process, line_mission, run_recording, with_far_waypoint

ROOT = Path(__file__).parents[1]

GUARDS = '''
    """The ranger plugin's behaviours: a guard of its own and an action writing a key of its own."""

    import py_trees

    from executive.world import blackboard
    from executive.behaviours import Guard
    from executive.behaviours.base import ExecutiveBehaviour


    class EnoughSatellites(Guard):
        """The GPS sees at least ``minimum`` satellites."""

        reads = ("/vehicle/gps",)

        def __init__(self, minimum: int = 6, name: str = "Enough satellites?") -> None:
            super().__init__(name)
            self.minimum = minimum

        def check(self):
            gps = self.get("/vehicle/gps")
            if gps is None or gps.satellites is None:
                return "no satellite count yet"
            return None if gps.satellites >= self.minimum else f"{gps.satellites} satellites"


    class CountLeg(ExecutiveBehaviour):
        """Counts the legs done in /plugin/ranger/legs."""

        declares = (blackboard.Key("/plugin/ranger/legs", 0, "CountLeg", "legs the ranger tree has driven"),)
        writes = ("/plugin/ranger/legs",)

        def __init__(self, name: str = "Count the leg") -> None:
            super().__init__(name)

        def update(self):
            self.set("/plugin/ranger/legs", self.get("/plugin/ranger/legs") + 1)
            return py_trees.common.Status.SUCCESS
'''

TREE = '''
    """The ranger plugin's tree: the waypoints tree, with its own guard and a leg counter."""

    import py_trees

    from executive.behaviours import ForEachLeg, SetMode
    from rangerplugin.guards import CountLeg, EnoughSatellites
    from executive.trees.parts import failsafe_guarded, guided_leg, mission_root, preflight, safe_mode, standard_guards


    def build(mission):
        counted = py_trees.composites.Sequence("Counted leg", memory=True, children=[guided_leg(mission), CountLeg()])
        route = failsafe_guarded(ForEachLeg(counted), [*standard_guards(mission), EnoughSatellites(6)], mission)
        return mission_root(mission, preflight(mission), route, SetMode(safe_mode(mission), name="Hold at the end"))
'''

MISSION = """\
version: 1
name: ranger
vehicle: rover
tree: {tree}
waypoints:
  - {{lat: 47.397742, lon: 8.545594}}
"""


def write_distribution(site: Path, name: str, modules: dict[str, str], entry_points: dict[str, dict[str, str]]) -> None:
    """An installed distribution as pip leaves it in site-packages: its modules and ``NAME-1.0.dist-info`` with its entry points."""
    for module, source in modules.items():
        path = site / module
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(source), encoding="utf-8")
    info = site / f"{name}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n", encoding="utf-8")
    groups = "".join(f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in points.items()) for group, points in entry_points.items())
    (info / "entry_points.txt").write_text(groups, encoding="utf-8")


@pytest.fixture
def site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A directory on sys.path standing for site-packages; the modules imported from it are forgotten after the test."""
    path = tmp_path / "site"
    path.mkdir()
    monkeypatch.syspath_prepend(str(path))
    before = set(sys.modules)
    catalogue.cache_clear()  # made once a process: with the plugins of this test, then without them again
    yield path
    catalogue.cache_clear()
    for name in set(sys.modules) - before:
        if name.split(".")[0] in ("rangerplugin", "brokenplugin"):
            del sys.modules[name]
    for key in [k for k in blackboard.KEYS if k.startswith(blackboard.PLUGIN_NAMESPACE)]:
        del blackboard.KEYS[key]


@pytest.fixture
def ranger(site: Path) -> Path:
    """The ranger plugin installed: tree ``ranger`` and behaviour ``enough_satellites``."""
    modules = {"rangerplugin/__init__.py": "", "rangerplugin/guards.py": GUARDS, "rangerplugin/trees.py": TREE}
    points = {
        "executive.trees": {"ranger": "rangerplugin.trees:build"},
        "executive.behaviours": {"enough_satellites": "rangerplugin.guards:EnoughSatellites"},
    }
    write_distribution(site, "rangerplugin", modules, points)
    importlib.invalidate_caches()
    return site


@pytest.fixture
def broken(site: Path) -> Path:
    """A plugin whose tree module fails to import, and whose behaviour and instrument entry points name no class."""
    modules = {"brokenplugin/__init__.py": "", "brokenplugin/trees.py": "import not_installed_anywhere\n", "brokenplugin/things.py": "VALUE = 3\n"}
    points = {
        "executive.trees": {"broken": "brokenplugin.trees:build"},
        "executive.behaviours": {"thing": "brokenplugin.things:VALUE"},
        "executive.instruments": {"sonde": "brokenplugin.things:VALUE"},
    }
    write_distribution(site, "brokenplugin", modules, points)
    importlib.invalidate_caches()
    return site


def mission_file(tmp_path: Path, tree: str) -> str:
    path = tmp_path / "ranger.yaml"
    path.write_text(MISSION.format(tree=tree), encoding="utf-8")
    return str(path)


def test_an_installed_package_adds_a_tree_and_a_behaviour(ranger: Path) -> None:
    assert "ranger" in trees.load_all() and "waypoints" in trees.load_all()
    assert [cls.__name__ for cls in load_behaviours()] == ["EnoughSatellites"]
    assert trees.resolve("ranger") is sys.modules["rangerplugin.trees"].build
    assert admission.plugin_problems() == []
    spec = Catalogue.build(load_behaviours()).get("enough_satellites")  # the node catalogue has it, as it has ours
    assert (
        spec is not None
        and spec.kind == "guard"
        and spec.params[0] == spec.param("minimum")
        and (spec.params[0].type, spec.params[0].default) == ("int", 6)
    )


def test_validate_and_show_use_the_plugin_tree_and_its_guard(ranger: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = mission_file(tmp_path, "ranger")
    assert main(["validate", path]) == 0
    assert capsys.readouterr().out == f"{path}: ok (1 waypoint, vehicle rover, tree ranger)\n"
    assert main(["show", path, "--format", "ascii"]) == 0
    out = capsys.readouterr().out
    assert "Enough satellites?" in out and "Count the leg" in out and "Link alive?" in out


def test_a_plugin_tree_runs_to_the_end_with_its_guard_judging_every_tick(ranger: Path) -> None:
    with Lockstep(line_mission("ranger", tree="ranger")) as sim:
        seen: list[py_trees.common.Status] = []
        sim.observers.append(
            lambda s: seen.extend(n.status for n in (s.runtime.tree.root.iterate() if s.runtime.tree else ()) if n.name == "Enough satellites?")
        )
        outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert blackboard.value("/plugin/ranger/legs") == 4  # the plugin's own key, written by its own action once a leg
    assert py_trees.common.Status.SUCCESS in seen


def test_a_plugin_tree_cannot_leave_out_the_distance_rule(ranger: Path) -> None:
    """The ranger tree checks no distance of its own: the runtime refuses a waypoint 10 km away before the tree arms or sets anything."""
    mission, boots_at = with_far_waypoint(line_mission("ranger", tree="ranger"), 10_000.0)
    outcome, sim, received = run_recording(mission, boots_at)
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason == (
        "refused before anything was commanded: Within reach: waypoints[4] (far): 10000 m from the vehicle, over limits.max_goal_distance_m (5000 m)"
    )
    assert acting(received) == [] and not sim.autopilot.armed
    assert blackboard.value("/plugin/ranger/legs") == 0  # its tree never ran


def test_a_module_on_the_path_is_a_tree_as_module_colon_function(ranger: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for tree in ("rangerplugin.trees:build", "rangerplugin.trees"):
        assert main(["validate", mission_file(tmp_path, tree)]) == 0, capsys.readouterr().err
    assert main(["show", mission_file(tmp_path, "rangerplugin.trees:build")]) == 0
    assert "Enough satellites?" in capsys.readouterr().out


def test_a_tree_that_cannot_be_loaded_is_named_at_the_tree_line(ranger: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cases = {
        "rangerplugin.trees:missing": "AttributeError: module 'rangerplugin.trees' has no attribute 'missing'",
        "nosuchpackage.trees": "ModuleNotFoundError: No module named 'nosuchpackage'",
        "rangerplugin.guards:EnoughSatellites": "is not a function build(mission) -> Behaviour",
    }
    for tree, why in cases.items():
        path = mission_file(tmp_path, tree)
        assert main(["validate", path]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"{path}:4:7: tree: plugin '{tree}': ") and why in err, err
    path = mission_file(tmp_path, "'a:b:c'")
    assert main(["validate", path]) == 2
    assert "tree: 'a:b:c': not a tree name" in capsys.readouterr().err


def test_validate_names_a_broken_plugin_and_its_error(broken: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = mission_file(tmp_path, "broken")
    assert main(["validate", path]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"{path}:4:7: tree: {broken}/brokenplugin/trees.py:1: plugin 'broken' (executive.trees = brokenplugin.trees:build, from brokenplugin 1.0): "
        "ModuleNotFoundError: No module named 'not_installed_anywhere'",
        "executive: validate: plugin 'thing' (executive.behaviours = brokenplugin.things:VALUE, from brokenplugin 1.0): "
        "3 is not a behaviour class (subclass executive.behaviours.base.ExecutiveBehaviour)",
        "executive: validate: plugin 'sonde' (executive.instruments = brokenplugin.things:VALUE, from brokenplugin 1.0): "
        "3 is not an instrument (subclass executive.instruments.sampler.InstrumentSampler)",
    ]
    assert main(["validate", mission_file(tmp_path, "waypoints")]) == 2  # a mission that does not use it: still said, once
    assert len([line for line in capsys.readouterr().err.splitlines() if ": warning: no home:" not in line]) == 3
    assert main(["behaviours"]) == 2  # any command that needs the plugins says it, no traceback
    assert capsys.readouterr().err.startswith("executive: behaviours: plugin 'thing' (executive.behaviours = brokenplugin.things:VALUE")


def test_from_the_command_line_a_plugin_on_the_path_is_validated_and_shown(ranger: Path, tmp_path: Path) -> None:
    env = {"PYTHONPATH": os.pathsep.join([str(ranger), str(ROOT)])}
    path = mission_file(tmp_path, "ranger")
    validate = executive_process("validate", path, stdout=subprocess.PIPE, env=env)
    out, err = validate.communicate(timeout=60)
    assert validate.returncode == 0 and "tree ranger" in out, err
    show = executive_process("show", path, stdout=subprocess.PIPE, env=env)
    out, err = show.communicate(timeout=60)
    assert show.returncode == 0 and "Enough satellites?" in out, err


class Plain(ExecutiveBehaviour):
    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS


def test_a_behaviour_writes_only_the_plugin_keys_it_declares(site: Path) -> None:
    class Writer(Plain):
        declares = (blackboard.Key("/plugin/mine/count", 0, "Writer", "a count"),)
        writes = ("/plugin/mine/count",)

    assert "/plugin/mine/count" not in blackboard.KEYS  # defining the class documents nothing
    writer = Writer("w")
    assert blackboard.value("/plugin/mine/count") == 0 and blackboard.KEYS["/plugin/mine/count"] == Writer.declared_keys()[0]
    writer.set("/plugin/mine/count", 3)
    assert blackboard.value("/plugin/mine/count") == 3 == writer.get("/plugin/mine/count")

    class Sneaky(Plain):
        writes = ("/vehicle/armed",)

    with pytest.raises(KeyError, match="behaviours write only keys under /plugin/"):
        Sneaky("s")

    class Forgetful(Plain):
        writes = ("/plugin/mine/other",)

    with pytest.raises(KeyError, match="undeclared blackboard key '/plugin/mine/other'"):
        Forgetful("f")
    with pytest.raises(ValueError, match="already declared differently"):
        blackboard.declare(blackboard.Key("/plugin/mine/count", 1, "Other", "another count"))
    with pytest.raises(ValueError, match="a plugin declares keys under /plugin/<plugin name>/<key>"):
        blackboard.declare(blackboard.Key("/vehicle/extra", 0, "Other", "not ours to add"))


COMPOSED = """\
version: 1
name: composed
vehicle: rover
auto_arm: true
tree:
  use: mission_root
  steps:
    - use: preflight
    - node: failsafe_guarded
      guards: [link_alive, ekf_ok, armed, {node: enough_satellites, minimum: 5}]
      work: {node: for_each_leg, child: {use: guided_leg}}
waypoints:
  - {lat: 47.397742, lon: 8.545594}
"""


def test_a_plugin_guard_composes_a_yaml_tree_that_runs_and_is_in_the_groot2_model(
    ranger: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "composed.yaml"
    path.write_text(COMPOSED, encoding="utf-8")
    assert main(["validate", str(path)]) == 0, capsys.readouterr().err
    assert main(["export", str(path), "-o", str(tmp_path / "tree.xml")]) == 0
    xml = (tmp_path / "tree.xml").read_text(encoding="utf-8")
    assert '<enough_satellites minimum="5" />' in xml and '<Condition ID="enough_satellites">' in xml
    with Lockstep(load_mission(path)) as sim:
        assert sim.run_to_end(limit_s=300).status is MissionStatus.COMPLETED
    path.write_text(COMPOSED.replace("minimum: 5", "minimum: five"), encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    assert "tree.steps[1].guards[3].minimum: expected an integer" in capsys.readouterr().err
