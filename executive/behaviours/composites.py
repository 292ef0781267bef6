"""py_trees' composites and plain decorators as the catalogue offers them: keyword parameters, a default name, a one-line doc.

Each returns the py_trees class itself, so a tree composed in a mission file is the same tree,
node for node, as one built in Python (``executive show``, ``replay`` and the snapshots see no
difference). The decorators that need the clock or the mission are behaviours of their own
(:class:`~executive.behaviours.flow.Timeout`, ``WaitUntil``, ``ForEachLeg``, ``UnlessPaused``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import py_trees
from py_trees.common import OneShotPolicy, ParallelPolicy

Behaviour = py_trees.behaviour.Behaviour


def sequence(children: Sequence[Behaviour], memory: bool = True, name: str = "Sequence") -> py_trees.composites.Sequence:
    """Its children in order: SUCCESS once all have succeeded, FAILURE at the first failure.

    With ``memory`` a child that succeeded is not ticked again until the sequence starts over;
    without, every child is ticked again each tick (a reactive sequence: guards before the work).
    """
    return py_trees.composites.Sequence(name, memory=memory, children=list(children))


def selector(children: Sequence[Behaviour], memory: bool = False, name: str = "Selector") -> py_trees.composites.Selector:
    """Its children in order until one does not fail: its status; FAILURE when all have failed.

    With ``memory`` a RUNNING child is resumed without ticking those before it; without, the
    children before it are tried again each tick (a reactive fallback).
    """
    return py_trees.composites.Selector(name, memory=memory, children=list(children))


def parallel(
    children: Sequence[Behaviour], policy: Literal["success_on_all", "success_on_one"] = "success_on_all", name: str = "Parallel"
) -> py_trees.composites.Parallel:
    """All its children every tick: FAILURE as soon as one fails; SUCCESS when all (``success_on_all``) or one (``success_on_one``) succeeded."""
    chosen = ParallelPolicy.SuccessOnOne() if policy == "success_on_one" else ParallelPolicy.SuccessOnAll()
    return py_trees.composites.Parallel(name, policy=chosen, children=list(children))


def inverter(child: Behaviour, name: str = "Inverter") -> py_trees.decorators.Inverter:
    """SUCCESS when the child fails and FAILURE when it succeeds (a condition turned around)."""
    return py_trees.decorators.Inverter(name=name, child=child)


def retry(child: Behaviour, failures: int, name: str = "Retry") -> py_trees.decorators.Retry:
    """The child again after a failure (RUNNING meanwhile), until it has failed ``failures`` times: then FAILURE."""
    return py_trees.decorators.Retry(name=name, child=child, num_failures=failures)


def repeat(child: Behaviour, successes: int, name: str = "Repeat") -> py_trees.decorators.Repeat:
    """The child again after a success (RUNNING meanwhile), until it has succeeded ``successes`` times; FAILURE at its first failure."""
    return py_trees.decorators.Repeat(name=name, child=child, num_success=successes)


def once(child: Behaviour, name: str = "Once") -> py_trees.decorators.OneShot:
    """The child until it has succeeded once; from then on SUCCESS without ticking it (a check or a phase done for good)."""
    return py_trees.decorators.OneShot(name, child, OneShotPolicy.ON_SUCCESSFUL_COMPLETION)
