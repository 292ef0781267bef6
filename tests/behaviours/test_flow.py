"""Flow control tick by tick: waiting with a limit, holding while guards fail, looping over legs."""

from __future__ import annotations

import re

import py_trees
from py_trees.common import Status

from executive.behaviours import Arm, Armed, EkfOk, ForEachLeg, LinkAlive, RcNotTakingOver, Timeout, UnlessPaused, WaitForGuards, WaitUntil
from executive.world.dialect import mavlink


def test_wait_until_succeeds_when_the_condition_holds(harness, vehicle):
    h = harness(WaitUntil(LinkAlive(), limit_s=5.0))
    assert [h.tick() for _ in range(3)] == [Status.RUNNING] * 3
    vehicle.set(link__up=True)
    assert h.tick() == Status.SUCCESS


def test_wait_until_gives_up_after_its_limit(harness):
    node = WaitUntil(LinkAlive(), limit_s=1.0)
    h = harness(node)
    statuses = [h.tick(0.25) for _ in range(7)]  # waited 0, 0.25, ... 1.5 s
    assert statuses == [Status.RUNNING] * 5 + [Status.FAILURE, Status.RUNNING]  # restarts when ticked again
    assert node.status == Status.RUNNING


def test_wait_until_retries_a_failed_action_no_faster_than_retry_s(harness, vehicle):
    h = harness(WaitUntil(Arm(), limit_s=60.0, retry_s=2.0))
    arm_requests = 0
    for _ in range(50):  # 5 s; the autopilot refuses every arm
        h.tick()
        for msg in h.link.take("COMMAND_LONG"):
            arm_requests += 1
            h.ack(msg.command, mavlink.MAV_RESULT_FAILED)
    assert arm_requests == 3  # at 0 s, ~2 s and ~4 s
    assert h.root.status == Status.RUNNING
    vehicle.set(vehicle__armed=True)
    assert [h.tick() for _ in range(21)][-1] == Status.SUCCESS


def guarded(harness, leg: py_trees.behaviour.Behaviour, hold_mode: str | None = "HOLD"):
    guards = [LinkAlive(), Armed(), RcNotTakingOver(6, 1700)]
    route = py_trees.composites.Sequence("route", memory=False, children=[*guards, leg])
    wait = WaitForGuards(guards, limit_s=10.0, hold_mode=hold_mode)
    return harness(py_trees.composites.Selector("route or hold", memory=False, children=[route, wait])), wait


def test_wait_for_guards_holds_then_gives_way_on_recovery(harness, vehicle):
    vehicle.set(link__up=True, vehicle__armed=True)
    h, wait = guarded(harness, py_trees.behaviours.Running("leg"))
    assert h.tick() == Status.RUNNING
    vehicle.set(link__up=False)
    assert h.tick() == Status.RUNNING
    assert wait.status == Status.RUNNING
    assert "Link alive? no heartbeat from the autopilot" in wait.feedback_message
    (hold,) = h.link.take("COMMAND_LONG")
    assert (hold.command, hold.param2) == (mavlink.MAV_CMD_DO_SET_MODE, 4)  # HOLD, asked once
    assert [h.tick() for _ in range(5)] == [Status.RUNNING] * 5
    assert h.link.take("COMMAND_LONG") == []
    vehicle.set(link__up=True)
    assert [h.tick() for _ in range(20)] == [Status.RUNNING] * 20
    assert wait.status == Status.RUNNING  # the link must stay up for 2 s (LinkAlive.resume_after_s)
    assert h.tick() == Status.RUNNING
    assert wait.status == Status.INVALID  # the route runs again


def test_wait_for_guards_keeps_hands_off_when_a_person_has_the_vehicle(harness, vehicle):
    vehicle.set(link__up=True, vehicle__armed=True, rc__channels=(1500,) * 5 + (1900,))
    h, wait = guarded(harness, py_trees.behaviours.Running("leg"))
    assert h.tick() == Status.RUNNING
    assert wait.status == Status.RUNNING
    assert h.link.take("COMMAND_LONG") == []  # no HOLD while the pilot drives


def test_wait_for_guards_gives_up_after_its_limit(harness, vehicle):
    vehicle.set(link__up=True, vehicle__armed=False)
    h, wait = guarded(harness, py_trees.behaviours.Running("leg"))
    statuses = [h.tick(1.0) for _ in range(12)]
    assert statuses[:11] == [Status.RUNNING] * 11
    assert statuses[11] == Status.FAILURE
    assert wait.feedback_message == "not recovered after 10 s: Armed? vehicle is disarmed"


def test_wait_for_guards_fails_when_the_route_itself_failed(harness, vehicle):
    vehicle.set(link__up=True, vehicle__armed=True)
    h, wait = guarded(harness, py_trees.behaviours.Failure("leg"))
    assert h.tick() == Status.FAILURE
    assert wait.feedback_message == ""  # nothing to add: the reason is the route's


