"""The tree a mission runs: composed in its file (:mod:`executive.composition`), or named (:func:`executive.trees.resolve`)."""

from __future__ import annotations

import py_trees

from executive import composition, trees
from executive.mission.model import Mission


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The root behaviour of the tree the mission selects (built in, a plugin's, ``module:function``, or composed in the file)."""
    if not isinstance(mission.tree, str):
        return composition.build(mission)
    return trees.resolve(mission.tree)(mission)
