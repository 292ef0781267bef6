"""A behaviour tree as a Groot2 monitor sees it: nodes with BehaviorTree.CPP uids, the XML of ``FULLTREE``, the status records.

A node's tag is BehaviorTree.CPP's built-in where one means what ours does (py_trees' ``Sequence``
without memory ticks every child again each tick: ``ReactiveSequence``; with memory: ``Sequence``;
``Selector`` likewise ``ReactiveFallback`` / ``Fallback``; ``Parallel``, ``Inverter``,
``RetryUntilSuccessful``, ``Repeat``, our vehicle-time ``Timeout``; not py_trees' ``OneShot``: BehaviorTree.CPP's
``RunOnce`` keeps a first FAILURE for good, ours ticks the child again until it succeeds), else the catalogue's
name of our node (``go_to``, ``ekf_ok``...), else its class name; every tag that is not a built-in is
declared in ``<TreeNodesModel>`` with its kind. Uids count from 1 in pre-order, as BehaviorTree.CPP
gives them. The XML carries ``_uid`` and ``_fullpath`` on every node, as ``WriteTreeToXML`` writes
them with its metadata (``src/xml_parsing.cpp``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from executive.observers.groot2.protocol import FAILURE, IDLE, IDLE_AFTER, RUNNING, SUCCESS

TREE_ID = "MainTree"
#: BehaviorTree.CPP's built-in node IDs used here: never declared in the model.
BUILT_INS = frozenset(
    {"Sequence", "ReactiveSequence", "Fallback", "ReactiveFallback", "Parallel", "Inverter", "RetryUntilSuccessful", "Repeat", "Timeout"}
)
KINDS = ("Action", "Condition", "Decorator", "Control")
CODES = {Status.RUNNING: RUNNING, Status.SUCCESS: SUCCESS, Status.FAILURE: FAILURE}
SNAPSHOT_CODES = {"R": RUNNING, "S": SUCCESS, "F": FAILURE}


@dataclass
class MonitoredNode:
    """One node: its uid, tag (BehaviorTree.CPP ID), instance name, kind (Action, Condition, Decorator, Control), ports."""

    uid: int
    tag: str
    name: str
    kind: str
    ports: dict[str, str] = field(default_factory=dict)
    children: list[MonitoredNode] = field(default_factory=list)

    def preorder(self) -> list[MonitoredNode]:
        out = [self]
        for child in self.children:
            out.extend(child.preorder())
        return out


def _builtin(behaviour: py_trees.behaviour.Behaviour) -> tuple[str, dict[str, str]] | None:
    """The BehaviorTree.CPP built-in that means what this py_trees (or our vehicle-time Timeout) node does, with its ports."""
    from executive.behaviours.flow import Timeout

    composites, decorators = py_trees.composites, py_trees.decorators
    if type(behaviour) is composites.Sequence:
        return ("Sequence" if behaviour.memory else "ReactiveSequence"), {}
    if type(behaviour) is composites.Selector:
        return ("Fallback" if behaviour.memory else "ReactiveFallback"), {}
    if type(behaviour) is composites.Parallel:
        on_one = isinstance(behaviour.policy, py_trees.common.ParallelPolicy.SuccessOnOne)
        return "Parallel", {"success_count": "1" if on_one else "-1", "failure_count": "1"}  # py_trees fails on any child's failure
    if type(behaviour) is decorators.Inverter:
        return "Inverter", {}
    if type(behaviour) is decorators.Retry:
        return "RetryUntilSuccessful", {"num_attempts": str(behaviour.num_failures)}
    if type(behaviour) is decorators.Repeat:
        return "Repeat", {"num_cycles": str(behaviour.num_success)}
    if type(behaviour) is Timeout:
        return "Timeout", {"msec": str(round(behaviour.timeout_s * 1000))}
    return None


def _kind(behaviour: py_trees.behaviour.Behaviour) -> str:
    from executive.behaviours.guards import Guard

    if isinstance(behaviour, py_trees.decorators.Decorator):
        return "Decorator"
    if isinstance(behaviour, py_trees.composites.Composite):
        return "Control"
    return "Condition" if isinstance(behaviour, Guard) else "Action"


def behaviours_in_order(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    """The tree's behaviours in pre-order: the order of their uids."""
    out = [root]
    for child in root.children:
        out.extend(behaviours_in_order(child))
    return out


