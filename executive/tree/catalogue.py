"""The catalogue of nodes a tree is made of: every guard, action, decorator, composite and built-in subtree, described from the code itself.

One source of truth: a node's parameters are its ``__init__`` (or factory function) signature and
type hints; its doc is the first line of its docstring; a unit comes from the parameter's name
(``_m`` metres, ``_s`` seconds, ``_m_s`` m/s, ``_us`` µs, ``_pct`` %...) unless the class says
otherwise. A behaviour class may declare, as class attributes:

- ``param_units``: parameter -> unit, where the name does not tell (a ``Range`` of metres);
- ``param_docs``: parameter -> one line, where :data:`PARAM_DOCS` (shared names) has none;
- ``from_mission``: parameter -> where its default comes from in the mission
  (``limits.acceptance_radius_m``, ``rc.takeover_channel``, or a name of :data:`MISSION_VALUES`);
- ``node_refs``: parameters naming another node of the tree (FailsafeNote's ``guard``);
- ``catalogued = False``: a base class or an internal part, not offered.

A guard's ``unknown_or_stale`` (what it does with no reading yet, and with a reading older than its
limit: :mod:`executive.behaviours.guards`) is part of its entry.

Use it as ``catalogue().get("go_to")``, ``catalogue().nodes(kind="guard")``; ``executive
behaviours [--json]`` prints it. Plugins' behaviours (entry-point group ``executive.behaviours``,
:mod:`executive.registry`) are part of it; :meth:`Catalogue.build` takes others.
"""

from __future__ import annotations

import functools
import inspect
import re
import types
import typing
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint
from typing import TYPE_CHECKING, Any, Literal, get_args, get_origin

import py_trees

from executive import behaviours, registry, trees
from executive.behaviours import composites
from executive.behaviours.guards import Guard
from executive.mission.declaration import vehicle_profile
from executive.mission.model import Range, RcRouteOptions, SamplingOptions, VtolOptions
from executive.mission.rules import height_tolerance, rc_switch_channels, seabed_clearance
from executive.world import frames

if TYPE_CHECKING:
    from executive.mission.model import Mission

Kind = Literal["guard", "action", "decorator", "composite", "subtree"]
KINDS: tuple[str, ...] = get_args(Kind)

#: Parameter types, as the catalogue and the mission file spell them.
#: ``node``/``nodes``: a child or a list of children; ``guard``/``guards``: the same, guards only;
#: ``node name``: the name of another node of the tree; ``(mission)``: taken from the mission, not written.
PARAM_TYPES = ("bool", "int", "float", "str", "one of", "range", "numbers", "enu", "node", "nodes", "guard", "guards", "node name", "(mission)")
CHILD_TYPES = frozenset({"node", "nodes", "guard", "guards"})

#: Units by the end of a parameter's name (the house convention), longest first.
UNIT_SUFFIXES = (
    ("_m_s2", "m/s²"),
    ("_m_s", "m/s"),
    ("_us", "µs"),
    ("_pct", "%"),
    ("_deg", "°"),
    ("_hz", "Hz"),
    ("_m", "m"),
    ("_s", "s"),
    ("_v", "V"),
)

