"""Tree drawings: Unicode lines with kind and status glyphs, DOT with one id per node whatever the names."""

from __future__ import annotations

import py_trees

from executive.tree.drawing import dot_graph, unicode_tree


def ticked_tree() -> py_trees.behaviour.Behaviour:
    """A sequence that succeeded its first child and runs its second, ``Wait: EKF`` (a name with ':'); its third, named as its first, not ticked."""
    done = py_trees.behaviours.Success("Arm")
    running = py_trees.behaviours.Running("Wait: EKF")
    root = py_trees.composites.Sequence("Run", memory=True, children=[done, running, py_trees.behaviours.Success("Arm")])
    root.tick_once()
    running.feedback_message = "no EKF status yet"  # what a waiting behaviour says
    return root


def test_unicode_shows_the_statuses_and_the_feedback_of_a_ticked_tree() -> None:
    root = ticked_tree()
    assert unicode_tree(root, show_status=True).splitlines() == [
        "* → Run",
        "├─ ✓ • Arm — success",
        "├─ * • Wait: EKF — no EKF status yet",
        "└─ - • Arm",
    ]
    assert unicode_tree(root).splitlines()[1] == "├─ • Arm"  # without statuses: the tree alone


def test_dot_outlines_each_ticked_node_in_its_statuss_colour_and_keeps_same_names_apart() -> None:
    graph = dot_graph(ticked_tree(), 'a "quoted" mission', show_status=True)
    assert graph.startswith('digraph "a \\"quoted\\" mission" {')
    assert '  n1 [label="Arm", shape=ellipse, fillcolor=gray, color=green, penwidth=2];' in graph
    assert '  n2 [label="Wait: EKF", shape=ellipse, fillcolor=gray, color=blue, penwidth=2];' in graph
    assert '  n3 [label="Arm", shape=ellipse, fillcolor=gray];' in graph  # not ticked: no outline, and not merged with n1
    assert [line.strip() for line in graph.splitlines() if "->" in line] == ["n0 -> n1;", "n0 -> n2;", "n0 -> n3;"]
