"""BehaviorTree.CPP v4 XML (the format Groot2 opens and edits) to and from a mission's YAML tree.

Written as BehaviorTree.CPP's own writer does (``src/xml_parsing.cpp``: ``writeTreeNodesModelXML``,
``addNodeModelToXML``, ``addTreeToXML``; its XSD, ``writeTreeXSD``):

- ``<root BTCPP_format="4" main_tree_to_execute="ID">`` holding ``<BehaviorTree ID="...">`` with
  exactly one child, then one ``<TreeNodesModel>``;
- a node in the compact form: the element is its registration ID (``<ekf_ok name="EKF ok?"/>``),
  its ports are attributes, ``name`` is the instance name;
- ``<TreeNodesModel>`` has one element per node type, tagged by its kind (``toStr(NodeType)``,
  basic_types.cpp: ``Action``, ``Condition``, ``Control``, ``Decorator``), with ``ID``, and
  ``<input_port name= type= default=>`` elements whose text is the description, then an optional
  ``<description>`` (the XSD's ``treeNodesModelNodeType``).

Our catalogue (:mod:`executive.tree.catalogue`) maps onto it by the children a node takes, as
BehaviorTree.CPP checks them: none, a Condition (a guard) or an Action (built-in subtrees too: their
content is Python, not XML); one, a Decorator; more, a Control, its child slots in order
(``failsafe_guarded``: the work, then the guards). A value parameter is an input port; the
mission's YAML tree form is :mod:`executive.tree.composition`'s. A BehaviorTree.CPP blackboard reference
(``{key}``) has no meaning here and is refused on import.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any
from xml.parsers import expat

from executive.mission.errors import FieldError, MissionError
from executive.tree.composition import NODE, USE

#: The catalogue's parameter types -> the port types BehaviorTree.CPP writes (``BT::demangle`` of the C++ type).
PORT_TYPES = {
    "bool": "bool", "int": "int", "float": "double", "str": "std::string", "one of": "std::string", "node name": "std::string",
    "numbers": "std::vector<double>", "range": "std::vector<double>", "enu": "std::vector<double>",
}  # fmt: skip
#: Compound values as BehaviorTree.CPP writes vectors: the items joined by ``;`` (``convertFromString<std::vector<double>>``, basic_types.h).
FIELDS = {"range": ("min", "max"), "enu": ("east", "north", "up")}
#: BehaviorTree.CPP's built-in nodes that are ours under another name: (our node, fixed parameters, port -> parameter); ``export``
#: writes them, ``import`` reads them (and our own lower-case names). Sequence and Fallback resume the RUNNING child and start over
#: after a result, as py_trees' composites with memory; the reactive ones tick every child again each tick (sequence_node.h,
#: fallback_node.h, reactive_sequence.h, reactive_fallback.h). RetryUntilSuccessful gives up after num_attempts failures, Repeat
#: ends after num_cycles successes (retry_node.h, repeat_node.h). Timeout fails its RUNNING child after msec (timeout_node.h;
#: ours counts vehicle time). Parallel (parallel_node.cpp) with failure_count 1 fails at a child's failure, success_count -1 (all)
#: or 1; it decides after each child, py_trees' Parallel after ticking them all: see :func:`differences`.
BUILT_IN_NODES: dict[str, tuple[str, dict[str, Any], dict[str, str]]] = {
    "Sequence": ("sequence", {"memory": True}, {}),
    "ReactiveSequence": ("sequence", {"memory": False}, {}),
    "Fallback": ("selector", {"memory": True}, {}),
    "ReactiveFallback": ("selector", {"memory": False}, {}),
    "Parallel": ("parallel", {}, {"success_count": "policy", "failure_count": "policy"}),
    "Inverter": ("inverter", {}, {}),
    "RetryUntilSuccessful": ("retry", {}, {"num_attempts": "failures"}),
    "Repeat": ("repeat", {}, {"num_cycles": "successes"}),
    "Timeout": ("timeout", {}, {"msec": "timeout_s"}),
}
#: Parallel's (success_count, failure_count) -> our policy (BehaviorTree.CPP's defaults: -1, 1).
PARALLEL_POLICIES = {(-1, 1): "success_on_all", (1, 1): "success_on_one"}
#: Our nodes that are always written as a built-in (so not declared in the TreeNodesModel).
WRITTEN_AS_BUILT_INS = frozenset(node for node, _, _ in BUILT_IN_NODES.values())
#: Our nodes with more than one slot of children, each written as a Decorator of ours over one built-in composite holding them all,
#: in this order: what the node builds (trees/parts.py: ``failsafe_guarded`` ticks the guards, then the work, every tick, under its
#: failsafe; ``mission_root`` the steps in order, with memory, held while PAUSED). BehaviorTree.CPP checks a Control's children
#: by their number only, and its Python bindings register no Control node of ours; a Decorator loads.
GROUPED_CHILDREN: dict[str, tuple[str, tuple[str, ...]]] = {
    "failsafe_guarded": ("ReactiveSequence", ("guards", "work")),
    "mission_root": ("Sequence", ("steps",)),
}
MAIN_TREE = "MainTree"
MAX_BYTES = 1 << 20


@dataclass(frozen=True)
class Port:
    """A node type's parameter that is a value (not a child) as a port."""

    name: str
    type: str  # the catalogue's type (bool, int, float, str, one of, node name, numbers, range, enu)
    default: Any = None
    required: bool = False
    doc: str = ""
    unit: str = ""
    choices: tuple[str, ...] = ()
    nullable: bool = False
    from_mission: str | None = None