#: One line for parameters many nodes share (a class's ``param_docs`` wins).
PARAM_DOCS: dict[str, str] = {
    "name": "the node's name, as show, replay, the journal and the snapshots print it",
    "child": "the node it decorates",
    "children": "its children, ticked in order",
    "confirm_timeout_s": "FAILURE when the vehicle has not confirmed the command by then",
    "timeout_s": "FAILURE when not done by then",
    "acceptance_radius_m": "the target counts as reached within this distance",
    "leg_timeout_s": "FAILURE when the leg has taken longer than this",
    "resend_s": "how often a setpoint or an unanswered command is sent again",
    "method": "setpoint: SET_POSITION_TARGET re-sent; reposition: MAV_CMD_DO_REPOSITION, acked (ArduPlane)",
    "mode": "flight mode name, as the autopilot spells it (GUIDED, LOITER, HOLD...)",
    "max_distance_m": "FAILURE when farther than this from the vehicle",
    "limit": "the allowed interval {min, max}",
    "tolerance_m": "how far outside the interval still counts as inside (waves, sensor noise)",
    "channel": "RC channel number (1-18)",
    "above_us": "PWM above which the channel counts as high",
    "source": "mavlink: the autopilot's RC_CHANNELS; can: the AgileX base's RC frames",
    "variance_threshold": "EKF variances over this fail",
    "waypoints": "the mission's waypoints",
    "hold_after_s": "debounce: how long the condition must fail, once it has held, before the guard fails",
    "resume_after_s": "debounce: how long the condition must hold again, once the guard failed, before it passes",
    "awaiting_recovery": "judged as failed already: passes only once the condition has held for resume_after_s (a wait for a recovery)",
    "limit_s": "FAILURE when the child has not succeeded by then",
    "retry_s": "a failed attempt is tried again this much later",
    "hint": "what a person does to end the wait (how to arm the vehicle), logged when the wait starts and said again on giving up",
    "hold_mode": "the mode the vehicle is held in",
    "fixed_wing_hold_mode": "the hold of a VTOL flying as a plane (none: hold_mode)",
    "work": "the work the guards guard",
    "guards": "guards re-checked every tick before the work (the failsafe's guards are added: GPS, heading, battery, RC loss, geofence)",
    "guard": "the guard",
    "steps": "the mission's steps, in order",
    "failures": "how many failures end it",
    "successes": "how many successes end it",
    "policy": "success_on_all or success_on_one",
    "check_name": "the name of the waypoint check",
    "takeover_channel": "RC channel whose high position means manual take-over (mavlink)",
    "takeover_above_us": "PWM above which the take-over channel is high",
    "operator_timeout_s": "FAILURE when the operator has not started the route by then",
    "aux_mode": "the mode for switch C down (null: ignored)",
    "give_up_after_s": "a wish not met by then is left to the operator",
    "max_position_age_s": "a waypoint is added only from a position younger than this",
    "memory": "a child that succeeded (sequence) or is running (selector) is not ticked again before the composite starts over",
}

#: Mission values a ``from_mission`` entry may name besides a dotted path of the mission's fields.
MISSION_VALUES: dict[str, Callable[[Mission], Any]] = {
    "vehicle.safe_mode": lambda m: vehicle_profile(m.vehicle).safe_mode,
    "vehicle.guided_mode": lambda m: vehicle_profile(m.vehicle).guided_mode,
    "vehicle.manual_mode": lambda m: vehicle_profile(m.vehicle).manual_mode,
    "vehicle.fixed_wing_hold_mode": lambda m: "LOITER" if m.vehicle == "vtol" else None,
    "vehicle.seabed_clearance_m": seabed_clearance,
    "vehicle.height_tolerance_m": height_tolerance,
    "geofence": lambda m: m.geofence.fence() if m.geofence is not None else None,
    "home": lambda m: (m.home.lat, m.home.lon) if m.home is not None else None,
    "rc.switch_channels": rc_switch_channels,
}
#: Option sections a dotted path may go through when the mission has none: their defaults apply.
_SECTION_DEFAULTS = {"sampling": SamplingOptions, "vtol": VtolOptions, "rc_route": RcRouteOptions}

#: Decorators whose child must be able to run (a guard there never does, so it is refused): (node, parameter).
ACTION_SLOTS = frozenset({("for_each_leg", "child"), ("timeout", "child"), ("repeat", "child"), ("failsafe_guarded", "work")})

#: Extra parameters every guard takes (its debounce, and whether it starts out failed): name -> (type, default).
GUARD_PARAMS: dict[str, tuple[str, Any]] = {"hold_after_s": ("float", None), "resume_after_s": ("float", None), "awaiting_recovery": ("bool", False)}


class CatalogueError(Exception):
    """A behaviour cannot be catalogued (a name taken twice, a parameter of a type no file can give)."""


