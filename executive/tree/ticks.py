"""A tree as it was at one tick: its nodes in pre-order, each node's status as a one-letter code, and that drawn for a person.

What a snapshot file records, the control socket's ``tree`` answers and the live view shows.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees import console
from py_trees.common import Status

#: Each status as py_trees' own display draws it (``py_trees.display.unicode_symbols``): the one set of status symbols, for
#: the tree drawings (:mod:`executive.tree.drawing`) and a recorded tick's (:func:`render_tree`).
STATUS_SYMBOLS = {Status.SUCCESS: console.check_mark, Status.FAILURE: console.multiplication_x, Status.RUNNING: "*", Status.INVALID: "-"}
#: Each status as a snapshot file's one-letter code (``-``: not ticked).
STATUS_CODES = {Status.SUCCESS: "S", Status.FAILURE: "F", Status.RUNNING: "R"}


def _preorder(node: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    yield node
    for child in node.children:
        yield from _preorder(child)


def describe(root: py_trees.behaviour.Behaviour) -> tuple[list[py_trees.behaviour.Behaviour], list[dict[str, Any]]]:
    """The nodes of a tree in pre-order, and their description (id, name, type, parent id) as a snapshot file holds it."""
    nodes = list(_preorder(root))
    ids = {id(node): i for i, node in enumerate(nodes)}
    return nodes, [{"id": i, "name": n.name, "type": type(n).__name__, "parent": ids.get(id(n.parent))} for i, n in enumerate(nodes)]


def status_codes(nodes: list[py_trees.behaviour.Behaviour]) -> list[str]:
    """Each node's status as a snapshot code: S, F, R, or - (not ticked)."""
    return [STATUS_CODES.get(n.status, "-") for n in nodes]


@dataclass
class TickState:
    """The tree and the blackboard as they were at one tick."""

    tick: int
    t: float
    nodes: list[dict[str, Any]]
    status: dict[int, str] = field(default_factory=dict)
    feedback: dict[int, str] = field(default_factory=dict)
    blackboard: dict[str, str] = field(default_factory=dict)
    changed: set[str] = field(default_factory=set)

    def tree_dict(self) -> dict[str, Any]:
        """The tree part as JSON (the control socket's ``tree`` reply): tick, t, nodes, status and feedback by node id."""
        return {"tick": self.tick, "t": self.t, "nodes": self.nodes, "status": self.status, "feedback": self.feedback}

    @classmethod
    def from_tree_dict(cls, data: dict[str, Any]) -> TickState:
        """Back from :meth:`tree_dict` (JSON made the node ids strings)."""
        status = {int(i): s for i, s in data["status"].items()}
        return cls(data["tick"], data["t"], data["nodes"], status, {int(i): m for i, m in data["feedback"].items()})


_SYMBOL_OF_CODE = {STATUS_CODES.get(status, "-"): symbol for status, symbol in STATUS_SYMBOLS.items()}


def render_tree(state: TickState) -> Iterable[str]:
    """The tree at that tick: one line per node, indented, with its status symbol and feedback."""
    yield f"tick {state.tick} at {state.t:.1f} s"
    depth: dict[int, int] = {}
    for node in state.nodes:
        depth[node["id"]] = 0 if node["parent"] is None else depth[node["parent"]] + 1
        status = state.status.get(node["id"], "-")
        note = state.feedback.get(node["id"], "")
        yield f"{'    ' * depth[node['id']]}{_SYMBOL_OF_CODE[status]} {node['name']}" + (f" -- {note}" if note else "")
