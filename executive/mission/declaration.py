"""What a tree declares of itself, for the mission rules: the vehicles it drives, the firmware it needs, the section it reads.

A tree module (built in, a plugin's, or ``module:function``) holds, beside its ``build``, a
``DECLARATION = TreeDeclaration(...)``; the registry finds it (:func:`executive.registry.tree_declaration`)
and the rules of :mod:`executive.mission.rules` read it, so no rule names a tree. A tree that
declares nothing drives any vehicle kind, on any firmware, guided only, and reads no section.
A plugin may bring a vehicle kind of its own in ``vehicle_kinds`` (:class:`executive.world.vehicles.VehicleProfile`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, get_args

from executive import registry
from executive.mission.failsafes import NO_REACTION, REACTION_MODES, VEHICLE_FAILSAFES
from executive.world.vehicles import AUTOPILOT_VEHICLES, PROFILES, VehicleKind

if TYPE_CHECKING:
    from pydantic import BaseModel

    from executive.world.vehicles import VehicleProfile

#: The vehicle kinds of the executive's own (:data:`executive.world.vehicles.PROFILES`).
BUILT_IN_KINDS: tuple[str, ...] = get_args(VehicleKind)
#: How a firmware a tree needs is said in messages.
FIRMWARE_NAMES = MappingProxyType({"ardupilot": "ArduPilot", "px4": "PX4"})


def _frozen(mapping: Mapping[str, Any]) -> MappingProxyType[str, Any]:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class TreeDeclaration:
    """What a tree says of itself; every field has the default of a tree that says nothing."""

    #: A line on what the tree does (``executive behaviours --trees``).
    doc: str = ""
    #: The vehicle kinds it drives (None: any).
    vehicles: frozenset[str] | None = None
    #: The one autopilot firmware that can fly it (``ardupilot``, ``px4``) and why; None: any.
    needs: tuple[str, str] | None = None
    #: ``drive: auto``: vehicle kind -> the firmware whose own AUTO drives the tree's route on it (empty: guided only).
    auto_drive: Mapping[str, str] = field(default_factory=dict)
    #: ``drive: auto`` refused: why (None: refused only where ``auto_drive`` says nothing).
    auto_refused: str | None = None
    #: The mission's options section the tree reads (a field of the mission, e.g. ``sampling``); None: none.
    section: str | None = None
    #: A section of the plugin's own: its pydantic model (strict, as ours: ``extra="forbid"``), the mission's field ``section``.
    options: type[BaseModel] | None = None
    #: RC channels the tree reads from the autopilot (``rc.source: mavlink``), each with what it is; None: the take-over switch.
    rc_switches: Callable[[Any], dict[int, str]] | None = None  # takes the Mission (whose module imports this one)
    #: The ``rc:`` settings the tree takes where the file says nothing (``rc.source: mavlink`` only), e.g. ``{"arm_channel": 5}``.
    rc_defaults: Mapping[str, Any] = field(default_factory=dict)
    #: Failsafe defaults that differ from the vehicle kind's: condition -> (reaction, recovery).
    failsafes: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    #: Failsafe reactions the tree refuses, and why.
    refused_reactions: Mapping[str, str] = field(default_factory=dict)
    #: The route may start empty (its operator records it).
    empty_route: bool = False
    #: It takes samples: at least one waypoint with ``sample: true`` (and only such trees take any).
    samples: bool = False
    #: Each leg ends after ``limits.leg_timeout_s`` at speeds within ``limits.speed_m_s``: a leg too long to drive is refused.
    timed_legs: bool = False
    #: Vehicle kinds of the plugin's own, each with its profile (a kind's name, firmware, modes and failsafe defaults).
    vehicle_kinds: tuple[VehicleKindSpec, ...] = ()

    def __post_init__(self) -> None:
        if self.options is not None and self.section is None:
            raise ValueError("options (the model of an options section of the tree's own) needs section: the mission's field it is")
        for name in ("auto_drive", "rc_defaults", "failsafes", "refused_reactions"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        if self.vehicles is not None:
            object.__setattr__(self, "vehicles", frozenset(self.vehicles))

    def options_of(self, mission: Any) -> Any:
        """The tree's own options section of ``mission`` as the file gives it, else its defaults (the ``options`` model's)."""
        assert self.section is not None and self.options is not None, "the tree declares no options section of its own"
        given = getattr(mission, self.section, None)
        return given if given is not None else self.options()

    def to_json(self) -> dict[str, Any]:
        """The declaration as ``executive behaviours --trees --json`` lists it."""
        return {
            "doc": self.doc,
            "vehicles": sorted(self.vehicles) if self.vehicles is not None else None,
            "needs": {"autopilot": self.needs[0], "why": self.needs[1]} if self.needs else None,
            "auto_drive": dict(sorted(self.auto_drive.items())),
            "auto_refused": self.auto_refused,
            "section": self.section,
            "rc_switches": self.rc_switches is not None,
            "rc_defaults": dict(self.rc_defaults),
            "failsafes": {c: {"reaction": r, "recovery": v} for c, (r, v) in self.failsafes.items()},
            "refused_reactions": dict(self.refused_reactions),
            "empty_route": self.empty_route,
            "samples": self.samples,
            "timed_legs": self.timed_legs,
            "vehicle_kinds": [k.kind for k in self.vehicle_kinds],
            **({"options": sorted(self.options.model_fields)} if self.options is not None else {}),
        }


@dataclass(frozen=True)
class VehicleKindSpec:
    """A vehicle kind a plugin brings: its profile (MAV_TYPE, modes, safe mode), the firmware that drives it, its failsafes.

    The built-in kinds' are :data:`executive.world.vehicles.PROFILES`, :data:`~executive.world.vehicles.AUTOPILOT_VEHICLES` and
    :mod:`executive.mission.failsafes`' tables.
    """

    profile: VehicleProfile
    #: The autopilot firmware that drives it (``ardupilot``, ``px4``).
    autopilots: frozenset[str]
    #: The default failsafe of every condition: condition -> (reaction, recovery).
    failsafes: Mapping[str, tuple[str, str]]
    #: The energy rule's seeds where ``energy:`` gives none: (Wh per km, Wh per minute) (:mod:`executive.sensing.consumption`).
    energy_seeds: tuple[float, float]
    #: reaction -> the mode it commands (flying as a plane: the second); a reaction left out is not for this kind.
    reactions: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    #: Why a reaction left out is not for this kind (the loader's error), e.g. ``{"surface": "a glider cannot surface"}``.
    no_reaction: Mapping[str, str] = field(default_factory=dict)
    #: The built-in simulated vehicle it rides in ``executive run`` without ``--mavlink`` (a name of ``simulator.model``,
    #: e.g. ``vtol``: the simulated ArduPlane), given this kind's profile; None: none (it runs with ``--mavlink`` only).
    simulator: str | None = None

    def __post_init__(self) -> None:
        for name in ("failsafes", "reactions", "no_reaction"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        object.__setattr__(self, "autopilots", frozenset(self.autopilots))

    @property
    def kind(self) -> str:
        return self.profile.kind


#: What a tree that declares nothing is taken to say.
UNDECLARED = TreeDeclaration()


def declared(name: str | None) -> TreeDeclaration:
    """The declaration of tree ``name`` (None, a tree composed in the file: :data:`UNDECLARED`).

    A tree that cannot be found or loaded is :data:`UNDECLARED` here: admission says why it cannot be run.
    """
    if name is None:
        return UNDECLARED
    try:
        return declaration_of(name)
    except (registry.PluginError, LookupError):
        return UNDECLARED


def declaration_of(name: str, plugin: str | None = None) -> TreeDeclaration:
    """What tree ``name`` declares (:data:`UNDECLARED`: its module has no ``DECLARATION``); LookupError: no such tree.

    PluginError, naming ``plugin`` (by default ``name``), if its module cannot be loaded or its ``DECLARATION`` is no TreeDeclaration.
    """
    found = registry.tree_declaration(name)
    if found is not None and not isinstance(found, TreeDeclaration):
        raise registry.PluginError(plugin or repr(name), f"{registry.DECLARATION} {found!r} is not a TreeDeclaration (executive.mission.declaration)")
    return found or UNDECLARED


def declarations() -> dict[str, TreeDeclaration]:
    """Every named tree's declaration (built in and the plugins'), by name; one that cannot be loaded as :data:`UNDECLARED`."""
    return {name: declared(name) for name in registry.names(registry.TREES)}


def trees_with(predicate: Callable[[TreeDeclaration], bool]) -> list[str]:
    """The named trees whose declaration ``predicate`` holds of, sorted."""
    return [name for name, declaration in declarations().items() if predicate(declaration)]


def plugin_kinds() -> dict[str, VehicleKindSpec]:
    """The vehicle kinds the plugins' trees bring, by name (a built-in kind's name is not taken)."""
    found: dict[str, VehicleKindSpec] = {}
    for point in registry.named(registry.TREES).values():
        for spec in declared(point.value).vehicle_kinds:  # by its module:function: the entry points are read once
            if spec.kind not in BUILT_IN_KINDS:
                found.setdefault(spec.kind, spec)
    return found


def kind_spec(kind: str) -> VehicleKindSpec | None:
    """A plugin's vehicle kind (None: a built-in kind, or none at all)."""
    return None if kind in BUILT_IN_KINDS else plugin_kinds().get(kind)


