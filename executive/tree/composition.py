"""Trees composed in the mission file: ``tree:`` as a mapping of catalogue nodes, checked with every error located, then built.

Grammar (every name and parameter is in ``executive behaviours``)::

    tree:                        # one node: the root
      node: sequence             # node: NAME of a guard, action, decorator or composite ...
      name: Run                  # ... with its parameters as keys beside it
      children:                  # child slots (children, child, guards, work, steps, guard) hold nodes
        - use: preflight         # use: NAME of a built-in subtree, with its parameters
        - armed                  # a node without parameters may be just its name
        - node: set_mode
          mode: GUIDED

A parameter left out takes its default, or the mission's value the catalogue names (``go_to``'s
``acceptance_radius_m`` is ``limits.acceptance_radius_m``). A guard takes its debounce
(``hold_after_s``, ``resume_after_s``) and ``awaiting_recovery`` too. A ``node name`` parameter
(``failsafe_note``'s ``guard``) names a guard that comes before it in the tree: the nearest one of
that name. The tree is built exactly as a Python builder would build it: the same classes, so
``show``, ``replay``, the journal and the snapshots see a tree like any other. A root other than
``mission_root`` or ``unless_paused`` is put under ``mission_root``: the runtime ticks the tree
while the mission is PAUSED, and only they stop the work and hold the vehicle then.
"""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import py_trees
from pydantic import ValidationError

from executive.behaviours.guards import Guard
from executive.mission.declaration import vehicle_profile
from executive.mission.errors import Path, format_path
from executive.mission.loader import describe_value  # the loader's wording for every other field
from executive.mission.model import Mission, Range
from executive.tree.catalogue import ACTION_SLOTS, Catalogue, NodeSpec, ParamSpec, catalogue, mission_value
from executive.trees.parts import mission_root

NODE, USE = "node", "use"
#: Roots that hold the vehicle while the mission is PAUSED; any other root is put under ``mission_root`` (a person always wins).
PAUSE_AWARE = frozenset({"mission_root", "unless_paused"})
#: Parameters that name a flight mode: checked against the vehicle's modes.
MODE_PARAMS = frozenset({"mode", "hold_mode", "fixed_wing_hold_mode", "mc_mode", "aux_mode"})

_EXPECTED = {"bool": "true or false", "int": "an integer", "float": "a number", "str": "a string"}


class CompositionError(ValueError):
    """A composed tree that cannot be built; carries every (path, why)."""

    def __init__(self, errors: list[tuple[Path, str]]) -> None:
        self.errors = errors
        super().__init__("; ".join(f"{format_path(p)}: {why}" for p, why in errors))


@dataclass
class _Plan:
    """One node of the file, checked: what to make and with what."""

    spec: NodeSpec
    path: Path
    values: dict[str, Any] = field(default_factory=dict)  # parameters given in the file
    children: dict[str, _Plan | list[_Plan]] = field(default_factory=dict)
    refs: dict[str, str] = field(default_factory=dict)  # parameter -> the name of the node it names

    def walk(self) -> Iterator[_Plan]:
        yield self
        for slot in self.children.values():
            for child in slot if isinstance(slot, list) else [slot]:
                yield from child.walk()


def is_composed(mission: Mission) -> bool:
    """The mission's tree is composed in its file (a mapping), not named."""
    return isinstance(mission.tree, dict)


def errors(mission: Mission, nodes: Catalogue | None = None) -> list[tuple[Path, str]]:
    """Every problem of the mission's composed tree, each at its path in the file (empty for a named tree)."""
    if not is_composed(mission):
        return []
    checker = _Checker(mission, nodes or catalogue())
    plan = checker.node(mission.tree, ("tree",), None)
    found = checker.errors + _sample_errors(mission, plan)
    if plan is not None and not checker.errors:
        try:
            _Builder(mission).make(plan)
        except CompositionError as exc:
            found += exc.errors
    return found


def build(mission: Mission, nodes: Catalogue | None = None) -> py_trees.behaviour.Behaviour:
    """The tree composed in the mission's file; CompositionError listing every problem."""
    checker = _Checker(mission, nodes or catalogue())
    plan = checker.node(mission.tree, ("tree",), None)
    if checker.errors or plan is None:
        raise CompositionError(checker.errors)
    root = _Builder(mission).make(plan)
    if plan.spec.name in PAUSE_AWARE:
        return root
    return mission_root(mission, root)


def _sample_errors(mission: Mission, plan: _Plan | None) -> list[tuple[Path, str]]:
    """Sample points need a sample node to take them."""
    if plan is None or any(p.spec.name == "sample" for p in plan.walk()):
        return []
    return [(("waypoints", i, "sample"), "no sample node in the tree takes it") for i, wp in enumerate(mission.waypoints) if wp.sample]