def test_for_each_leg_runs_the_child_once_per_leg(harness, mission_state):
    mission_state.start()
    visits = []

    class Leg(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            visits.append(mission_state.legs.leg_index)
            return Status.SUCCESS if len(visits) % 2 == 0 else Status.RUNNING  # two ticks per leg

    h = harness(ForEachLeg(Leg("leg")))
    statuses = [h.tick() for _ in range(8)]
    assert visits == [0, 0, 1, 1, 2, 2, 3, 3]
    assert statuses == [Status.RUNNING] * 7 + [Status.SUCCESS]
    assert mission_state.legs.leg_index == 4 and mission_state.legs.target is None


def test_for_each_leg_resumes_the_same_leg_after_an_interruption(harness, mission_state, vehicle):
    """A guard failing mid-leg and recovering continues that leg, not the first one."""
    mission_state.start()
    mission_state.advance_leg()
    vehicle.set(link__up=True, vehicle__armed=True)
    seen = []

    class Leg(py_trees.behaviour.Behaviour):
        def initialise(self) -> None:
            seen.append(mission_state.legs.leg_index)

        def update(self) -> Status:
            return Status.RUNNING

    h, _ = guarded(harness, ForEachLeg(Leg("leg")))
    h.tick()
    vehicle.set(vehicle__armed=False)
    h.tick()
    vehicle.set(vehicle__armed=True)
    h.tick()
    assert seen == [1, 1]


def test_for_each_leg_fails_with_the_leg_failure(harness, mission_state):
    mission_state.start()
    node = ForEachLeg(py_trees.behaviours.Failure("leg"))
    assert harness(node).tick() == Status.FAILURE
    assert node.feedback_message.startswith("leg 1/4 failed")
    assert mission_state.legs.leg_index == 0


def test_guards_only_read_the_blackboard():
    for guard in (LinkAlive(), EkfOk(), Armed(), RcNotTakingOver(6, 1700)):
        assert guard.bb.read == set(guard.reads)
        assert not guard.bb.write and not guard.bb.exclusive


def test_the_hold_asked_during_a_link_loss_is_not_retried_once_the_guards_recover(harness, vehicle):
    """A HOLD still being retried when the link returns would undo the leg the tree resumed."""
    vehicle.set(link__up=True, vehicle__armed=True)
    h, _ = guarded(harness, py_trees.behaviours.Running("leg"))
    h.tick()
    vehicle.set(link__up=False)
    h.tick()
    assert [m.param2 for m in h.link.take("COMMAND_LONG")] == [4]  # HOLD, unanswered: the link is down
    vehicle.set(link__up=True)
    for _ in range(20):  # while the link proves itself (2 s) the hold is still wanted: retried
        h.tick()
    h.link.take("COMMAND_LONG")
    for _ in range(60):  # 6 s after the guards recovered: well past the commander's retry interval
        h.tick()
    assert h.link.take("COMMAND_LONG") == []


def test_a_hold_asked_while_paused_is_not_retried_after_resume(harness, mission_state, vehicle):
    mission_state.start()
    h = harness(UnlessPaused(py_trees.behaviours.Running("body"), hold_mode="HOLD"))
    h.tick()
    mission_state.pause()
    h.tick()
    assert [m.param2 for m in h.link.take("COMMAND_LONG")] == [4]
    mission_state.resume()
    for _ in range(60):
        h.tick()
    assert h.link.take("COMMAND_LONG") == []


def test_timeout_fails_a_child_still_running_after_its_vehicle_time_and_stops_it(harness, vehicle):
    child = WaitUntil(LinkAlive(), limit_s=600.0)
    h = harness(Timeout(child, timeout_s=1.0))
    assert [h.tick(0.25) for _ in range(5)] == [Status.RUNNING] * 5  # 0 .. 1.0 s after it started
    assert h.tick(0.25) == Status.FAILURE
    assert child.status == Status.INVALID and h.root.feedback_message.startswith("timed out after 1 s: waiting")
    assert h.root.name == "Wait until Link alive? (within 1 s)"


def test_timeout_passes_on_the_child_s_result_in_time(harness, vehicle):
    h = harness(Timeout(WaitUntil(LinkAlive(), limit_s=600.0), timeout_s=1.0, name="Link within 1 s"))
    assert h.tick() == Status.RUNNING
    vehicle.set(link__up=True)
    assert h.tick() == Status.SUCCESS


def test_wait_for_guards_asks_its_hold_again_until_accepted_and_seen_never_anything_else(harness, vehicle):
    """A refused hold is asked again every 1.5 s (vehicle time), the feedback says so; accepted and seen, it is done."""
    vehicle.set(link__up=True, vehicle__armed=True, vehicle__mode="GUIDED")
    h, wait = guarded(harness, py_trees.behaviours.Running("leg"))
    assert h.tick() == Status.RUNNING
    vehicle.set(link__up=False)  # Link alive? fails (the heartbeats stop, the acks still come: a downlink that drops heartbeats)
    asks, states = [], []
    for tick in range(50):
        h.tick()
        for msg in h.link.take("COMMAND_LONG"):
            asks.append((tick, msg.command, msg.param2))
            h.ack(msg.command, mavlink.MAV_RESULT_FAILED if tick < 40 else mavlink.MAV_RESULT_ACCEPTED)
            if tick >= 40:
                vehicle.set(vehicle__mode="HOLD")
        state = re.sub(r" \(\d+/10 s\): Link alive\? no heartbeat from the autopilot$", "", wait.feedback_message)
        if not states or states[-1] != state:
            states.append(state)
    assert asks == [(t, mavlink.MAV_CMD_DO_SET_MODE, 4) for t in (0, 15, 30, 45)]  # HOLD, and only HOLD: no next reaction here
    assert states == ["asking HOLD", "asking HOLD: refused (FAILED)", "asking HOLD: refused (FAILED) x2", "asking HOLD: refused (FAILED) x3",
                      "in HOLD"]  # fmt: skip
