"""The runtime's tree ticks as py_trees' own does: the same statuses, handlers and count; its visitors still visited."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from executive.tree.ticking import BehaviourTree


def _root() -> py_trees.behaviour.Behaviour:
    root = py_trees.composites.Sequence("root", memory=False)
    root.add_children([py_trees.behaviours.Success("first"), py_trees.behaviours.Running("second"), py_trees.behaviours.Failure("never")])
    return root


def test_a_tick_without_visitors_is_py_trees_tick() -> None:
    ours, theirs = BehaviourTree(_root()), py_trees.trees.BehaviourTree(_root())
    calls: list[str] = []
    for tree, name in ((ours, "ours"), (theirs, "theirs")):
        tree.add_pre_tick_handler(lambda _t, n=name: calls.append(f"{n} pre"))
        tree.add_post_tick_handler(lambda _t, n=name: calls.append(f"{n} post"))
        for _ in range(3):
            tree.tick(pre_tick_handler=lambda _t, n=name: calls.append(f"{n} once"))
    assert [(n.name, n.status) for n in ours.root.iterate()] == [(n.name, n.status) for n in theirs.root.iterate()]
    assert ours.root.status is Status.RUNNING and ours.count == theirs.count == 3
    assert [c.split()[1] for c in calls if c.startswith("ours")] == [c.split()[1] for c in calls if c.startswith("theirs")]
    assert calls[:3] == ["ours once", "ours pre", "ours post"]


def test_a_visitor_still_sees_every_node_ticked() -> None:
    tree = BehaviourTree(_root())
    snapshot = py_trees.visitors.SnapshotVisitor()
    tree.visitors.append(snapshot)
    tree.tick()
    names = {node.name for node in tree.root.iterate() if node.id in snapshot.visited}
    assert names == {"root", "first", "second"}