@dataclass(frozen=True)
class Slot:
    """A node type's parameter that holds children: one node (``many`` False) or a list."""

    name: str
    many: bool
    required: bool = True


@dataclass(frozen=True)
class NodeType:
    """A node type of the catalogue as BehaviorTree.CPP models it."""

    id: str
    kind: str  # guard | action | decorator | composite | subtree
    doc: str = ""
    ports: tuple[Port, ...] = ()
    slots: tuple[Slot, ...] = ()

    @property
    def model_tag(self) -> str:
        """Its NodeType in BehaviorTree.CPP (``toStr(NodeType)``): by the children it takes, as BehaviorTree.CPP checks them.

        No children: Condition (a guard) or Action; one child, or its children grouped under one built-in (:data:`GROUPED_CHILDREN`):
        Decorator; more (or a list): Control.
        """
        if not self.slots:
            return "Condition" if self.kind == "guard" else "Action"
        if self.id in GROUPED_CHILDREN:
            return "Decorator"
        return "Decorator" if len(self.slots) == 1 and not self.slots[0].many else "Control"


def node_types(catalogue: Any) -> dict[str, NodeType]:
    """Every node of the catalogue (:class:`executive.tree.catalogue.Catalogue`) as a BehaviorTree.CPP node type, by ID."""
    types: dict[str, NodeType] = {}
    for spec in catalogue.nodes():
        slots = tuple(Slot(p.name, p.type in ("nodes", "guards"), p.required) for p in spec.params if p.is_child)
        if sum(slot.many for slot in slots) > 1:
            continue  # two lists of children cannot be told apart in one list of XML children
        ports = tuple(
            Port(p.name, p.type, p.default, p.required, p.doc, p.unit, tuple(p.choices), p.nullable, p.from_mission)
            for p in spec.params
            if not p.is_child and p.type in PORT_TYPES and p.name != "name"
        )
        types[spec.name] = NodeType(spec.name, spec.kind, spec.doc, ports, slots)
    return types


@dataclass
class Node:
    """One node of a tree, neutral between YAML and XML: its type, instance name, value parameters and children by slot."""

    type: str
    name: str | None = None
    params: dict[str, Any] = field(default_factory=dict)
    slots: dict[str, list[Node]] = field(default_factory=dict)


# -- writing ------------------------------------------------------------------------------------


