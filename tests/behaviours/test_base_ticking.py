"""An executive behaviour ticks and stops as py_trees' own Behaviour does: the same hooks in the same order, the same statuses."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours.base import ExecutiveBehaviour
from executive.world import blackboard

SCRIPT = [Status.RUNNING, Status.RUNNING, Status.SUCCESS, Status.FAILURE, "not a status", Status.RUNNING]


class _Scripted:
    """Returns the statuses of SCRIPT in turn, noting each hook py_trees calls."""

    def __init__(self, name: str) -> None:
        super().__init__(name)  # type: ignore[call-arg]
        self.calls: list[str] = []
        self._script = iter(SCRIPT)

    def initialise(self) -> None:
        self.calls.append("initialise")

    def update(self) -> Status:
        self.calls.append("update")
        return next(self._script)

    def terminate(self, new_status: Status) -> None:
        self.calls.append(f"terminate {new_status.name}")


class Ours(_Scripted, ExecutiveBehaviour):
    pass


class Theirs(_Scripted, py_trees.behaviour.Behaviour):
    pass


def _run(node: _Scripted) -> Iterator[tuple[list[str], Status]]:
    for _ in SCRIPT:
        node.calls.clear()
        node.tick_once()
        yield node.calls[:], node.status  # type: ignore[attr-defined]


@pytest.fixture(params=["info", "debug"])
def py_trees_log(request: pytest.FixtureRequest) -> Iterator[None]:
    """py_trees' debug log off (the executive's fast tick) and on (py_trees' own, with its lines)."""
    before = py_trees.logging.level
    py_trees.logging.level = py_trees.logging.Level.DEBUG if request.param == "debug" else py_trees.logging.Level.INFO
    yield
    py_trees.logging.level = before


@pytest.mark.usefixtures("py_trees_log")
def test_the_same_hooks_and_statuses_as_py_trees() -> None:
    ours = list(_run(Ours("ours")))
    assert ours == list(_run(Theirs("theirs")))
    assert ours[2] == (["update", "terminate SUCCESS"], Status.SUCCESS)
    assert ours[3] == (["initialise", "update", "terminate FAILURE"], Status.FAILURE)
    assert ours[4][1] is Status.INVALID  # an update that returns no status


def test_stopped_from_outside_it_terminates_and_ticks_afresh() -> None:
    node = Ours("ours")
    node.tick_once()
    node.stop(Status.INVALID)
    assert node.calls[-1] == "terminate INVALID" and node.status is Status.INVALID
    node.tick_once()
    assert node.calls[-2:] == ["initialise", "update"]


class _ReadsArmed(ExecutiveBehaviour):
    reads = ("/vehicle/armed",)

    def update(self) -> Status:
        return Status.SUCCESS if self.get("/vehicle/armed") else Status.FAILURE


class _SaysArmed(_ReadsArmed):
    def get(self, key: str) -> object:
        return True if key == "/vehicle/armed" else super().get(key)


def test_a_behaviour_reads_the_board_as_it_is_now_and_a_subclass_s_own_get_is_kept() -> None:
    """ExecutiveBehaviour.get is its client's (bound once); a plugin's class that defines get has it called instead."""
    board = blackboard.writer("test vehicle", ["/vehicle/armed"])
    ours, theirs = _ReadsArmed("armed?"), _SaysArmed("says armed")
    outcomes = []
    for armed in (False, True):
        board.set("/vehicle/armed", armed)
        ours.tick_once()
        theirs.tick_once()
        outcomes.append((ours.status, theirs.status))
    assert outcomes == [(Status.FAILURE, Status.SUCCESS), (Status.SUCCESS, Status.SUCCESS)]


def test_the_status_names_of_base_are_py_trees_own_members() -> None:
    """Code run every tick reads RUNNING, SUCCESS, FAILURE, INVALID from base (a module's global, not an Enum class's attribute)."""
    from executive.behaviours import base

    assert [name for name in ("RUNNING", "SUCCESS", "FAILURE", "INVALID") if getattr(base, name) is not Status[name]] == []


def test_its_iterator_ticks_it_as_py_trees_own_does() -> None:
    """py_trees keeps a tick of the node, not started, as ``iterator`` (set at every stop); ours is made when read."""
    seen = []
    for node in (Ours("ours"), Theirs("theirs")):
        for _ in range(3):  # RUNNING, RUNNING, SUCCESS: stopped
            node.tick_once()
        node.calls.clear()
        seen.append(([n is node for n in node.iterator], node.calls, node.status))  # FAILURE (SCRIPT's fourth)
    assert seen[0] == seen[1] == ([True], ["initialise", "update", "terminate FAILURE"], Status.FAILURE)
