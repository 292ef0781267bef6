"""Trees composed in the mission file: every error at once, located as FILE:LINE:COL: tree.path: why; a good tree built as Python would."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import py_trees
import pytest
import yaml
from py_trees.common import ParallelPolicy, Status

from executive.admission.checks import load_mission_text
from executive.behaviours import EkfOk, FailsafeNote, Sample, SetMode, Timeout
from executive.cli import main
from executive.mission.errors import MissionError
from executive.testing import Harness
from executive.tree import select as mission_tree
from executive.tree.schema import mission_json_schema

HEAD = "version: 1\nname: m\nvehicle: rover\nauto_arm: true\nwaypoints: [{lat: 47.397742, lon: 8.545594}]\ntree:\n"  # the tree on line 7


def load(tree: str, head: str = HEAD):
    return load_mission_text(head + tree, "m.yaml")


def errors_of(tree: str, head: str = HEAD) -> list[str]:
    with pytest.raises(MissionError) as info:
        load(tree, head)
    return [str(e) for e in info.value.errors]


def test_every_error_at_once_each_at_its_line_and_column() -> None:
    tree = """\
  use: mission_root
  steps:
    - use: preflight
    - node: sequence
      children:
        - ekf_okk
        - node: set_mode
        - node: timeout
          timeout_s: "5"
          child: armed
        - {node: go_to, look_ahead: 1, radius: 3}
    - node: failsafe_guarded
      guards: [link_alive, {node: set_mode, mode: HOLD}]
      work: {node: for_each_leg, child: armed}
    - {use: sequence}
    - {node: preflight}
    - {node: set_mode, mode: GUIDD}
    - {node: failsafe_note, condition: ekf_loss, text: x, guard: "Nobody?"}
"""
    assert errors_of(tree) == [
        "m.yaml:12:11: tree.steps[1].children[0]: unknown node 'ekf_okk' (did you mean ekf_ok?); executive behaviours lists them",
        "m.yaml:13:11: tree.steps[1].children[1].mode: required parameter of set_mode is missing (a string)",
        "m.yaml:15:22: tree.steps[1].children[2].timeout_s: expected a number, got string '5'",
        "m.yaml:16:18: tree.steps[1].children[2].child: armed is a guard, which never runs: timeout.child needs an action, a composite or a subtree",
        "m.yaml:17:37: tree.steps[1].children[3].look_ahead: expected true or false, got integer 1",
        "m.yaml:17:48: tree.steps[1].children[3].radius: unknown parameter of go_to (allowed: acceptance_radius_m, leg_timeout_s, name, "
        "resend_s, method, look_ahead, seabed_clearance_m, height_tolerance_m)",
        "m.yaml:19:28: tree.steps[2].guards[1]: set_mode is an action: failsafe_guarded.guards takes guards only",
        "m.yaml:20:41: tree.steps[2].work.child: armed is a guard, which never runs: for_each_leg.child needs an action, a composite or a subtree",
        "m.yaml:21:13: tree.steps[3].use: sequence is a composite, not a built-in subtree: write node: sequence",
        "m.yaml:22:14: tree.steps[4].node: preflight is a built-in subtree: write use: preflight",
        "m.yaml:23:30: tree.steps[5].mode: 'GUIDD': not a rover mode (known: MANUAL, ACRO, STEERING, HOLD, LOITER, FOLLOW, SIMPLE, "
        "DOCK, CIRCLE, AUTO, RTL, SMART_RTL, GUIDED)",
    ]  # the reference to a guard is judged once the rest is right


def test_a_guard_named_must_come_before_and_sample_points_need_a_sample_node() -> None:
    tree = """\
  node: sequence
  children:
    - {node: failsafe_note, condition: ekf_loss, text: x, guard: "EKF ok?"}
    - ekf_ok