def vehicle_profile(kind: str) -> VehicleProfile:
    """The profile of a vehicle kind, built in or a plugin's (KeyError: neither)."""
    if kind in PROFILES:
        return PROFILES[kind]
    spec = kind_spec(kind)
    if spec is None:
        raise KeyError(kind)
    return spec.profile


def kind_failsafes(kind: str) -> dict[str, tuple[str, str]]:
    """A vehicle kind's default failsafe policy: condition -> (reaction, recovery)."""
    if kind in VEHICLE_FAILSAFES:
        return dict(VEHICLE_FAILSAFES[kind])
    spec = kind_spec(kind)
    return dict(spec.failsafes) if spec is not None else {}


def reaction_modes(kind: str, reaction: str) -> tuple[str, str]:
    """The modes ``reaction`` commands a vehicle of ``kind``: (in general, flying as a plane); KeyError: none for this kind."""
    spec = kind_spec(kind)
    return REACTION_MODES[reaction][kind] if spec is None else spec.reactions[reaction]


def reaction_refused(kind: str, reaction: str) -> str | None:
    """Why ``reaction`` is not for a vehicle of ``kind`` (None: it is)."""
    spec = kind_spec(kind)
    if spec is None:
        return None if kind in REACTION_MODES[reaction] else NO_REACTION[reaction]
    return None if reaction in spec.reactions else spec.no_reaction.get(reaction, f"a {kind} has no {reaction} declared")


def drives(autopilot: str, kind: str) -> bool:
    """The autopilot firmware drives vehicles of ``kind`` here."""
    spec = kind_spec(kind)
    return kind in AUTOPILOT_VEHICLES[autopilot] if spec is None else autopilot in spec.autopilots