PortReader = Callable[[py_trees.behaviour.Behaviour], tuple[str, dict[str, str]] | None]


def from_tree(root: py_trees.behaviour.Behaviour, describe: PortReader | None = None) -> MonitoredNode:
    """The running tree. ``describe(behaviour)`` gives our own node's catalogue name and ports (as text), or None: its class name, no ports."""
    counter = iter(range(1, 1 << 16))

    def build(behaviour: py_trees.behaviour.Behaviour) -> MonitoredNode:
        uid = next(counter)
        builtin = _builtin(behaviour)
        if builtin is not None:
            tag, ports = builtin
        else:
            tag, ports = (describe(behaviour) if describe is not None else None) or (type(behaviour).__name__, {})
        node = MonitoredNode(uid, tag, behaviour.name, _kind(behaviour), ports)
        node.children = [build(child) for child in behaviour.children]
        return node

    return build(root)


SNAPSHOT_BUILT_INS = {"Sequence": "Sequence", "Selector": "Fallback", "Parallel": "Parallel", "Inverter": "Inverter"}


def from_snapshot(nodes: Sequence[Mapping[str, Any]]) -> MonitoredNode:
    """A recorded tree (a snapshot file's ``tree`` line: id, name, type, parent in pre-order). The file keeps no memory flag
    nor ports: a Sequence is shown as ``Sequence``, a Selector as ``Fallback``; a node's kind is read from its children."""
    by_id: dict[int, MonitoredNode] = {}
    root: MonitoredNode | None = None
    for n in nodes:
        kind_of_children = sum(1 for m in nodes if m["parent"] == n["id"])
        tag = SNAPSHOT_BUILT_INS.get(n["type"], n["type"])
        kind = "Action" if kind_of_children == 0 else "Decorator" if n["type"] in ("Inverter",) or "Decorator" in n["type"] else "Control"
        node = MonitoredNode(n["id"] + 1, tag, n["name"], kind)
        by_id[n["id"]] = node
        if n["parent"] is None:
            root = node
        else:
            by_id[n["parent"]].children.append(node)
    if root is None:
        raise ValueError("a recorded tree without a root")
    return root


def to_xml(root: MonitoredNode) -> str:
    """The ``FULLTREE`` answer: the tree with its metadata and a model of every node type that is not a built-in."""
    doc = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": TREE_ID})
    tree = ET.SubElement(doc, "BehaviorTree", {"ID": TREE_ID, "_fullpath": ""})

    def write(parent: ET.Element, node: MonitoredNode) -> None:
        element = ET.SubElement(parent, node.tag, {"name": node.name, **node.ports, "_uid": str(node.uid), "_fullpath": f"{node.name}::{node.uid}"})
        for child in node.children:
            write(element, child)

    write(tree, root)
    model = ET.SubElement(doc, "TreeNodesModel")
    declared: dict[str, MonitoredNode] = {}
    for node in root.preorder():
        if node.tag not in BUILT_INS:
            declared.setdefault(node.tag, node)
    for tag, node in sorted(declared.items()):
        element = ET.SubElement(model, node.kind, {"ID": tag})
        for port in node.ports:
            ET.SubElement(element, "input_port", {"name": port})
    return ET.tostring(doc, encoding="unicode")


class StatusTrack:
    """Each node's last status as Groot2 codes it: a node not ticked any more (py_trees' INVALID) is 10 + what it was, or IDLE."""

    def __init__(self, uids: Sequence[int]) -> None:
        self.uids = tuple(uids)
        self.codes = [IDLE] * len(self.uids)

    def update(self, statuses: Sequence[int | None]) -> list[tuple[int, int]]:
        """Take this tick's statuses (a Groot2 code, or None for not ticked); the (uid, code) pairs that changed."""
        changed = []
        for i, status in enumerate(statuses):
            old = self.codes[i]
            new = status if status is not None else (old if old == IDLE or old >= IDLE_AFTER else IDLE_AFTER + old)
            if new != old:
                self.codes[i] = new
                changed.append((self.uids[i], new))
        return changed