def port_text(value: Any, kind: str) -> str:
    """A parameter's value as a port's string (what BehaviorTree.CPP's ``convertFromString`` reads back)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if kind in FIELDS and isinstance(value, Mapping):
        return ";".join(port_text(value[f], "float") for f in FIELDS[kind] if f in value)
    if isinstance(value, list | tuple):
        return ";".join(port_text(v, "float") for v in value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


def write_xml(root: Node, types: Mapping[str, NodeType], tree_id: str = MAIN_TREE) -> str:
    """The tree as a BehaviorTree.CPP v4 document, with a TreeNodesModel of every node type in ``types`` not written as a built-in.

    Our standard composites and decorators are written as the built-ins that mean the same (:data:`BUILT_IN_NODES`), a node of
    ours with several slots of children as a Decorator over one built-in composite (:data:`GROUPED_CHILDREN`).
    """
    doc = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": tree_id})
    tree = ET.SubElement(doc, "BehaviorTree", {"ID": tree_id})
    _write_node(tree, root, types)
    model = ET.SubElement(doc, "TreeNodesModel")
    for spec in sorted(types.values(), key=lambda t: t.id):
        if spec.id in WRITTEN_AS_BUILT_INS:
            continue
        element = ET.SubElement(model, spec.model_tag, {"ID": spec.id})
        for port in spec.ports:
            attributes = {"name": port.name, "type": PORT_TYPES[port.type]}
            if not port.required and port.from_mission is None and (port.default is not None or port.nullable):
                attributes["default"] = port_text(port.default, port.type)
            ET.SubElement(element, "input_port", attributes).text = _port_doc(port)
        ET.SubElement(element, "description").text = spec.doc + _slots_doc(spec)
    ET.indent(doc, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(doc, encoding="unicode") + "\n"


def _port_doc(port: Port) -> str:
    unit = f" [{port.unit}]" if port.unit else ""
    choices = f" (one of: {', '.join(port.choices)})" if port.choices else ""
    fields = f" ({';'.join(FIELDS[port.type])})" if port.type in FIELDS else ""
    source = f" (default: the mission's {port.from_mission})" if port.from_mission else ""
    return f"{port.doc}{unit}{choices}{fields}{source}"


def _slots_doc(spec: NodeType) -> str:
    slots = {s.name: s for s in spec.slots}
    if spec.id in GROUPED_CHILDREN:
        composite, order = GROUPED_CHILDREN[spec.id]
        held = ", then ".join(f"the {name} ({'any number' if slots[name].many else 'one'})" for name in order)
        return f" Its one child: a {composite} of {held}."
    if len(spec.slots) < 2:
        return ""
    return " Children, in order: " + ", ".join(f"{s.name} ({'any number' if s.many else 'one'})" for s in spec.slots) + "."


def _value(node: Node, spec: NodeType, name: str) -> Any:
    """A parameter of the node: given, or its default."""
    return node.params.get(name, next((p.default for p in spec.ports if p.name == name), None))


def built_in(node: Node, spec: NodeType) -> tuple[str, dict[str, str]] | None:
    """The BehaviorTree.CPP built-in (its ID and ports) that means what ``node`` does, or None (see :data:`BUILT_IN_NODES`)."""
    if node.type not in WRITTEN_AS_BUILT_INS or spec.id != node.type:
        return None
    if node.type in ("sequence", "selector"):
        memory = bool(_value(node, spec, "memory"))
        return {"sequence": ("Sequence", "ReactiveSequence"), "selector": ("Fallback", "ReactiveFallback")}[node.type][not memory], {}
    if node.type == "parallel":
        counts = next(c for c, policy in PARALLEL_POLICIES.items() if policy == _value(node, spec, "policy"))
        return "Parallel", {"success_count": str(counts[0]), "failure_count": str(counts[1])}
    if node.type == "timeout":
        return "Timeout", {"msec": str(round(float(_value(node, spec, "timeout_s")) * 1000))}
    tag, _, renamed = next((t, f, r) for t, (ours, f, r) in BUILT_IN_NODES.items() if ours == node.type)
    return tag, {port: str(_value(node, spec, param)) for port, param in renamed.items()}


def _write_node(parent: ET.Element, node: Node, types: Mapping[str, NodeType]) -> None:
    spec = types.get(node.type)
    attributes = {"name": node.name} if node.name is not None else {}
    as_built_in = built_in(node, spec) if spec is not None else None
    if as_built_in is not None:
        tag, ports = as_built_in
        attributes |= ports
    else:
        kinds = {p.name: p.type for p in spec.ports} if spec is not None else {}
        tag = node.type
        attributes |= {k: port_text(v, kinds.get(k, "")) for k, v in node.params.items()}
    element = ET.SubElement(parent, tag, attributes)
    if node.type in GROUPED_CHILDREN and spec is not None:
        composite, order = GROUPED_CHILDREN[node.type]
        element = ET.SubElement(element, composite)
    else:
        order = tuple(s.name for s in spec.slots) if spec is not None else tuple(node.slots)
    for slot in order:
        for child in node.slots.get(slot, ()):
            _write_node(element, child, types)


def differences(root: Node, types: Mapping[str, NodeType]) -> list[tuple[str, str]]:
    """Where BehaviorTree.CPP would run the written tree otherwise than we do, or could not load it without C++ of ours: (node path, why)."""
    out: list[tuple[str, str]] = []

    def visit(node: Node, path: str) -> None:
        here = f"{path}/{node.name or node.type}"
        spec = types.get(node.type)
        if node.type == "once":
            out.append((here, "once is written as our own decorator: BehaviorTree.CPP's RunOnce keeps its child's first FAILURE for good, "
                              "ours ticks the child again until it succeeds (run_once_node.h)"))  # fmt: skip
        elif node.type == "parallel" and spec is not None and _value(node, spec, "policy") == "success_on_one":
            out.append((here, "Parallel success_count=1: in a tick where one child succeeds and a later one fails, BehaviorTree.CPP's "
                              "succeeds, ours fails (parallel_node.cpp decides after each child)"))  # fmt: skip
        elif node.type == "timeout" and spec is not None and float(_value(node, spec, "timeout_s")) * 1000 % 1:
            out.append((here, f"Timeout msec is whole milliseconds: {_value(node, spec, 'timeout_s')} s written rounded"))
        elif spec is not None and spec.model_tag == "Control" and built_in(node, spec) is None:
            out.append((here, f"{node.type} is a Control node of ours: BehaviorTree.CPP loads it only with a C++ node registered as it"))
        for children in node.slots.values():
            for child in children:
                visit(child, here)

    visit(root, "")
    return out


# -- reading ------------------------------------------------------------------------------------


@dataclass
class _Element:
    """An XML element with where it starts (1-based line and column)."""

    tag: str
    attributes: dict[str, str]
    line: int
    column: int
    children: list[_Element] = field(default_factory=list)


def _parse(text: str, filename: str) -> _Element:
    """The document's root element, each element with its line; MissionError for what is not well-formed XML.

    expat reports positions (ElementTree does not); a DTD (and with it any entity) is refused.
    """
    stack: list[_Element] = []
    found: list[_Element] = []
    parser = expat.ParserCreate()

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = _Element(tag, attributes, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        (stack[-1].children if stack else found).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def doctype(*_: object) -> None:
        raise MissionError([FieldError(filename, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "(file)", "a DTD is not allowed")])

    parser.StartElementHandler, parser.EndElementHandler, parser.StartDoctypeDeclHandler = start, end, doctype
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        where = FieldError(filename, exc.lineno, exc.offset + 1, "(file)", f"not well-formed XML: {expat.ErrorString(exc.code)}")
        raise MissionError([where]) from None
    return found[0]


def read_xml(text: str, filename: str, types: Mapping[str, NodeType]) -> Node:
    """The main tree of a BehaviorTree.CPP v4 document as a :class:`Node`; MissionError naming every problem with its line.

    Nodes are read in the compact form (``<ekf_ok/>``) and in the explicit one (``<Condition ID="ekf_ok"/>``);
    the TreeNodesModel is not needed (our catalogue is the model) and is skipped.
    """
    if len(text.encode("utf-8", "surrogatepass")) > MAX_BYTES:
        raise MissionError([FieldError(filename, 1, 1, "(file)", f"larger than {MAX_BYTES // (1024 * 1024)} MiB")])
    root = _parse(text, filename)
    errors: list[FieldError] = []

    def error(element: _Element, where: str, why: str) -> None:
        errors.append(FieldError(filename, element.line, element.column, where, why))

    if root.tag != "root":
        error(root, root.tag, 'the document\'s element must be <root BTCPP_format="4">')
        raise MissionError(errors)
    if root.attributes.get("BTCPP_format") != "4":
        error(root, "root.BTCPP_format", f"{root.attributes.get('BTCPP_format')!r}: only BehaviorTree.CPP format 4 is read")
    trees = {e.attributes.get("ID", f"BehaviorTree_{i}"): e for i, e in enumerate(c for c in root.children if c.tag == "BehaviorTree")}
    main = root.attributes.get("main_tree_to_execute", next(iter(trees), MAIN_TREE))
    if main not in trees:
        error(root, "root.main_tree_to_execute", f"no <BehaviorTree ID={main!r}> in the file" if trees else "no <BehaviorTree> in the file")
        raise MissionError(errors)
    tree = trees[main]
    if len(tree.children) != 1:
        error(tree, f"BehaviorTree[{main}]", f"must have exactly one child node, has {len(tree.children)}")
        raise MissionError(errors)
    node = _read_node(tree.children[0], types, error, main)
    if errors:
        raise MissionError(errors)
    return node


def _read_node(element: _Element, types: Mapping[str, NodeType], error: Callable[[_Element, str, str], None], path: str) -> Node:
    explicit = element.tag in ("Action", "Condition", "Control", "Decorator")
    type_id = element.attributes.get("ID", "") if explicit else element.tag
    here = f"{path}/{type_id or element.tag}"
    tag = type_id
    type_id, fixed, renamed = BUILT_IN_NODES.get(type_id, (type_id, {}, {})) if type_id not in types else (type_id, {}, {})
    spec = types.get(type_id)
    if spec is None:
        error(element, here, f"unknown node type {type_id!r} (not in the catalogue: executive behaviours lists it)")
        return Node(type_id)
    node = Node(type_id, name=element.attributes.get("name"))
    ports = {p.name: p for p in spec.ports}
    node.params = {k: v for k, v in fixed.items() if v != ports[k].default}
    counts: dict[str, int] = {}
    for key, raw in element.attributes.items():
        if key in ("name", "ID") or key.startswith("_"):  # _uid, _fullpath: Groot2's bookkeeping
            continue
        port = ports.get(renamed.get(key, key))
        if port is None or (key == port.name and key not in renamed and tag != type_id):
            known = ", ".join(renamed) if tag != type_id else ", ".join(ports)
            error(element, f"{here}.{key}", f"unknown port (ports of {tag}: {known or 'none'})")
            continue
        try:
            if tag == "Parallel":
                counts[key] = int(_number(raw.strip(), "int"))
            elif tag == "Timeout":
                node.params[port.name] = _milliseconds(raw) / 1000
            else:
                node.params[port.name] = port_value(raw, port)
        except ValueError as exc:
            error(element, f"{here}.{key}", f"{raw!r}: {exc}")
    if tag == "Parallel" and type_id == "parallel":
        pair = (counts.get("success_count", -1), counts.get("failure_count", 1))
        if pair not in PARALLEL_POLICIES:
            error(element, here, f"success_count={pair[0]}, failure_count={pair[1]}: no node of ours does that (parallel: -1 or 1, and 1)")
        elif PARALLEL_POLICIES[pair] != ports["policy"].default:
            node.params["policy"] = PARALLEL_POLICIES[pair]
    order = [s.name for s in spec.slots]
    kids = element.children
    if type_id in GROUPED_CHILDREN and len(kids) == 1 and kids[0].tag == GROUPED_CHILDREN[type_id][0]:
        group = kids[0]  # the children, grouped as export writes them (our lower-case form holds them directly)
        for key in group.attributes:
            if not key.startswith("_"):
                error(group, f"{here}/{group.tag}.{key}", f"the {group.tag} that holds {type_id}'s children takes no ports")
        kids, order = group.children, list(GROUPED_CHILDREN[type_id][1])
    children = [_read_node(child, types, error, here) for child in kids]
    slots = {s.name: s for s in spec.slots}
    singles = sum(not s.many for s in spec.slots)
    many = next((s for s in spec.slots if s.many), None)
    least = singles + (1 if many is not None and many.required else 0)
    if len(children) < least or (many is None and len(children) > singles):
        wanted = f"exactly {singles}" if many is None else f"at least {least}"
        names = ", ".join(order) or "none"
        error(element, here, f"{type_id} takes {wanted} child node{'' if wanted.endswith(' 1') else 's'} ({names}), has {len(children)}")
        return node
    rest = iter(children)
    for name in order:
        slot = slots[name]
        taken = [next(rest) for _ in range(len(children) - singles if slot.many else 1)]
        if taken or slot.required:
            node.slots[slot.name] = taken
    return node


def _milliseconds(raw: str) -> int:
    """Timeout's msec (an unsigned integer in BehaviorTree.CPP)."""
    number = int(_number(raw.strip(), "int"))
    if number < 0:
        raise ValueError("not a number of milliseconds (0 or more)")
    return number


