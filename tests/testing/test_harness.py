"""The tick-by-tick harness as README's "Testing your own tree" shows it: inputs, asks, acks, nodes by path."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.testing import EKF_READY, Harness, ScriptedAutopilot
from executive.tree import select as mission_tree
from executive.world.dialect import mavlink


@pytest.fixture
def h(square_mission) -> Harness:
    return Harness.build(square_mission)


def test_readme_s_walk_through(h: Harness) -> None:
    h.vehicle.set(link__up=True, vehicle__ekf=EKF_READY, vehicle__mode="HOLD", rc__channels=(1500,) * 8)
    assert h.tick() == Status.RUNNING
    assert h.asked() == [("arm", True)]
    assert h.feedback("Pre-flight/Arm/Arm") == "waiting for the autopilot"
    h.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_DENIED)
    h.tick()
    assert h.feedback("Pre-flight/Arm/Arm") == "refused: DENIED"


def test_a_path_that_names_no_node_or_several_lists_the_tree(h: Harness) -> None:
    with pytest.raises(KeyError, match=r"no node at 'Nowhere'.*Mission/Run/Pre-flight"):
        h.node("Nowhere")
    with pytest.raises(KeyError, match=r"\d+ nodes at 'EKF ok\?'"):
        h.node("EKF ok?")  # in the pre-flight wait and among the route's guards


def test_statuses_by_path_and_the_mission_started(h: Harness) -> None:
    h.tick()
    assert h.statuses()["Mission/Run/Pre-flight"] == Status.RUNNING
    assert h.mission_state.status.name == "RUNNING"


def test_asked_reads_setpoints_and_other_commands(square_mission) -> None:
    h = Harness.build(square_mission, root=mission_tree.build(square_mission))
    h.commander.change_speed(2.5)
    h.commander.goto(47.3977, 8.5456, 0.0)
    h.commander.flush()
    goto, speed = h.asked()  # a setpoint leaves at once, a command at the flush
    assert speed[0] == "DO_CHANGE_SPEED" and speed[1][1] == pytest.approx(2.5)
    assert goto == ("goto", 47.3977, 8.5456, 0.0)


def test_tick_until_counts_ticks_and_gives_up_with_the_vehicle_time(h: Harness) -> None:
    autopilot = ScriptedAutopilot(h, (47.3975, 8.5456))
    h.vehicle.set(link__up=True, vehicle__ekf=EKF_READY)
    n = h.tick_until(lambda: autopilot.armed, between=autopilot.respond)
    assert n == 1 and autopilot.commands == [("arm", 1.0)]
    with pytest.raises(AssertionError, match=r"not done after 5 ticks \(0.5 s\)"):
        h.tick_until(lambda: False, max_ticks=5)
