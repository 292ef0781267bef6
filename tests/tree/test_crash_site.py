"""The crash site: the node an exception came out of, whatever function deeper down raised it."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from executive.tree.crash_site import CrashSite


class Explodes(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        raise ZeroDivisionError("boom")


class Asks(py_trees.behaviour.Behaviour):
    """Calls another node's method in its update (as NoReturnUnderWay asks its failsafe)."""

    def __init__(self, name: str, other: Explodes) -> None:
        super().__init__(name)
        self.other = other

    def update(self) -> Status:
        return self.other.update()


class Catches(py_trees.behaviour.Behaviour):
    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, *, again: bool) -> None:
        super().__init__(name)
        self.child, self.again = child, again

    def update(self) -> Status:
        try:
            self.child.update()
        except ZeroDivisionError as exc:
            if self.again:
                raise ValueError("the child failed") from exc
        return Status.SUCCESS


def tick_raising(root: py_trees.behaviour.Behaviour) -> tuple[CrashSite, BaseException]:
    site = CrashSite(root)
    with pytest.raises(Exception) as raised:
        py_trees.trees.BehaviourTree(root).tick()
    return site, raised.value


def test_the_innermost_node_whose_own_code_raised_is_named() -> None:
    boom = Explodes("Divide")
    site, error = tick_raising(
        py_trees.composites.Sequence("Mission", memory=True, children=[py_trees.behaviours.Success("ok"), py_trees.decorators.Inverter("Not", boom)])
    )
    assert site.node_of(error) is boom


def test_a_node_that_calls_another_node_s_code_is_the_one_named() -> None:
    """The node ticked is named, not the one whose method it called (a traceback's innermost ``self`` would be)."""
    asks = Asks("Ask", Explodes("Elsewhere"))
    site, error = tick_raising(py_trees.composites.Sequence("Mission", memory=True, children=[asks]))
    assert site.node_of(error) is asks


def test_a_node_that_raises_its_own_error_after_catching_one_is_named() -> None:
    boom = Explodes("Divide")
    catches = Catches("Careful", boom, again=True)
    site, error = tick_raising(py_trees.composites.Sequence("Mission", memory=True, children=[catches, boom]))
    assert isinstance(error, ValueError) and site.node_of(error) is catches


def test_an_error_no_node_raised_is_nobody_s() -> None:
    site = CrashSite(py_trees.behaviours.Success("ok"))
    assert site.node_of(RuntimeError("from the tree's own code")) is None


def test_setup_and_terminate_are_watched_too() -> None:
    class Bad(py_trees.behaviours.Running):
        def setup(self, **kwargs: object) -> None:
            raise OSError("no sonar")

        def terminate(self, new_status: Status) -> None:
            raise RuntimeError("cannot stop")

    bad = Bad("Sonar")
    root = py_trees.composites.Sequence("Mission", memory=True, children=[bad])
    site = CrashSite(root)
    tree = py_trees.trees.BehaviourTree(root)
    with pytest.raises(OSError) as setup:
        tree.setup()
    assert site.node_of(setup.value) is bad
    tree.tick()  # RUNNING: stopping the tree stops it
    with pytest.raises(RuntimeError) as stop:
        root.stop(Status.INVALID)
    assert site.node_of(stop.value) is bad


def test_py_trees_empty_defaults_are_left_alone_and_the_rest_watched() -> None:
    """A guard's default initialise and terminate (py_trees' ``pass``) run unwrapped; its own hooks, and one set on the node, are watched."""

    def cannot_stop(new_status: Status) -> None:
        raise OSError("set on the node")

    plain, own = py_trees.behaviours.Success("plain"), Explodes("own")
    plain.terminate = cannot_stop  # type: ignore[method-assign]
    root = py_trees.composites.Sequence("Mission", memory=True, children=[plain, own])
    site = CrashSite(root)
    assert "initialise" not in vars(plain) and "initialise" not in vars(own) and "update" in vars(own)
    with pytest.raises(OSError) as raised:
        py_trees.trees.BehaviourTree(root).tick()
    assert site.node_of(raised.value) is plain
