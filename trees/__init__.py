"""Tree builders, one module per mission kind; a mission file names its module in ``tree:``.

Each module exposes ``build(mission: Mission) -> py_trees.behaviour.Behaviour``.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import py_trees

    from executive.mission.model import Mission


def available() -> list[str]:
    """Names of the tree modules a mission may select."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The root behaviour of the tree the mission selects."""
    if mission.tree not in available():
        raise ValueError(f"unknown tree {mission.tree!r}; available: {', '.join(available())}")
    return importlib.import_module(f"trees.{mission.tree}").build(mission)