"""
    head = HEAD.replace("waypoints: [{lat: 47.397742, lon: 8.545594}]", "waypoints: [{lat: 47.397742, lon: 8.545594, sample: true}]")
    assert errors_of(tree, head) == [
        "m.yaml:5:53: waypoints[0].sample: no sample node in the tree takes it (waypoint 1)",
        "m.yaml:9:66: tree.children[0].guard: no guard named 'EKF ok?' comes before it in the tree",
    ]


def test_a_node_needing_a_mission_section_says_so() -> None:
    assert errors_of("  node: inside_geofence\n") == [
        "m.yaml:7:3: tree: inside_geofence needs geofence in the mission (it has none), or fence: here",
    ]
    assert errors_of("  {node: inside_geofence, fence: {}}\n") == ["m.yaml:7:34: tree.fence: taken from the mission (geofence), not given here"]


@pytest.mark.parametrize(
    ("tree", "expected"),
    [
        ("  5\n", "m.yaml:7:3: tree: 5: expected a tree name, or a tree composed in the file (a mapping with node: or use:)"),
        ("  [armed]\n", "m.yaml:7:3: tree: expected a tree name, or a tree composed in the file (a mapping with node: or use:)"),
        ("  {name: x}\n", "m.yaml:7:3: tree: a node is node: NAME or use: SUBTREE, with its parameters"),
        ("  {node: sequence, use: preflight}\n", "m.yaml:7:3: tree: node: and use: together"),
        ("  {node: [armed]}\n", "m.yaml:7:10: tree.node: expected a node name, got a list"),
        ("  {node: sequence, children: armed}\n", "m.yaml:7:30: tree.children: expected a list of nodes, got string 'armed'"),
        ("  {node: speed_within, limit: {min: 2, max: 1}}\n", "m.yaml:7:31: tree.limit: min (2.0) is greater than max (1.0)"),
        ("  {node: speed_within, limit: [1, 2]}\n", "m.yaml:7:31: tree.limit: expected a mapping of min, max (numbers), got a list"),
        ("  {node: vtol_transition, to: UP}\n", "m.yaml:7:31: tree.to: string 'UP': expected one of FW, MC"),
        ("  {node: set_mode, mode: null}\n", "m.yaml:7:26: tree.mode: expected a string, got null"),
    ],
)  # fmt: skip
def test_what_is_not_a_node(tree: str, expected: str) -> None:
    assert errors_of(tree) == [expected]


def test_a_refused_tree_is_reported_by_validate_with_exit_2(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(HEAD + "  {node: sequence, children: [{node: timeout, timeout_s: soon, child: arm}, nope]}\n")
    assert main(["validate", str(bad)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{bad}:7:58: tree.children[0].timeout_s: expected a number, got string 'soon'",
        f"{bad}:7:77: tree.children[1]: unknown node 'nope'; executive behaviours lists them",
    ]


def test_a_good_tree_is_built_from_the_catalogue_s_classes_with_the_mission_s_values() -> None:
    tree = """\
  use: mission_root
  steps:
    - node: parallel
      policy: success_on_one
      children:
        - {node: timeout, timeout_s: 30, child: {node: retry, failures: 3, child: arm}}
        - {node: once, child: {node: repeat, successes: 2, child: {node: set_mode, mode: hold}}}
    - {node: ekf_ok, hold_after_s: 1.5, awaiting_recovery: true, name: "Recovered?"}
    - {node: failsafe_note, condition: ekf_loss, text: seen, guard: "Recovered?"}
    - {node: go_to, method: reposition}
