"""Plugins: trees and behaviours that other packages add, found through entry points, and ``tree: module:function``.

A package adds to the executive with no change to it, as python-can's interfaces are added, by
naming objects in entry-point groups of its ``pyproject.toml``::

    [project.entry-points."executive.trees"]
    patrol = "mypkg.patrol:build"                        # a mission says `tree: patrol`

    [project.entry-points."executive.behaviours"]
    enough_satellites = "mypkg.guards:EnoughSatellites"  # a behaviour class, in the node catalogue

    [project.entry-points."executive.instruments"]       # sample-taking instruments: executive.io.instruments
    mysonde = "mypkg.sonde:SondeSampler"

A tree is ``build(mission) -> py_trees.behaviour.Behaviour``; a behaviour is a class, an
:class:`~executive.behaviours.base.ExecutiveBehaviour` subclass for the services ours get. A module
on the Python path needs no packaging: ``tree: mypkg.patrol:build`` (``tree: mypkg.patrol`` means its
``build``). A plugin that cannot be loaded is a :class:`PluginError` naming it and what went wrong.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from importlib.metadata import EntryPoint, entry_points
from typing import TYPE_CHECKING, Any, TypeVar

import trees

if TYPE_CHECKING:
    import py_trees

    from executive.mission.model import Mission

    TreeBuilder = Callable[[Mission], py_trees.behaviour.Behaviour]

TREES = "executive.trees"
BEHAVIOURS = "executive.behaviours"
INSTRUMENTS = "executive.instruments"  # executive.io.instruments
T = TypeVar("T")


class PluginError(Exception):
    """A plugin (an entry point, or a ``module:function`` a mission names) that cannot be loaded or is not what it must be."""

    def __init__(self, plugin: str, error: BaseException | str) -> None:
        self.plugin = plugin
        self.error = error
        why = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
        super().__init__(f"plugin {plugin}: {why}")


class UnknownTree(LookupError):
    """A tree name that is neither built in, nor a plugin's, nor ``module:function``."""


def named(group: str) -> dict[str, EntryPoint]:
    """The entry points of ``group`` by name (of two with one name, the first found on the path)."""
    found: dict[str, EntryPoint] = {}
    for point in entry_points(group=group):
        found.setdefault(point.name, point)
    return found


def describe(point: EntryPoint) -> str:
    """How a plugin is named in messages: ``'patrol' (executive.trees = mypkg.patrol:build, from mypkg 1.0)``."""
    dist = getattr(point, "dist", None)
    source = f", from {dist.name} {dist.version}" if dist is not None else ""
    return f"{point.name!r} ({point.group} = {point.value}{source})"


def load(point: EntryPoint) -> Any:
    """What an entry point names; PluginError if it cannot be imported."""
    try:
        return point.load()
    except Exception as exc:  # an import runs the plugin's code: anything may be raised
        raise PluginError(describe(point), exc) from exc


def load_object(reference: str, default: str) -> Any:
    """What ``module:attribute`` (``module`` alone: its ``default`` attribute) names, imported from the Python path; PluginError if it cannot be."""
    module, _, attribute = reference.partition(":")
    try:
        found: Any = importlib.import_module(module)
        for part in (attribute or default).split("."):
            found = getattr(found, part)
    except Exception as exc:  # an import runs the plugin's code: anything may be raised
        raise PluginError(repr(reference), exc) from exc
    return found


def _checked_tree(plugin: str, found: Any) -> TreeBuilder:
    if not callable(found) or isinstance(found, type):
        raise PluginError(plugin, f"{found!r} is not a function build(mission) -> Behaviour")
    return found


def _builtin(name: str) -> TreeBuilder:
    builder: TreeBuilder = importlib.import_module(f"trees.{name}").build
    return builder


def _tree_plugin(point: EntryPoint) -> TreeBuilder:
    if point.name in trees.available():
        raise PluginError(describe(point), f"a built-in tree is named {point.name!r}")
    return _checked_tree(describe(point), load(point))


def load_class(point: EntryPoint, base: type[T], what: str) -> type[T]:
    """The class an entry point names, a subclass of ``base``; PluginError if it cannot be loaded or is not one (``what`` it must be)."""
    found = load(point)
    if not (isinstance(found, type) and issubclass(found, base)):
        raise PluginError(describe(point), f"{found!r} is not {what}")
    return found


def _behaviour_plugin(point: EntryPoint) -> type[py_trees.behaviour.Behaviour]:
    import py_trees

    return load_class(point, py_trees.behaviour.Behaviour, "a behaviour class (subclass executive.behaviours.base.ExecutiveBehaviour)")


def _instrument_plugin(point: EntryPoint) -> type:
    from executive.io.sampler import InstrumentSampler

    return load_class(point, InstrumentSampler, "an instrument (subclass executive.io.sampler.InstrumentSampler)")


def resolve_tree(name: str) -> TreeBuilder:
    """The builder of a tree: built in (``trees/``), a plugin's (``executive.trees``), or ``module:function`` on the path.

    Raises UnknownTree for a name that is none of these, PluginError for one that cannot be loaded.
    """
    if ":" in name or "." in name:
        return _checked_tree(repr(name), load_object(name, "build"))
    if name in trees.available():
        return _builtin(name)
    points = named(TREES)
    if name not in points:
        raise UnknownTree(f"unknown tree {name!r} (available: {', '.join(sorted({*trees.available(), *points})) or 'none'}; or module:function)")
    return _tree_plugin(points[name])


def load_trees() -> dict[str, TreeBuilder]:
    """Every named tree: the built-in ones and the plugins'; PluginError for the first plugin that cannot be loaded or takes a built-in name."""
    return {name: _builtin(name) for name in trees.available()} | {name: _tree_plugin(point) for name, point in named(TREES).items()}


def load_behaviours() -> list[type[py_trees.behaviour.Behaviour]]:
    """The behaviour classes plugins add (``executive.behaviours``); PluginError for the first that cannot be loaded or is no behaviour class."""
    return [_behaviour_plugin(point) for point in named(BEHAVIOURS).values()]


def problems() -> list[PluginError]:
    """Every installed tree, behaviour and instrument plugin that cannot be loaded or is not what its group needs (empty: all load)."""
    errors: list[PluginError] = []
    for group, check in ((TREES, _tree_plugin), (BEHAVIOURS, _behaviour_plugin), (INSTRUMENTS, _instrument_plugin)):
        for point in named(group).values():
            try:
                check(point)
            except PluginError as exc:
                errors.append(exc)
    return errors