def port_value(raw: str, port: Port) -> Any:
    """A port's string as the parameter's value (ValueError saying why it is not one)."""
    text = raw.strip()
    if text.startswith("{") and text.endswith("}"):
        raise ValueError("a blackboard reference ({key}) is not supported here: give the value")
    if port.nullable and text == "null":
        return None
    if port.type in FIELDS or port.type == "numbers":
        numbers = [_number(part, "float") for part in text.split(";")] if text else []
        if port.type == "numbers":
            return numbers
        if len(numbers) != len(FIELDS[port.type]):
            raise ValueError(f"{len(FIELDS[port.type])} numbers separated by ';' ({';'.join(FIELDS[port.type])})")
        return dict(zip(FIELDS[port.type], numbers, strict=True))
    if port.type == "bool":  # what BehaviorTree.CPP's convertFromString<bool> takes (basic_types.h)
        if text not in ("true", "false", "TRUE", "FALSE", "1", "0"):
            raise ValueError("not true or false")
        return text in ("true", "TRUE", "1")
    if port.type in ("int", "float"):
        return _number(text, port.type)
    if port.choices and raw not in port.choices:
        raise ValueError(f"not one of {', '.join(port.choices)}")
    return raw


def _number(text: str, kind: str) -> int | float:
    try:
        number = int(text) if kind == "int" else float(text)
    except ValueError:
        raise ValueError("not an integer" if kind == "int" else "not a number") from None
    if not math.isfinite(number):
        raise ValueError("not a finite number")
    return number