"""
    mission = load(tree)
    root = mission_tree.build(mission)
    assert (root.name, type(root).__name__, root.hold_mode) == ("Mission", "UnlessPaused", "HOLD")  # the rover's hold, from the mission
    run = root.children[0]
    parallel, ekf, note, go = run.children
    assert isinstance(parallel, py_trees.composites.Parallel) and isinstance(parallel.policy, ParallelPolicy.SuccessOnOne)
    timeout, once = parallel.children
    assert isinstance(timeout, Timeout) and timeout.timeout_s == 30.0 and type(timeout.decorated).__name__ == "Retry"
    assert isinstance(once.decorated.decorated, SetMode) and once.decorated.decorated.mode == "HOLD"
    assert isinstance(ekf, EkfOk) and (ekf.hold_after_s, ekf.resume_after_s, ekf.name) == (1.5, 3.0, "Recovered?")
    assert ekf.judge() is not None  # awaiting recovery: failed until the condition has held for resume_after_s
    assert isinstance(note, FailsafeNote) and note.guard is ekf
    assert (go.acceptance_radius_m, go.leg_timeout_s, go.method) == (2.0, 120.0, "reposition")  # the mission's limits


def test_a_composed_tree_runs_tick_by_tick_like_any_other(harness, vehicle) -> None:
    mission = load("  {node: sequence, children: [{node: wait_until, limit_s: 5, child: link_alive}, {node: set_mode, mode: HOLD}]}\n")
    h = harness(mission_tree.build(mission))
    assert h.tick() == Status.RUNNING
    vehicle.set(link__up=True)
    assert h.tick() == Status.RUNNING
    assert h.asked() == [("mode", "HOLD")]


def test_the_schema_completes_a_composed_tree_and_refuses_what_the_loader_refuses() -> None:
    from tests.tree.test_mission_schema import violations

    schema = mission_json_schema()
    good = yaml.safe_load(HEAD + "  {use: mission_root, steps: [{use: preflight}, {node: go_to, look_ahead: true}, armed]}\n")
    assert violations(good, schema, schema) == []
    bad: dict[str, Any] = yaml.safe_load(HEAD + "  {node: go_to, look_ahead: 1}\n")
    assert violations(bad, schema, schema) == ["$.tree: anyOf"]
    go_to = schema["$defs"]["TreeNode_go_to"]
    assert go_to["properties"]["acceptance_radius_m"] == {
        "type": "number", "description": "the target counts as reached within this distance [m] (default: the mission's limits.acceptance_radius_m)",
    }  # fmt: skip
    assert "sample" in schema["$defs"]["TreeNode"]["anyOf"][0]["enum"]
    assert {"$ref": "#/$defs/TreeNode_ekf_ok"} in schema["$defs"]["TreeGuard"]["anyOf"]
    assert {"$ref": "#/$defs/TreeNode_go_to"} not in schema["$defs"]["TreeGuard"]["anyOf"]
    assert Sample  # the sample action is in the catalogue the schema was made from


def test_the_readme_s_example_loads_and_its_errors_are_the_readme_s() -> None:
    readme = (Path(__file__).parents[2] / "docs" / "own-trees.md").read_text(encoding="utf-8")  # README's section, in the manual
    section = readme.split("### A tree written in the mission file")[1]
    example, shown = section.split("```yaml\n")[1].split("```")[0], "m.yaml" + section.split("```\nm.yaml")[1].split("```")[0]
    head = HEAD.removesuffix("tree:\n")
    assert isinstance(load(example, head).tree, dict)
    bad = example.replace("use: preflight ", "use: pre_flight").replace("rc_not_taking_over]", "{node: set_mode, mode: HOLD}]")
    assert errors_of(bad.replace("timeout_s: 90,", "timeout_s: 90s,"), head) == shown.splitlines()


def test_a_root_that_would_not_hold_the_vehicle_while_paused_is_put_under_mission_root() -> None:
    mission = load("  {node: sequence, children: [{node: set_mode, mode: GUIDED}, {node: wait_until, limit_s: 60, child: position_known}]}\n")
    h = Harness.build(mission)  # the mission's own tree, the mission started
    root = h.root
    assert (root.name, [c.name for c in root.children[0].children]) == ("Mission", ["Sequence"])
    h.tick()
    assert h.asked() == [("mode", "GUIDED")]
    h.mission_state.pause("a person asked")
    h.tick()
    assert h.asked() == [("mode", "HOLD")]  # the rover held, the work stopped
    assert root.children[0].status == Status.INVALID


def test_a_missing_child_is_named_with_what_it_takes() -> None:
    assert errors_of("  {node: timeout, timeout_s: 5}\n") == ["m.yaml:7:3: tree.child: required parameter of timeout is missing (a node)"]