@dataclass(frozen=True)
class ParamSpec:
    """One parameter of a node."""

    name: str
    type: str  # one of PARAM_TYPES
    unit: str = ""
    default: Any = None  # JSON-able; meaningless when required
    required: bool = False
    doc: str = ""
    choices: tuple[str, ...] = ()  # type "one of"
    nullable: bool = False  # null is allowed
    from_mission: str | None = None  # where the default comes from, when the mission has it

    @property
    def is_child(self) -> bool:
        """A child slot (a node, a list of nodes, guards) rather than a value."""
        return self.type in CHILD_TYPES

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "type": self.type, "unit": self.unit, "required": self.required, "doc": self.doc}
        if self.from_mission is not None:
            out["from_mission"] = self.from_mission  # the default: this value of the mission
        elif not self.required:
            out["default"] = self.default
        if self.choices:
            out["choices"] = list(self.choices)
        if self.nullable:
            out["nullable"] = True
        return out


@dataclass(frozen=True)
class NodeSpec:
    """One node type: its name in a mission file, its kind, its doc line and parameters, and what makes it."""

    name: str
    kind: Kind
    doc: str
    params: tuple[ParamSpec, ...]
    factory: Callable[..., py_trees.behaviour.Behaviour] = field(compare=False, repr=False)
    origin: str = ""  # module.qualname of the class or function
    takes_mission: bool = False  # the factory's ``mission`` parameter gets the mission
    refs: tuple[str, ...] = ()  # parameters naming another node of the tree
    unknown_or_stale: str = ""  # a guard: what it does with no reading yet, and with one older than its limit

    def param(self, name: str) -> ParamSpec | None:
        return next((p for p in self.params if p.name == name), None)

    @property
    def child_params(self) -> tuple[ParamSpec, ...]:
        return tuple(p for p in self.params if p.is_child)

    def to_json(self) -> dict[str, Any]:
        out = {"name": self.name, "kind": self.kind, "doc": self.doc, "origin": self.origin, "params": [p.to_json() for p in self.params]}
        if self.kind == "guard":
            out["unknown_or_stale"] = self.unknown_or_stale
        return out


class Catalogue:
    """Every node a tree may use, by name."""

    def __init__(self, specs: Iterable[NodeSpec]) -> None:
        self._specs: dict[str, NodeSpec] = {}
        for spec in specs:
            if spec.name in self._specs:
                raise CatalogueError(f"node name {spec.name!r} is taken twice: {self._specs[spec.name].origin} and {spec.origin}")
            self._specs[spec.name] = spec

    @classmethod
    def build(cls, extra: Iterable[type[py_trees.behaviour.Behaviour]] = ()) -> Catalogue:
        """Ours (behaviours, composites, decorators, subtrees) and the classes of ``extra`` (plugins')."""
        specs = [describe_class(c) for c in _our_classes()]
        specs += [describe_function(name, kind, f) for name, kind, f in _our_functions()]
        specs += [describe_class(c) for c in extra]
        return cls(sorted(specs, key=lambda s: (KINDS.index(s.kind), s.name)))

    def get(self, name: str) -> NodeSpec | None:
        """The node called ``name`` (None: no such node)."""
        return self._specs.get(name)

    def nodes(self, kind: str | None = None) -> list[NodeSpec]:
        """Every node (of ``kind``), by kind then name."""
        return [s for s in self._specs.values() if kind is None or s.kind == kind]

    def names(self) -> list[str]:
        return list(self._specs)

    def to_json(self) -> list[dict[str, Any]]:
        return [s.to_json() for s in self._specs.values()]


@functools.cache
def catalogue() -> Catalogue:
    """The catalogue of this installation: ours and the installed plugins' behaviours (a plugin that fails raises its error)."""
    return Catalogue.build(load_behaviours())


def plugin_behaviour(point: EntryPoint) -> type[py_trees.behaviour.Behaviour]:
    """The class an ``executive.behaviours`` entry point names; PluginError if it cannot be loaded or is no behaviour class."""
    return registry.load_class(point, py_trees.behaviour.Behaviour, "a behaviour class (subclass executive.behaviours.base.ExecutiveBehaviour)")


