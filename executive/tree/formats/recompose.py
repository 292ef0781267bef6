"""A tree built in Python (a built-in tree, a plugin's) described as catalogue nodes: what ``export --format btcpp`` writes for a named tree.

:func:`export_tree` writes a mission's tree, named or composed in its file, as a BehaviorTree.CPP v4 document.

Each behaviour becomes the catalogue node of its class, its parameters read back from the
attributes of the same names, or those its class's ``param_attributes`` (parameter -> attribute)
names; those equal to the default, or to the mission's value they default to, are left out
(a tree built in Python takes them from the mission too). py_trees' composites and
decorators become ``sequence``, ``selector``, ``parallel``, ``inverter``, ``retry``, ``repeat`` and
``once`` (written as BehaviorTree.CPP's built-ins where one means the same: :data:`executive.tree.formats.btcpp.BUILT_IN_NODES`).
What ``failsafe_guarded`` and ``checked`` make (a selector of the guarded work, or of a guard, and a failsafe) is folded back
into them. A behaviour the catalogue does not offer keeps its
class name, and is reported: Groot2 shows it, ``import`` refuses it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import py_trees
import yaml

from executive import registry
from executive.behaviours.failsafe import Failsafe
from executive.behaviours.guards import Guard
from executive.tree import select as mission_tree
from executive.tree.catalogue import mission_value
from executive.tree.formats.btcpp import FIELDS, Node, NodeType, Port, Slot, differences, from_yaml, node_types, write_xml

if TYPE_CHECKING:
    from executive.mission.model import Mission

#: py_trees' own classes -> (catalogue node, parameter -> how to read it from the instance).
PY_TREES: dict[type, tuple[str, dict[str, Any]]] = {
    py_trees.composites.Sequence: ("sequence", {"memory": lambda n: n.memory}),
    py_trees.composites.Selector: ("selector", {"memory": lambda n: n.memory}),
    py_trees.composites.Parallel: (
        "parallel",
        {"policy": lambda n: "success_on_one" if isinstance(n.policy, py_trees.common.ParallelPolicy.SuccessOnOne) else "success_on_all"},
    ),
    py_trees.decorators.Inverter: ("inverter", {}),
    py_trees.decorators.Retry: ("retry", {"failures": lambda n: n.num_failures}),
    py_trees.decorators.Repeat: ("repeat", {"successes": lambda n: n.num_success}),
    py_trees.decorators.OneShot: ("once", {}),
}
_UNREADABLE = object()


class Recomposer:
    """Describes built trees with the node types of a catalogue (:func:`executive.tree.formats.btcpp.node_types`)."""

    def __init__(self, types: Mapping[str, NodeType], catalogue: Any, mission: Mission) -> None:
        self.types = types
        self.mission = mission
        self.by_class = {spec.factory: spec.name for spec in catalogue.nodes() if isinstance(spec.factory, type)}
        self.default_names = {spec.name: p.default for spec in catalogue.nodes() if (p := spec.param("name")) is not None and p.type == "str"}
        #: What could not be described exactly: (node path, why).
        self.warnings: list[tuple[str, str]] = []
        #: Node types the catalogue does not have, as they were met (so the model still describes them).
        self.unknown: dict[str, NodeType] = {}

    def node(self, behaviour: py_trees.behaviour.Behaviour, path: str = "") -> Node:
        """``behaviour`` and what is under it, as catalogue nodes."""
        here = f"{path}/{behaviour.name}"
        folded = self._folded(behaviour, here)
        if folded is not None:
            return folded
        node = self._describe(behaviour, here)
        if node is None:
            return self._unknown(behaviour, here)
        self._children(node, self.types[node.type], list(behaviour.children), here)
        return node

    def describe_one(self, behaviour: py_trees.behaviour.Behaviour) -> Node | None:
        """``behaviour`` alone as its catalogue node (its type and parameters; no children, nothing folded); None if the catalogue
        does not offer its class (a Groot2 monitor's view of each running node)."""
        return self._describe(behaviour, behaviour.name)

    def _describe(self, behaviour: py_trees.behaviour.Behaviour, here: str) -> Node | None:
        cls = type(behaviour)
        type_id, readers = PY_TREES.get(cls, (self.by_class.get(cls), {}))
        if type_id is None or type_id not in self.types:
            return None
        spec = self.types[type_id]
        attributes: Mapping[str, str] = getattr(cls, "param_attributes", {})
        name = getattr(behaviour, attributes.get("name", "name"))
        node = Node(type_id, name=None if name == self.default_names.get(type_id) else name)
        for port in spec.ports:
            value = readers[port.name](behaviour) if port.name in readers else self._attribute(behaviour, port, attributes)
            value = _as_port_value(value, port)
            if port.from_mission is not None and (value is _UNREADABLE or value == self._mission_value(port)):
                continue  # the mission's, as the tree built in Python has it
            if value is _UNREADABLE:
                self.warnings.append((here, f"{port.name}: not readable from the {cls.__name__}: left at its default"))
            elif value != port.default:
                node.params[port.name] = value
        return node

    def _mission_value(self, port: Port) -> Any:
        assert port.from_mission is not None
        return _as_port_value(mission_value(port.from_mission, self.mission), port)

    def _attribute(self, behaviour: py_trees.behaviour.Behaviour, port: Port, attributes: Mapping[str, str]) -> Any:
        if port.name == "awaiting_recovery" and isinstance(behaviour, Guard):
            return behaviour._failed and behaviour._passed  # set by Guard.awaiting_recovery()
        value = getattr(behaviour, attributes.get(port.name, port.name), _UNREADABLE)
        return value.name if port.type == "node name" and isinstance(value, py_trees.behaviour.Behaviour) else value

    def _children(self, node: Node, spec: NodeType, children: list[py_trees.behaviour.Behaviour], here: str) -> None:
        singles = sum(not s.many for s in spec.slots)
        if len(children) < singles or (len(children) > singles and not any(s.many for s in spec.slots)):
            self.warnings.append(
                (here, f"{len(children)} children where {spec.id} takes {', '.join(s.name for s in spec.slots) or 'none'}: left out")
            )
            return
        rest = iter(children)
        for slot in spec.slots:
            taken = [self.node(child, here) for child in [next(rest) for _ in range(len(children) - singles if slot.many else 1)]]
            if taken or slot.required:
                node.slots[slot.name] = taken

    def _folded(self, behaviour: py_trees.behaviour.Behaviour, here: str) -> Node | None:
        """What ``failsafe_guarded`` (executive.trees.parts.failsafe_guarded) or ``checked`` made, as that node; None for anything else."""
        kids = list(behaviour.children)
        if type(behaviour) is not py_trees.composites.Selector or len(kids) != 2 or not isinstance(kids[1], Failsafe):
            return None
        first = kids[0]
        if type(first) is py_trees.composites.Sequence and not first.memory and behaviour.name == f"{first.name} or hold" and first.children:
            *guards, work = first.children
            node = Node("failsafe_guarded", name=None if first.name == self.default_names.get("failsafe_guarded") else first.name)
            node.slots = {"work": [self.node(work, here)], "guards": [self.node(g, here) for g in guards]}
            return node
        if isinstance(first, Guard):
            name = None if behaviour.name == f"{first.name} or failsafe" else behaviour.name
            return Node("checked", name=name, slots={"guard": [self.node(first, here)]})
        return None

    def _unknown(self, behaviour: py_trees.behaviour.Behaviour, here: str) -> Node:
        cls = type(behaviour)
        if isinstance(behaviour, py_trees.decorators.Decorator):
            kind, slots = "decorator", (Slot("child", False),)
        elif isinstance(behaviour, py_trees.composites.Composite):
            kind, slots = "composite", (Slot("children", True, required=False),)
        else:
            kind, slots = ("guard" if isinstance(behaviour, Guard) else "action"), ()
        self.unknown.setdefault(cls.__name__, NodeType(cls.__name__, kind, f"{cls.__module__}.{cls.__qualname__}: not in the catalogue", (), slots))
        self.warnings.append((here, f"{cls.__name__} is not in the catalogue: Groot2 shows it, import refuses it"))
        node = Node(cls.__name__, name=behaviour.name)
        self._children(node, self.unknown[cls.__name__], list(behaviour.children), here)
        return node


def _as_port_value(value: Any, port: Port) -> Any:
    """An attribute's value as the port's parameter value, or _UNREADABLE when it is not one."""
    if value is _UNREADABLE:
        return value
    if value is None:
        return None if port.nullable or port.default is None else _UNREADABLE
    if port.type in FIELDS:
        fields = FIELDS[port.type]
        ok = all(isinstance(getattr(value, f, None), int | float) for f in fields)
        return {f: float(getattr(value, f)) for f in fields} if ok else _UNREADABLE
    if port.type == "numbers":
        ok = isinstance(value, list | tuple) and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        return [float(v) for v in value] if ok else _UNREADABLE
    if port.type == "bool":
        return value if isinstance(value, bool) else _UNREADABLE
    if isinstance(value, bool):
        return _UNREADABLE
    if port.type == "int":
        return value if isinstance(value, int) else _UNREADABLE
    if port.type == "float":
        return float(value) if isinstance(value, int | float) else _UNREADABLE
    if not isinstance(value, str) or (port.choices and value not in port.choices):
        return _UNREADABLE
    return value


def export_tree(mission_file: str, mission: Mission, catalogue: Any) -> tuple[str, list[tuple[str, str]]]:
    """The tree of a (valid) mission file as a BehaviorTree.CPP v4 document, and what could not be described exactly (node path, why).

    A tree written in the file (``tree:`` a mapping) is written as it is; a named tree (built in
    Python) as the nodes it builds (:class:`Recomposer`). The differences are also where BehaviorTree.CPP
    would run it otherwise, or needs C++ of ours to load it (:func:`executive.tree.formats.btcpp.differences`).
    """
    with open(mission_file, encoding="utf-8") as stream:
        tree = (yaml.safe_load(stream) or {}).get("tree", registry.DEFAULT_TREE)
    types = node_types(catalogue)
    if isinstance(tree, Mapping):
        root = from_yaml(tree, types)
        return write_xml(root, types, mission.name), differences(root, types)
    recomposer = Recomposer(types, catalogue, mission)
    root = recomposer.node(mission_tree.build(mission))
    described = {**types, **recomposer.unknown}
    return write_xml(root, described, mission.name), recomposer.warnings + differences(root, described)