class _Checker:
    """Reads the file's tree against the catalogue, collecting every error."""

    def __init__(self, mission: Mission, nodes: Catalogue) -> None:
        self.mission, self.nodes = mission, nodes
        self.errors: list[tuple[Path, str]] = []

    def fail(self, path: Path, why: str) -> None:
        self.errors.append((path, why))

    def node(self, value: Any, path: Path, slot: tuple[str, ParamSpec] | None) -> _Plan | None:
        """The plan of one node of the file at ``path`` (None after reporting why it cannot be made); ``slot``: (parent, its parameter)."""
        if isinstance(value, str):
            spec = self._spec(value, path, None)
            given: dict[Any, Any] = {}
        elif isinstance(value, dict):
            keys = [k for k in (NODE, USE) if k in value]
            if len(keys) != 1:
                self.fail(path, "a node is node: NAME or use: SUBTREE, with its parameters" if not keys else "node: and use: together")
                return None
            key = keys[0]
            if not isinstance(value[key], str):
                self.fail((*path, key), f"expected a node name, got {describe_value(value[key])}")
                return None
            spec = self._spec(value[key], (*path, key), key)
            given = {k: v for k, v in value.items() if k != key}
        else:
            self.fail(path, f"expected a node: a name, or a mapping with node: or use:, got {describe_value(value)}")
            return None
        if spec is None:
            return None
        self._fits(spec, path, slot)
        return self._params(spec, given, path)

    def _spec(self, name: str, path: Path, key: str | None) -> NodeSpec | None:
        spec = self.nodes.get(name)
        if spec is None:
            close = difflib.get_close_matches(name, self.nodes.names(), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            self.fail(path, f"unknown node {name!r}{hint}; executive behaviours lists them")
            return None
        if key == USE and spec.kind != "subtree":
            self.fail(path, f"{name} is a {spec.kind}, not a built-in subtree: write node: {name}")
            return None
        if key == NODE and spec.kind == "subtree":
            self.fail(path, f"{name} is a built-in subtree: write use: {name}")
            return None
        return spec

    def _fits(self, spec: NodeSpec, path: Path, slot: tuple[str, ParamSpec] | None) -> None:
        """A guard only where guards go; anything that runs where the slot needs it."""
        if slot is None:
            return
        parent, param = slot
        if param.type in ("guard", "guards") and spec.kind != "guard":
            self.fail(path, f"{spec.name} is {_a(spec.kind)}: {parent}.{param.name} takes guards only")
        elif (parent, param.name) in ACTION_SLOTS and spec.kind == "guard":
            self.fail(path, f"{spec.name} is a guard, which never runs: {parent}.{param.name} needs an action, a composite or a subtree")

    def _params(self, spec: NodeSpec, given: dict[Any, Any], path: Path) -> _Plan:
        plan = _Plan(spec, path)
        known = {p.name: p for p in spec.params}
        for key, value in given.items():
            param = known.get(key) if isinstance(key, str) else None
            if param is None:
                self.fail((*path, key), f"unknown parameter of {spec.name} (allowed: {', '.join(known) or 'none'})")
            elif param.from_mission is not None and param.type == "(mission)":
                self.fail((*path, key), f"taken from the mission ({param.from_mission}), not given here")
            elif param.is_child:
                self._children(plan, param, value, (*path, key))
            elif param.name in spec.refs:
                if isinstance(value, str):
                    plan.refs[key] = value
                else:
                    self.fail((*path, key), f"expected the name of a guard of the tree, got {describe_value(value)}")
            else:
                checked = self._value(param, value, (*path, key))
                if checked is not _BAD:
                    plan.values[key] = checked
        for param in spec.params:
            if param.required and param.name not in given:
                self.fail((*path, param.name), f"required parameter of {spec.name} is missing ({_kind(param)})")
            elif param.from_mission and param.name not in given and not param.nullable and mission_value(param.from_mission, self.mission) is None:
                self.fail(path, f"{spec.name} needs {param.from_mission} in the mission (it has none), or {param.name}: here")
        return plan

    def _children(self, plan: _Plan, param: ParamSpec, value: Any, path: Path) -> None:
        if param.type in ("nodes", "guards"):
            if not isinstance(value, list):
                self.fail(path, f"expected a list of nodes, got {describe_value(value)}")
                return
            made = [self.node(item, (*path, i), (plan.spec.name, param)) for i, item in enumerate(value)]
            plan.children[param.name] = [m for m in made if m is not None]
            return
        child = self.node(value, path, (plan.spec.name, param))
        if child is not None:
            plan.children[param.name] = child

    def _value(self, param: ParamSpec, value: Any, path: Path) -> Any:
        """The value of a parameter as its type wants it, or _BAD after reporting why not."""
        if value is None:
            if param.nullable or (not param.required and param.default is None and param.from_mission is None):
                return None
            self.fail(path, f"expected {_kind(param)}, got null")
            return _BAD
        kind = param.type
        ok = {
            "bool": isinstance(value, bool),
            "int": isinstance(value, int) and not isinstance(value, bool),
            "float": isinstance(value, int | float) and not isinstance(value, bool),
            "str": isinstance(value, str),
        }
        if kind in ok:
            if not ok[kind]:
                self.fail(path, f"expected {_kind(param)}, got {describe_value(value)}")
                return _BAD
            if kind == "float":
                value = float(value)
            if param.name in MODE_PARAMS and value.upper() not in vehicle_profile(self.mission.vehicle).modes:
                known = ", ".join(m for m in vehicle_profile(self.mission.vehicle).modes if m != "INITIALISING")
                self.fail(path, f"{value!r}: not a {self.mission.vehicle} mode (known: {known})")
                return _BAD
            return value
        if kind == "one of":
            if value not in param.choices:
                self.fail(path, f"{describe_value(value)}: expected one of {', '.join(param.choices)}")
                return _BAD
            return value
        if kind == "range":
            return self._mapping(value, path, ("min", "max"), lambda v: Range.model_validate(v))
        if kind == "enu":
            from executive.world.frames import Enu

            return self._mapping(value, path, ("east", "north", "up"), lambda v: Enu(**{k: float(x) for k, x in v.items()}))
        if kind == "numbers":
            if not isinstance(value, list) or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
                self.fail(path, f"expected a list of numbers, got {describe_value(value)}")
                return _BAD
            return [float(v) for v in value]
        self.fail(path, f"cannot be given in a mission file ({kind})")
        return _BAD

    def _mapping(self, value: Any, path: Path, keys: tuple[str, ...], make: Any) -> Any:
        numbers = isinstance(value, dict) and all(isinstance(value.get(k), int | float) and not isinstance(value.get(k), bool) for k in keys)
        if not numbers or set(value) != set(keys):
            self.fail(path, f"expected a mapping of {', '.join(keys)} (numbers), got {describe_value(value)}")
            return _BAD
        try:
            return make(value)
        except ValidationError as exc:
            self.fail(path, "; ".join(e["msg"].removeprefix("Value error, ") for e in exc.errors(include_url=False)))
            return _BAD


_BAD = object()


class _Builder:
    """Makes the behaviours of a checked plan, children first; then resolves the node names parameters give."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission
        self.made: list[tuple[_Plan, py_trees.behaviour.Behaviour | None]] = []  # in the file's pre-order
        self.errors: list[tuple[Path, str]] = []

    def make(self, plan: _Plan) -> py_trees.behaviour.Behaviour:
        root = self._make(plan)
        self._resolve_refs()
        if self.errors or root is None:
            raise CompositionError(self.errors)
        return root

    def _make(self, plan: _Plan) -> py_trees.behaviour.Behaviour | None:
        """The behaviour of ``plan`` (None when it, or a child, could not be made: the reason is in :attr:`errors`)."""
        spot = len(self.made)
        self.made.append((plan, None))  # pre-order: a node before its children
        kwargs: dict[str, Any] = {}
        for param in plan.spec.params:
            if param.name in plan.values:
                kwargs[param.name] = plan.values[param.name]
            elif param.is_child and param.name in plan.children:
                slot = plan.children[param.name]
                kwargs[param.name] = [self._make(c) for c in slot] if isinstance(slot, list) else self._make(slot)
            elif param.from_mission is not None and param.name not in plan.refs:
                kwargs[param.name] = mission_value(param.from_mission, self.mission)
        slots = [kwargs[p.name] for p in plan.spec.child_params if p.name in kwargs]
        if any(child is None for slot in slots for child in (slot if isinstance(slot, list) else [slot])):
            return None
        extras = {k: kwargs.pop(k) for k in ("hold_after_s", "resume_after_s", "awaiting_recovery") if k in kwargs}
        try:
            node = _call(plan.spec, kwargs, self.mission)
        except (ValueError, TypeError, KeyError) as exc:
            self.errors.append((plan.path, f"{plan.spec.name}: {exc}"))
            return None
        if isinstance(node, Guard):
            for key in ("hold_after_s", "resume_after_s"):
                if key in extras:
                    setattr(node, key, extras[key])
            if extras.get("awaiting_recovery"):
                node.awaiting_recovery()
        self.made[spot] = (plan, node)
        return node

    def _resolve_refs(self) -> None:
        for i, (plan, node) in enumerate(self.made):
            for param, wanted in plan.refs.items():
                before = [n for _, n in self.made[:i] if isinstance(n, Guard) and n.name == wanted]
                if not before:
                    self.errors.append(((*plan.path, param), f"no guard named {wanted!r} comes before it in the tree"))
                elif node is not None:
                    setattr(node, param, before[-1])


def _call(spec: NodeSpec, kwargs: dict[str, Any], mission: Mission) -> py_trees.behaviour.Behaviour:
    """``spec``'s factory with these parameters (the mission to a factory that takes it; ``*steps`` given in order)."""
    if not spec.takes_mission:
        return spec.factory(**kwargs)
    parameters = inspect.signature(spec.factory).parameters
    varargs = next((p.name for p in parameters.values() if p.kind is p.VAR_POSITIONAL), None)
    if varargs is None:
        return spec.factory(mission=mission, **kwargs)
    return spec.factory(mission, *kwargs.pop(varargs, []), **kwargs)


def _kind(param: ParamSpec) -> str:
    if param.type in _EXPECTED:
        return _EXPECTED[param.type]
    if param.type in ("node", "guard"):
        return f"a {param.type}"
    if param.type in ("nodes", "guards"):
        return f"a list of {param.type}"
    if param.type == "one of":
        return f"one of {', '.join(param.choices)}"
    return param.type


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


# -- the JSON schema of a composed tree, for editors ----------------------------------------------------

_JSON_TYPES = {"bool": "boolean", "int": "integer", "float": "number", "str": "string", "node name": "string"}


def tree_json_schema(nodes: Catalogue | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """(the schema of a composed tree, the definitions it refers to): a node of the catalogue, with its parameters, recursively."""
    nodes = nodes or catalogue()
    defs: dict[str, Any] = {}
    for spec in nodes.nodes():
        key = USE if spec.kind == "subtree" else NODE
        properties: dict[str, Any] = {key: {"const": spec.name}}
        properties |= {p.name: _param_schema(p) for p in spec.params if p.type != "(mission)"}
        required = [key, *(p.name for p in spec.params if p.required)]
        defs[_def_name(spec.name)] = {
            "type": "object",
            "description": f"{spec.kind}: {spec.doc}",
            "properties": properties,
            "required": required,
            "additionalProperties": False,
        }
    bare = [s.name for s in nodes.nodes() if not any(p.required for p in s.params)]
    defs["TreeNode"] = {"anyOf": [{"enum": bare}, *({"$ref": f"#/$defs/{_def_name(s.name)}"} for s in nodes.nodes())]}
    guards = nodes.nodes("guard")
    defs["TreeGuard"] = {
        "anyOf": [
            {"enum": [s.name for s in guards if not any(p.required for p in s.params)]},
            *({"$ref": f"#/$defs/{_def_name(s.name)}"} for s in guards),
        ]
    }
    return {"$ref": "#/$defs/TreeNode"}, defs


def _def_name(node: str) -> str:
    return "TreeNode_" + node


def _param_schema(p: ParamSpec) -> dict[str, Any]:
    if p.type in _JSON_TYPES:
        schema: dict[str, Any] = {"type": _JSON_TYPES[p.type]}
    elif p.type == "one of":
        schema = {"enum": list(p.choices)}
    elif p.type == "range":
        schema = {"$ref": "#/$defs/Range"}
    elif p.type == "numbers":
        schema = {"type": "array", "items": {"type": "number"}}
    elif p.type == "enu":
        axes = ("east", "north", "up")
        schema = {"type": "object", "properties": {a: {"type": "number"} for a in axes}, "required": list(axes), "additionalProperties": False}
    elif p.type in ("node", "guard"):
        schema = {"$ref": "#/$defs/TreeGuard" if p.type == "guard" else "#/$defs/TreeNode"}
    else:  # nodes, guards
        schema = {"type": "array", "items": {"$ref": "#/$defs/TreeGuard" if p.type == "guards" else "#/$defs/TreeNode"}}
    if p.nullable:
        schema = {"anyOf": [schema, {"type": "null"}]}
    unit = f" [{p.unit}]" if p.unit else ""
    default = f" (default: the mission's {p.from_mission})" if p.from_mission else ""
    return {**schema, "description": f"{p.doc}{unit}{default}"}
