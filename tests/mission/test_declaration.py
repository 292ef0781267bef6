"""Each tree declares itself (its module's DECLARATION) and the rules read the declarations: no module below the trees names one."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from executive import registry
from executive.cli import main
from executive.mission.declaration import UNDECLARED, declarations, declared

EXECUTIVE = Path(__file__).parents[2] / "executive"


def _names_a_tree(node: ast.Constant, parents: list[ast.AST], named: set[str]) -> bool:
    """``node`` is a built-in tree's name; ``waypoints``, a mission field's name too, only where a tree is meant."""
    if node.value not in named:
        return False
    if node.value != registry.DEFAULT_TREE:
        return True
    near = [ast.unparse(p) for p in parents[-3:] if isinstance(p, ast.Compare | ast.Call)]  # mission.tree == ..., .get("tree", ...)
    near += [ast.unparse(p.target) for p in parents if isinstance(p, ast.AnnAssign)]  # tree: TreeSpec = Field(...)
    near += [ast.unparse(t) for p in parents if isinstance(p, ast.Assign) for t in p.targets]  # TREE_SCHEMA = {...}
    return any("tree" in text.lower() for text in near)


def _constants(tree: ast.AST, named: set[str]) -> list[tuple[ast.Constant, list[ast.AST]]]:
    """Each constant of ``tree`` whose value is in ``named``, with its parents (outermost first)."""
    found: list[tuple[ast.Constant, list[ast.AST]]] = []
    parents: list[ast.AST] = []

    def visit(node: ast.AST) -> None:  # one list of parents, copied only for a constant that names a tree
        if isinstance(node, ast.Constant):
            if isinstance(node.value, str) and node.value in named:
                found.append((node, list(parents)))
            return
        parents.append(node)
        for child in ast.iter_child_nodes(node):
            visit(child)
        parents.pop()

    visit(tree)
    return found


def test_no_module_below_the_trees_names_a_built_in_tree() -> None:
    """Only the registry's table of built-in ones says their names; the rules, the failsafes and the model read declarations."""
    named = set(registry.built_in(registry.TREES))
    found = []
    for path in sorted(EXECUTIVE.rglob("*.py")):
        if path == EXECUTIVE / "registry.py":
            continue
        for node, parents in _constants(ast.parse(path.read_text(encoding="utf-8")), named):
            if _names_a_tree(node, parents, named):
                found.append(f"{path.relative_to(EXECUTIVE.parent)}:{node.lineno}: {node.value}")
    assert found == []


def test_every_built_in_tree_declares_itself() -> None:
    found = declarations()
    assert sorted(found) == registry.built_in(registry.TREES)
    assert all(d is not UNDECLARED and d.doc and d.vehicles for d in found.values())
    assert declared(None) is UNDECLARED and declared("no_such_tree") is UNDECLARED


def test_behaviours_trees_lists_what_each_built_in_tree_declares(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["behaviours", "--trees", "goto_sample", "ugv_rc_route"]) == 0
    assert capsys.readouterr().out == (
        "goto_sample (tree): the ASV go-to-and-sample node: drive the path under guards, sample at the sample points\n"
        "    vehicles: boat, rover\n"
        "    drive: auto: boat (ArduRover), rover (ArduRover)\n"
        "    reads: sampling:\n"
        "    rc: the take-over switch; rc.arm_channel: 5\n"
        "    failsafe ekf_loss: disarm, resume\n"
        "    failsafe rc_takeover: wait, abort\n"
        "    takes samples; legs timed\n"
        "ugv_rc_route (tree): the tracked UGV's RC route: the operator records a route with the transmitter's switches, "
        "the autopilot drives it in AUTO\n"
        "    vehicles: rover\n"
        "    needs: ArduPilot: its operator drives it with ArduRover's modes and switches (arming only in MANUAL, switch C to AUTO)\n"
        "    drive: auto: refused: its operator puts the route in AUTO already\n"
        "    reads: rc_route:\n"
        "    rc: its own switches\n"
        "    failsafe heading_insane: wait, resume\n"
        "    refuses failsafe reaction disarm: the operator arms and disarms with switch D\n"
        "    its route may start empty\n"
    )
    assert main(["behaviours", "--trees", "--json", "auv_survey"]) == 0
    assert json.loads(capsys.readouterr().out) == [
        {
            "name": "auv_survey", "kind": "tree",
            "doc": "the AUV survey: accept the route, dive and run it leg by leg under guards, surface, hold",
            "vehicles": ["sub"], "needs": None, "auto_drive": {"sub": "ArduSub"}, "auto_refused": None, "section": None,
            "rc_switches": False, "rc_defaults": {}, "failsafes": {"link_loss": {"reaction": "hold", "recovery": "resume"}},
            "refused_reactions": {}, "empty_route": False, "samples": False, "timed_legs": True, "vehicle_kinds": [],
        }
    ]  # fmt: skip


def test_behaviours_trees_names_a_tree_that_does_not_exist(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["behaviours", "--trees", "waypoint"]) == 2
    assert capsys.readouterr().err == "executive: behaviours: no tree 'waypoint' (did you mean waypoints?); executive behaviours --trees lists them\n"
