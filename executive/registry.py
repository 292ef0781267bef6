"""The one registry of trees, behaviours and instruments: a table of the built-in ones, and entry points for plugins'.

As python-can finds its interfaces (a table of its own, then the ``can.interface`` entry points), a
package adds to the executive with no change to it by naming objects in entry-point groups of its
``pyproject.toml``::

    [project.entry-points."executive.trees"]
    patrol = "mypkg.patrol:build"                        # a mission says `tree: patrol`

    [project.entry-points."executive.behaviours"]
    enough_satellites = "mypkg.guards:EnoughSatellites"  # a behaviour class, in the node catalogue

    [project.entry-points."executive.instruments"]       # sample-taking instruments: executive.instruments
    mysonde = "mypkg.sonde:SondeSampler"

A tree is ``build(mission) -> py_trees.behaviour.Behaviour``, its module's ``DECLARATION`` what it declares
of itself (:func:`tree_declaration`, :class:`executive.mission.declaration.TreeDeclaration`); a behaviour is a class, an
:class:`~executive.behaviours.base.ExecutiveBehaviour` subclass for the services ours get; an
instrument an :class:`~executive.instruments.sampler.InstrumentSampler` subclass. The built-in ones
are named here as strings (``module:attribute``) and imported when first asked for, so this module
imports nothing of the executive and anything may import it. A plugin that cannot be loaded is a
:class:`PluginError` naming it and what went wrong.
"""

from __future__ import annotations

import importlib
import os
import sys
import sysconfig
import traceback
from importlib.metadata import EntryPoint, entry_points
from types import MappingProxyType
from typing import Any, TypeVar

TREES = "executive.trees"
BEHAVIOURS = "executive.behaviours"
INSTRUMENTS = "executive.instruments"
T = TypeVar("T")
#: The tree a mission runs when it names none.
DEFAULT_TREE = "waypoints"
#: The attribute of a tree's module that holds what the tree declares of itself.
DECLARATION = "DECLARATION"

#: group -> name -> ``module:attribute`` of each built-in one. Our behaviours are not listed: the node catalogue reads them
#: from :mod:`executive.behaviours` itself (its ``__all__``).
BUILT_IN: MappingProxyType[str, MappingProxyType[str, str]] = MappingProxyType({
    TREES: MappingProxyType({
        "auv_survey": "executive.trees.auv_survey:build",
        "goto_sample": "executive.trees.goto_sample:build",
        "ugv_rc_route": "executive.trees.ugv_rc_route:build",
        "vtol_transit": "executive.trees.vtol_transit:build",
        "waypoints": "executive.trees.waypoints:build",
    }),
    BEHAVIOURS: MappingProxyType({}),
    INSTRUMENTS: MappingProxyType({
        "serial": "executive.instruments.serial:SerialSampler",
        "simulated": "executive.instruments.sampler:SimulatedSampler",
    }),
})  # fmt: skip


#: The libraries a plugin calls into: a frame of theirs is not where the plugin went wrong.
_LIBRARIES = ("py_trees", "pymavlink", "can", "filterpy", "yaml", "pydantic", "pydantic_core", "serial", "numpy")
_EXECUTIVE = os.path.dirname(os.path.abspath(__file__))
#: The module a user's tree imported before the redesign: said with where it went.
_MOVED = {"trees": "the built-in trees are the package executive.trees: from executive.trees import ..."}


def _not_theirs(filename: str) -> bool:
    """A file of Python's, of the executive's or of a library's (a frame there did not go wrong by itself)."""
    if filename.startswith("<"):  # <frozen importlib._bootstrap>, <string>
        return True
    path = os.path.abspath(filename)
    places = [_EXECUTIVE, sysconfig.get_paths()["stdlib"], sysconfig.get_paths()["platstdlib"]]
    for name in _LIBRARIES:
        module = sys.modules.get(name)
        if module is not None and getattr(module, "__file__", None):
            places.append(os.path.dirname(os.path.abspath(module.__file__)))  # type: ignore[arg-type]
    return any(path == place or path.startswith(place + os.sep) for place in places)


