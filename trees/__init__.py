"""Tree builders, one module per mission kind; a mission file names its module in ``tree:``.

Each module exposes ``build(mission: Mission) -> py_trees.behaviour.Behaviour``. A mission may
also name a plugin's tree or ``module:function`` on the Python path (:mod:`executive.plugins`).
"""

from __future__ import annotations

import pkgutil
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from collections.abc import Callable

    import py_trees

    from executive.mission.model import Mission


def available() -> list[str]:
    """Names of the tree modules a mission may select."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))


def subtrees() -> list[tuple[str, Literal["decorator", "subtree"], Callable[..., py_trees.behaviour.Behaviour]]]:
    """The parts of the built-in trees a tree composed in a mission file may use: (name, kind, function taking the mission).

    ``use: preflight``; ``failsafe_guarded`` decorates the work it guards.
    """
    from trees import _parts, waypoints

    return [
        ("preflight", "subtree", _parts.preflight),
        ("wait_for_ekf", "subtree", _parts.wait_for_ekf),
        ("within_reach", "subtree", _parts.within_reach),
        ("checked", "subtree", _parts.checked),
        ("mission_root", "subtree", _parts.mission_root),
        ("guided_leg", "subtree", waypoints.leg),
        ("failsafe_guarded", "decorator", _parts.guarded),
    ]


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The root behaviour of the tree the mission selects (built in, a plugin's, or ``module:function``)."""
    if not isinstance(mission.tree, str):
        from executive import composition

        return composition.build(mission)
    from executive.plugins import resolve_tree  # it lists this package's trees

    return resolve_tree(mission.tree)(mission)
