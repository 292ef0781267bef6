"""The tree a mission runs: composed in its file (:mod:`executive.tree.composition`), or named (:func:`executive.trees.resolve`)."""

from __future__ import annotations

import py_trees

from executive import registry, trees
from executive.mission.model import Mission
from executive.tree import composition


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The root behaviour of the tree the mission selects (built in, a plugin's, ``module:function``, or composed in the file).

    A tree of a user's (a plugin's, ``module:function``) that raises or returns no behaviour is a
    :class:`~executive.registry.PluginError` naming it, the user's file and line and the error: the
    user's bug, said as bad input (exit 2), not ours (a built-in tree that raises is: it is left to raise).
    """
    if not isinstance(mission.tree, str):
        return composition.build(mission)
    builder = trees.resolve(mission.tree)
    if mission.tree in trees.available():
        return builder(mission)
    try:
        root = builder(mission)
    except Exception as exc:  # a user's code: anything may be raised
        raise registry.PluginError(repr(mission.tree), exc, doing="build(mission)") from exc
    if not isinstance(root, py_trees.behaviour.Behaviour):
        raise registry.PluginError(repr(mission.tree), f"build(mission) returned {root!r}, not a py_trees behaviour")
    return root
