"""What the mission waits for: the deepest running node, a failed child named, the time it has run; live in the status and `ctl tree`."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from executive.operator.status import status_line
from executive.testing import Lockstep
from executive.tree.ticks import TickState, render_tree
from executive.tree.waiting import TreeWatch, WaitingWatch, deepest_running, waiting_text
from executive.world import blackboard

#: Mission > Run > (Pre-flight > Wait until EKF ok? > EKF ok?), (Route > Go to waypoint), and a parallel's second branch.
NODES = [
    {"id": 0, "name": "Mission", "type": "Sequence", "parent": None},
    {"id": 1, "name": "Pre-flight", "type": "Sequence", "parent": 0},
    {"id": 2, "name": "Wait until EKF ok?", "type": "WaitUntil", "parent": 1},
    {"id": 3, "name": "EKF ok?", "type": "EkfOk", "parent": 2},
    {"id": 4, "name": "Route", "type": "Sequence", "parent": 0},
    {"id": 5, "name": "Go to waypoint", "type": "GoTo", "parent": 4},
    {"id": 6, "name": "Watch battery", "type": "Watch", "parent": 0},
]


def state(t: float, status: dict[int, str], feedback: dict[int, str] | None = None) -> TickState:
    return TickState(int(t * 10), t, NODES, status, feedback or {})


EKF_WAIT = {0: "R", 1: "R", 2: "R", 3: "F"}
EKF_NOTES = {2: "waiting (9/120 s): no position", 3: "EKF has no position estimate"}


def test_a_wait_names_the_condition_it_waits_on_with_its_feedback_and_time():
    watch = WaitingWatch()
    watch.update(state(3.0, EKF_WAIT, EKF_NOTES))
    waiting = watch.update(state(15.0, EKF_WAIT, EKF_NOTES))
    assert waiting is not None
    assert (waiting.node, waiting.path, waiting.feedback) == (
        "EKF ok?",
        "Mission/Pre-flight/Wait until EKF ok?/EKF ok?",
        "EKF has no position estimate",
    )
    assert waiting_text(waiting.to_dict(15.0)) == "waiting: EKF ok? (12 s): EKF has no position estimate"


def test_the_deepest_running_node_is_named_and_its_time_restarts_when_it_changes():
    watch = WaitingWatch()
    watch.update(state(3.0, EKF_WAIT))
    going = {0: "R", 1: "S", 2: "S", 3: "S", 4: "R", 5: "R"}
    first = watch.update(state(20.0, going, {5: "leg 1/4: 30.0 m at 000°"}))
    later = watch.update(state(26.0, going, {5: "leg 1/4: 12.0 m at 000°"}))
    assert first is not None and later is not None
    assert (later.node, later.feedback, later.since) == ("Go to waypoint", "leg 1/4: 12.0 m at 000°", 20.0)
    assert waiting_text(later.to_dict(26.0)) == "waiting: Go to waypoint (6 s): leg 1/4: 12.0 m at 000°"


def test_equals_in_depth_go_to_the_first_in_preorder_and_a_running_node_under_a_stopped_one_is_stale():
    assert deepest_running(state(1.0, {0: "R", 4: "R", 5: "R", 6: "R"})) == 5
    assert deepest_running(state(1.0, {0: "R", 4: "R", 6: "R"})) == 4
    assert deepest_running(state(1.0, {0: "R", 1: "S", 2: "R", 3: "R"})) == 0  # 2 and 3 hold an old status under a finished parent
    assert deepest_running(state(1.0, {0: "S", 4: "R", 5: "R"})) is None
    assert WaitingWatch().update(state(1.0, {0: "F"})) is None


def test_a_long_feedback_is_cut_to_keep_the_status_one_line():
    text = waiting_text({"node": "Go", "feedback": "x" * 200, "for_s": 1.0})
    assert text.startswith("waiting: Go (1 s): xxx") and text.endswith("...") and len(text) < 90


@pytest.fixture
def slow_ekf(square_mission) -> Lockstep:
    """The square, with an EKF that has no position for its first 20 s of vehicle time."""
    with Lockstep(square_mission, ekf_ready_after_s=20) as sim:
        yield sim


def test_the_status_and_the_tree_say_what_the_running_mission_waits_for(slow_ekf):
    sim = slow_ekf
    sim.run(until=lambda: sim.clock.now() >= 12.0)
    reply = sim.runtime.operator.request("tree").to_dict()
    waiting = reply["status"]["waiting"]
    assert (waiting["node"], waiting["path"]) == ("EKF ok?", "Mission/Run/Pre-flight/Wait until EKF ok?/EKF ok?")
    assert 8.0 <= waiting["for_s"] <= 10.0  # since the mission started, just after the first heartbeat
    assert "waiting: EKF ok? (9 s): EKF has no position estimate" in status_line(reply["status"])
    tree = list(render_tree(TickState.from_tree_dict(reply["tree"])))
    assert "            * Wait until EKF ok? -- waiting (9/60 s): EKF has no position estimate (flags 0xa7)" in tree
    assert "                ✕ EKF ok? -- EKF has no position estimate (flags 0xa7)" in tree
    assert reply["tree"]["live"] is True

    sim.run(until=lambda: sim.runtime.mission_state.legs.leg_index == 1)
    leg_2 = sim.clock.now()
    sim.run(until=lambda: sim.clock.now() >= leg_2 + 2.0)
    waiting = sim.runtime.operator.request("status").status["waiting"]
    assert (waiting["node"], waiting["feedback"][:9]) == ("Go to waypoint", "leg 2/4: ")
    assert 1.5 <= waiting["for_s"] <= 2.1  # this leg's, not the mission's
    sim.run_to_end(limit_s=300)
    after = sim.runtime.operator.request("tree").to_dict()
    assert after["status"]["waiting"] is None
    assert after["tree"]["live"] is False and TickState.from_tree_dict(after["tree"]).status[0] == "S"  # the last tick, kept


def test_the_tree_is_refused_before_any_mission_has_run(square_mission):
    with Lockstep(square_mission) as sim:
        reply = sim.runtime.operator.request("tree")
    assert (reply.ok, reply.reason) == (False, "no mission has run yet (READY)")


def test_the_tree_watch_is_the_one_writer_of_the_mission_keys_it_publishes(slow_ekf):
    sim = slow_ekf
    sim.run(until=lambda: sim.clock.now() >= 2.0)  # the tree built, the reach gate judged
    board = sim.runtime.board
    writers = {key: {board.clients[c] for c in meta.write | meta.exclusive} for key, meta in board.metadata.items() if key.startswith("/mission/")}
    assert writers == {
        "/mission/waiting": {"tree watch"},
        "/mission/state": {"mission lifecycle"},
        "/mission/reason": {"mission lifecycle"},
        "/mission/leg_index": {"route progress"},
        "/mission/leg_count": {"route progress"},
        "/mission/target": {"route progress"},
        "/mission/next_target": {"route progress"},
        "/mission/samples": {"sample log"},
    }


def test_the_live_watch_follows_feedback_and_status_changes_tick_by_tick() -> None:
    """Between status changes only the feedback is read again; a status change walks the tree again (a new node, its own time)."""
    ekf = py_trees.behaviours.Running("EKF ok?")
    leg = py_trees.behaviours.Running("Go to waypoint")
    root = py_trees.composites.Selector("Mission", memory=False, children=[ekf, leg])
    watch = TreeWatch()
    watch.begin(None, root, None)  # type: ignore[arg-type]
    waited = []
    for t, note in [(1.0, "no position"), (2.0, "no position"), (3.0, "variances high"), (4.0, "")]:
        if t == 4.0:
            ekf.status = Status.FAILURE
        else:
            root.tick_once()
        ekf.feedback_message = note
        watch.ticked(int(t * 10), t)
        waiting = blackboard.value("/mission/waiting")
        waited.append((waiting.node, waiting.feedback, waiting.since))
    assert waited == [
        ("EKF ok?", "no position", 1.0),
        ("EKF ok?", "no position", 1.0),
        ("EKF ok?", "variances high", 1.0),
        ("EKF ok?", "", 4.0),  # it failed: Mission runs on and waits for it to succeed, from this tick
    ]
