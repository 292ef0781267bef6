"""The running executive served to Groot2: a run observer that hands each tick's statuses to a :class:`MonitorView`."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import py_trees

from executive.observers.groot2.model import CODES, MonitoredNode, behaviours_in_order, from_tree
from executive.observers.groot2.view import MonitorView
from executive.world import blackboard

if TYPE_CHECKING:
    from executive.mission.model import Mission
    from executive.runtime.assembly import Wiring


def catalogue_ports(mission: Mission) -> Callable[[py_trees.behaviour.Behaviour], tuple[str, dict[str, str]] | None]:
    """Our node's catalogue name and the ports it was built with (as ``export --format btcpp`` reads them back), or None."""
    from executive.tree.catalogue import catalogue
    from executive.tree.formats.btcpp import node_types, port_text
    from executive.tree.formats.recompose import Recomposer

    cat = catalogue()
    types = node_types(cat)
    reader = Recomposer(types, cat, mission)

    def describe(behaviour: py_trees.behaviour.Behaviour) -> tuple[str, dict[str, str]] | None:
        node = reader.describe_one(behaviour)
        if node is None:
            return None
        kinds = {port.name: port.type for port in types[node.type].ports}
        return node.type, {name: port_text(value, kinds.get(name, "")) for name, value in node.params.items()}

    return describe


def _board() -> dict[str, Any]:
    return {key: blackboard.value(key) for key in blackboard.KEYS}


class Groot2Monitor:
    """A run observer: each run's tree shown from its start, each tick's statuses after the tick (a walk of the tree, no more)."""

    def __init__(self, view: MonitorView) -> None:
        self.view = view
        self._nodes: list[py_trees.behaviour.Behaviour] = []

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self._nodes = behaviours_in_order(root)
        shape = from_tree(root)

        def with_ports() -> MonitoredNode:  # on the server's thread, when a client first asks for the tree
            return from_tree(root, catalogue_ports(mission))

        self.view.show_tree(shape, with_ports)

    def ticked(self, tick: int, now: float) -> None:
        self.view.ticked([CODES.get(node.status) for node in self._nodes], now, _board)

    def end(self, status: str, reason: str) -> None:
        """The statuses stay as the last tick left them."""


def groot2_monitor(view: MonitorView) -> Callable[[Wiring], None]:
    """A plug for :func:`~executive.runtime.assembly.build_runtime`: every run's tree served to Groot2 through ``view``."""

    def plug(w: Wiring) -> None:
        w.observers.append(Groot2Monitor(view))

    return plug