def load_behaviours(broken: list[registry.PluginError] | None = None) -> list[type[py_trees.behaviour.Behaviour]]:
    """The behaviour classes plugins add (``executive.behaviours``); PluginError for the first that cannot be loaded or is no behaviour class.

    With ``broken``, those that cannot be loaded are put there instead, and the others returned.
    """
    found = []
    for point in registry.named(registry.BEHAVIOURS).values():
        try:
            found.append(plugin_behaviour(point))
        except registry.PluginError as exc:
            if broken is None:
                raise
            broken.append(exc)
    return found


def _our_classes() -> list[type[py_trees.behaviour.Behaviour]]:
    """The behaviour classes :mod:`executive.behaviours` exports, but those marked ``catalogued = False``."""
    found = [getattr(behaviours, name) for name in behaviours.__all__]
    return [c for c in found if isinstance(c, type) and issubclass(c, py_trees.behaviour.Behaviour) and vars(c).get("catalogued", True)]


def _our_functions() -> list[tuple[str, Kind, Callable[..., py_trees.behaviour.Behaviour]]]:
    """The composites and plain decorators (:mod:`executive.behaviours.composites`), and the trees' built-in subtrees."""
    made: list[tuple[str, Kind, Callable[..., py_trees.behaviour.Behaviour]]] = [
        (name, "composite", getattr(composites, name)) for name in ("sequence", "selector", "parallel")
    ]
    made += [(name, "decorator", getattr(composites, name)) for name in ("inverter", "retry", "repeat", "once")]
    return made + trees.subtrees()


# -- describing ----------------------------------------------------------------------------------------


def node_name(cls: type) -> str:
    """A class's name in a mission file: its ``node_name``, else snake case (``EkfOk`` -> ``ekf_ok``, ``GoTo`` -> ``go_to``)."""
    declared = vars(cls).get("node_name")
    return declared if isinstance(declared, str) else re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", cls.__name__).lower()


def first_line(doc: str | None) -> str:
    """The first sentence line of a docstring."""
    return (inspect.cleandoc(doc).split("\n", 1)[0].strip() if doc else "") or ""


def describe_class(cls: type[py_trees.behaviour.Behaviour]) -> NodeSpec:
    """A behaviour class's node: kind from its base, parameters from ``__init__``."""
    if issubclass(cls, Guard):
        kind: Kind = "guard"
    elif issubclass(cls, py_trees.decorators.Decorator):
        kind = "decorator"
    elif issubclass(cls, py_trees.composites.Composite):
        kind = "composite"
    else:
        kind = "action"
    name = node_name(cls)
    params = _params(cls.__init__, cls, name, skip_first=True)
    if kind == "guard":
        params += tuple(_guard_param(cls, p, t, d) for p, (t, d) in GUARD_PARAMS.items() if all(q.name != p for q in params))
    return NodeSpec(
        name,
        kind,
        first_line(cls.__doc__),
        params,
        cls,
        f"{cls.__module__}.{cls.__qualname__}",
        refs=tuple(getattr(cls, "node_refs", ())),
        unknown_or_stale=getattr(cls, "unknown_or_stale", "") if kind == "guard" else "",
    )


def describe_function(name: str, kind: Kind, function: Callable[..., py_trees.behaviour.Behaviour]) -> NodeSpec:
    """A factory function's node (a composite, a decorator, a subtree of ``trees``); its ``mission`` parameter gets the mission."""
    takes_mission = "mission" in inspect.signature(function).parameters
    params = _params(function, function, name, skip_first=False)
    origin = f"{function.__module__}.{function.__qualname__}"
    return NodeSpec(name, kind, first_line(function.__doc__), params, function, origin, takes_mission=takes_mission)


def _guard_param(cls: type, name: str, kind: str, default: Any) -> ParamSpec:
    value = getattr(cls, name, default) if default is None else default
    return ParamSpec(name, kind, _unit(cls, name), value, doc=PARAM_DOCS[name])