def user_frame(error: BaseException) -> str | None:
    """``FILE:LINE`` of the innermost frame of ``error``'s traceback in a user's file (None: none is: the error is ours or a library's)."""
    frames = traceback.extract_tb(error.__traceback__)
    for frame in reversed(frames):
        if not _not_theirs(frame.filename):
            path = os.path.relpath(frame.filename) if not os.path.relpath(frame.filename).startswith("..") else frame.filename
            return f"{path}:{frame.lineno}"
    return None


def _hint(error: BaseException | str) -> str:
    if isinstance(error, ModuleNotFoundError) and error.name in _MOVED:
        return f" ({_MOVED[error.name]})"
    return ""


class PluginError(Exception):
    """A plugin (an entry point, or a ``module:function`` a mission names) that cannot be loaded, is not what it must be, or raised.

    Said as ``FILE:LINE: plugin NAME: [DOING raised ]Error: message``, the file and line the user's
    own (the innermost frame of the traceback in a file neither the executive's, Python's nor a
    library's), when the error came from there.
    """

    def __init__(self, plugin: str, error: BaseException | str, doing: str = "") -> None:
        self.plugin = plugin
        self.error = error
        why = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
        #: ``FILE:LINE`` in the user's code where it went wrong (None: not known, or not there).
        self.where = user_frame(error) if isinstance(error, BaseException) else None
        at = f"{self.where}: " if self.where else ""
        super().__init__(f"{at}plugin {plugin}: {f'{doing} raised ' if doing else ''}{why}{_hint(error)}")


def built_in(group: str) -> list[str]:
    """The names of the built-in ones of ``group``, sorted."""
    return sorted(BUILT_IN[group])


def installed_key() -> tuple[tuple[str, int], ...]:
    """What the installed entry points are read from: each place on the Python path and when it last changed.

    Installing or removing a package adds or removes a ``*.dist-info`` in a place on the path, which changes
    that folder's modification time: a key that changes whenever the entry points may have.
    """
    key = []
    for place in sys.path:
        try:
            key.append((place, os.stat(place or ".").st_mtime_ns))
        except OSError:
            key.append((place, -1))
    return tuple(key)


_named: dict[str, tuple[tuple[Any, tuple[tuple[str, int], ...]], dict[str, EntryPoint]]] = {}


def named(group: str) -> dict[str, EntryPoint]:
    """The entry points of ``group`` by name (of two with one name, the first found on the path).

    Read once per :func:`installed_key` (reading them all takes ~13 ms): a package installed later is found. The key
    holds the reader too: one put in its place (a test's) is read afresh.
    """
    key = (entry_points, installed_key())
    cached = _named.get(group)
    if cached is None or cached[0] != key:
        found: dict[str, EntryPoint] = {}
        for point in entry_points(group=group):
            found.setdefault(point.name, point)
        _named[group] = cached = (key, found)
    return dict(cached[1])


def names(group: str) -> list[str]:
    """Every name of ``group``: the built-in ones and those plugins add, sorted."""
    return sorted({*BUILT_IN[group], *named(group)})


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


def load_built_in(group: str, name: str) -> Any:
    """The built-in object ``name`` of ``group`` (KeyError for a name that is not built in)."""
    return load_object(BUILT_IN[group][name], "")


def tree_declaration(name: str) -> Any:
    """What tree ``name`` (built in, a plugin's or ``module:function``) declares of itself: its module's ``DECLARATION`` (None: none).

    KeyError for a name that is none of these; PluginError for a module that cannot be loaded. The
    declaration's type is :class:`executive.mission.declaration.TreeDeclaration`.
    """
    if ":" in name or "." in name:
        reference = name
    elif name in BUILT_IN[TREES]:
        reference = BUILT_IN[TREES][name]
    else:
        reference = named(TREES)[name].value
    module = reference.partition(":")[0]
    try:
        found = importlib.import_module(module)
    except Exception as exc:  # an import runs the plugin's code: anything may be raised
        raise PluginError(repr(reference), exc) from exc
    return getattr(found, DECLARATION, None)


def load_class(point: EntryPoint, base: type[T], what: str) -> type[T]:
    """The class an entry point names, a subclass of ``base``; PluginError if it cannot be loaded or is not one (``what`` it must be)."""
    found = load(point)
    if not (isinstance(found, type) and issubclass(found, base)):
        raise PluginError(describe(point), f"{found!r} is not {what}")
    return found
