"""Which node of a tree raised an exception: the node whose own code (setup, initialise, update, terminate) raised it.

py_trees calls each node's hooks from its parent's tick and says nothing of where an exception came
from; the runtime names a crashed behaviour by its path from the root. :class:`CrashSite` wraps the
hooks of every node of a tree when it is built, and notes the first node an exception leaves: the
innermost one, whose own code (or a function it called) raised it.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Status

#: The hooks py_trees calls on a node (Behaviour.tick: initialise, update; Behaviour.stop: terminate; the tree's setup).
HOOKS = ("setup", "initialise", "update", "terminate")
#: The hooks whose py_trees default does nothing (``pass``, py_trees/behaviour.py): no exception comes out of a node that keeps it.
EMPTY_BY_DEFAULT = ("setup", "initialise", "terminate")


class CrashSite:
    """The node each exception came out of, for the tree of ``root`` (its nodes' hooks wrapped once, here)."""

    def __init__(self, root: py_trees.behaviour.Behaviour) -> None:
        self._error: BaseException | None = None
        self._node: py_trees.behaviour.Behaviour | None = None
        for node in root.iterate():
            for hook in HOOKS:
                if not _empty(node, hook):  # left unwrapped: a guard's default initialise and terminate run every tick
                    setattr(node, hook, self._noting(node, hook, getattr(node, hook)))

    def node_of(self, error: BaseException) -> py_trees.behaviour.Behaviour | None:
        """The node whose hook ``error`` came out of first (None: it came from no node's hook, the tree's own code)."""
        return self._node if error is self._error else None

    def _noting(self, node: py_trees.behaviour.Behaviour, name: str, hook: Callable[..., Any]) -> Callable[..., Any]:
        # Each wrapper takes its hook's arguments as py_trees passes them (Behaviour.tick: initialise(), update();
        # Behaviour.stop: terminate(new_status); the tree's setup(**kwargs)): update runs every tick, and an unpacked
        # ``*args, **kwargs`` call costs several times a plain one.
        def noted(error: BaseException) -> None:
            if error is not self._error:  # raised here, not passed up from a node below
                self._error, self._node = error, node

        if name == "terminate":

            @functools.wraps(hook)
            def terminate(new_status: Status) -> Any:
                try:
                    return hook(new_status)
                except BaseException as error:
                    noted(error)
                    raise

            return terminate
        if name != "setup":

            @functools.wraps(hook)
            def run() -> Any:
                try:
                    return hook()
                except BaseException as error:
                    noted(error)
                    raise

            return run

        @functools.wraps(hook)
        def setup(*args: Any, **kwargs: Any) -> Any:
            try:
                return hook(*args, **kwargs)
            except BaseException as error:
                noted(error)
                raise

        return setup


def _empty(node: py_trees.behaviour.Behaviour, hook: str) -> bool:
    """``hook`` of ``node`` is py_trees' default that does nothing (not one of its class's, nor set on the node)."""
    return hook in EMPTY_BY_DEFAULT and getattr(getattr(node, hook), "__func__", None) is getattr(py_trees.behaviour.Behaviour, hook)