def _params(function: Callable[..., Any], owner: Any, node: str, *, skip_first: bool) -> tuple[ParamSpec, ...]:
    signature = inspect.signature(function)
    try:
        hints = typing.get_type_hints(function)
    except NameError as exc:
        raise CatalogueError(f"{node}: cannot read the type hints of {getattr(owner, '__qualname__', owner)}: {exc}") from None
    from_mission: Mapping[str, str] = getattr(owner, "from_mission", {})
    refs: Collection[str] = getattr(owner, "node_refs", ())
    specs = []
    for i, p in enumerate(signature.parameters.values()):
        if (skip_first and i == 0) or p.name == "mission" or p.kind is p.VAR_KEYWORD:
            continue
        hint = hints.get(p.name, Any)
        if p.kind is p.VAR_POSITIONAL:
            hint = Sequence[hint]  # type: ignore[valid-type]
        kind, choices, nullable = ("node name", (), True) if p.name in refs else _type_of(hint)
        source = from_mission.get(p.name)
        if kind == "(mission)" and source is None and p.default is p.empty:
            raise CatalogueError(f"{node}: parameter {p.name!r} ({hint}) cannot be given in a mission file and has no default")
        required = p.default is p.empty and source is None and p.kind is not p.VAR_POSITIONAL
        default = None if p.default is p.empty else _jsonable(p.default)
        if p.kind is p.VAR_POSITIONAL:
            default = []
        doc = getattr(owner, "param_docs", {}).get(p.name) or PARAM_DOCS.get(p.name, "")
        specs.append(ParamSpec(p.name, kind, _unit(owner, p.name), default, required, doc, choices, nullable, source))
    return tuple(specs)


def _unit(owner: Any, name: str) -> str:
    declared: Mapping[str, str] = getattr(owner, "param_units", {})
    if name in declared:
        return declared[name]
    return next((unit for suffix, unit in UNIT_SUFFIXES if name.endswith(suffix)), "")


def _type_of(hint: Any) -> tuple[str, tuple[str, ...], bool]:
    """(catalogue type, choices, nullable) of a type hint."""
    origin, args = get_origin(hint), get_args(hint)
    if origin in (typing.Union, types.UnionType):
        rest = [a for a in args if a is not type(None)]
        if len(rest) == 1:
            kind, choices, _ = _type_of(rest[0])
            return kind, choices, len(rest) < len(args)
        return "(mission)", (), False
    if origin is Literal:
        return "one of", tuple(str(a) for a in args), False
    if hint in (bool, int, float, str):
        return hint.__name__, (), False
    if hint is Range:
        return "range", (), False
    if hint is frames.Enu:
        return "enu", (), False
    if isinstance(hint, type) and issubclass(hint, Guard):
        return "guard", (), False
    if isinstance(hint, type) and issubclass(hint, py_trees.behaviour.Behaviour):
        return "node", (), False
    if origin in (Sequence, Collection, list, tuple, Iterable) or (isinstance(origin, type) and issubclass(origin, Sequence | Collection)):
        item = args[0] if args else Any
        if item in (float, int):
            return "numbers", (), False
        if isinstance(item, type) and issubclass(item, Guard):
            return "guards", (), False
        if isinstance(item, type) and issubclass(item, py_trees.behaviour.Behaviour):
            return "nodes", (), False
    return "(mission)", (), False


def _jsonable(value: Any) -> Any:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, tuple | list):
        return [_jsonable(v) for v in value]
    return repr(value)


# -- values from the mission ---------------------------------------------------------------------------


def mission_value(source: str, mission: Mission) -> Any:
    """The value ``source`` (a ``from_mission`` entry) names in ``mission``."""
    if source in MISSION_VALUES:
        return MISSION_VALUES[source](mission)
    value: Any = mission
    for part in source.split("."):
        found = getattr(value, part)
        if found is None and value is mission and part in _SECTION_DEFAULTS:
            found = _SECTION_DEFAULTS[part]()
        value = found
    return value