# -- the mission file's YAML tree ---------------------------------------------------------------

#: How a node is written in a mission's ``tree:`` (:mod:`executive.tree.composition`): its type, a built-in subtree, its name.
TYPE_KEY, USE_KEY, NAME_KEY = NODE, USE, "name"


def from_yaml(data: Mapping[str, Any] | str, types: Mapping[str, NodeType]) -> Node:
    """A (validated) YAML tree node as a :class:`Node`: a mapping with ``node:`` or ``use:``, or a bare name."""
    if isinstance(data, str):
        return Node(data)
    type_id = data[USE_KEY] if USE_KEY in data else data[TYPE_KEY]
    spec = types[type_id]
    slots = {s.name: s for s in spec.slots}
    node = Node(type_id, name=data.get(NAME_KEY))
    for key, value in data.items():
        if key in (TYPE_KEY, USE_KEY, NAME_KEY):
            continue
        if key in slots:
            children = value if slots[key].many else [value]
            node.slots[key] = [from_yaml(child, types) for child in children]
        else:
            node.params[key] = value
    return node


def to_yaml(node: Node, types: Mapping[str, NodeType]) -> dict[str, Any] | str:
    """A :class:`Node` as a YAML tree node: type first, then name, parameters, children; a node (not a subtree) without any: its bare name."""
    spec = types[node.type]
    if spec.kind != "subtree" and node.name is None and not node.params and not any(node.slots.values()):
        return node.type
    data: dict[str, Any] = {USE_KEY if spec.kind == "subtree" else TYPE_KEY: node.type}
    if node.name is not None:
        data[NAME_KEY] = node.name
    data |= node.params
    for slot in spec.slots:
        if slot.name in node.slots:
            children = [to_yaml(child, types) for child in node.slots[slot.name]]
            data[slot.name] = children if slot.many else children[0]
    return data


# -- files --------------------------------------------------------------------------------------


def import_tree(path: str, catalogue: Any) -> dict[str, Any]:
    """The main tree of a BehaviorTree.CPP v4 file as a mission's YAML ``tree:``; MissionError naming every problem with its line."""
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_BYTES + 1)
    except OSError as exc:
        raise MissionError([FieldError(path, 1, 1, "(file)", exc.strerror or str(exc))]) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MissionError([FieldError(path, 1, 1, "(file)", f"not UTF-8 text: byte 0x{data[exc.start]:02x} at offset {exc.start}")]) from None
    types = node_types(catalogue)
    return to_yaml(read_xml(text, path, types), types)
