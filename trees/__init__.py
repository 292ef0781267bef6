"""Tree builders, one module per mission kind (installed as ``executive.trees``); a mission file names its tree in ``tree:``.

Each tree module exposes ``build(mission: Mission) -> py_trees.behaviour.Behaviour`` and, beside it,
``DECLARATION`` (:class:`executive.mission.declaration.TreeDeclaration`: the vehicles it drives, the firmware
it needs, the section it reads, its RC switches and failsafe defaults), and is listed in the registry's
table of built-in trees (:data:`executive.registry.BUILT_IN`); :mod:`.parts` holds the
subtrees they share. A mission may also name a plugin's tree (entry-point group ``executive.trees``)
or ``module:function`` on the Python path: :func:`resolve` finds each.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.metadata import EntryPoint
from typing import TYPE_CHECKING, Literal

from executive import registry
from executive.mission.declaration import declaration_of

if TYPE_CHECKING:
    import py_trees

    from executive.mission.model import Mission

    TreeBuilder = Callable[[Mission], py_trees.behaviour.Behaviour]


#: The shared subtrees a tree composed in a mission file may use, by the name of their function in :mod:`.parts`.
SUBTREES: dict[str, Literal["decorator", "subtree"]] = {
    "preflight": "subtree",
    "wait_for_ekf": "subtree",
    "within_reach": "subtree",
    "checked": "subtree",
    "mission_root": "subtree",
    "guided_leg": "subtree",
    "failsafe_guarded": "decorator",
}


class UnknownTree(LookupError):
    """A tree name that is neither built in, nor a plugin's, nor ``module:function``."""


def available() -> list[str]:
    """Names of the built-in trees a mission may select."""
    return registry.built_in(registry.TREES)


def subtrees() -> list[tuple[str, Literal["decorator", "subtree"], Callable[..., py_trees.behaviour.Behaviour]]]:
    """The parts of the built-in trees a tree composed in a mission file may use: (name, kind, function taking the mission).

    ``use: preflight``; ``failsafe_guarded`` decorates the work it guards.
    """
    from executive.trees import parts

    return [(name, kind, getattr(parts, name)) for name, kind in SUBTREES.items()]


def _checked(plugin: str, found: object) -> TreeBuilder:
    if not callable(found) or isinstance(found, type):
        raise registry.PluginError(plugin, f"{found!r} is not a function build(mission) -> Behaviour")
    return found


def _built_in(name: str) -> TreeBuilder:
    builder: TreeBuilder = registry.load_built_in(registry.TREES, name)
    return builder


def plugin_tree(point: EntryPoint) -> TreeBuilder:
    """The builder an ``executive.trees`` entry point names; PluginError if it cannot be loaded, is no function or takes a built-in name."""
    if point.name in available():
        raise registry.PluginError(registry.describe(point), f"a built-in tree is named {point.name!r}")
    builder = _checked(registry.describe(point), registry.load(point))
    declaration_of(point.value, registry.describe(point))  # what it declares must be a declaration
    return builder


def resolve(name: str) -> TreeBuilder:
    """The builder of a tree: built in, a plugin's (``executive.trees``), or ``module:function`` on the path.

    Raises UnknownTree for a name that is none of these, PluginError for one that cannot be loaded.
    """
    if ":" in name or "." in name:
        builder = _checked(repr(name), registry.load_object(name, "build"))
        declaration_of(name)
        return builder
    if name in available():
        return _built_in(name)
    points = registry.named(registry.TREES)
    if name not in points:
        raise UnknownTree(f"unknown tree {name!r} (available: {', '.join(sorted({*available(), *points})) or 'none'}; or module:function)")
    return plugin_tree(points[name])


def load_all() -> dict[str, TreeBuilder]:
    """Every named tree: the built-in ones and the plugins'; PluginError for the first plugin that cannot be loaded or takes a built-in name."""
    return {name: _built_in(name) for name in available()} | {name: plugin_tree(point) for name, point in registry.named(registry.TREES).items()}
