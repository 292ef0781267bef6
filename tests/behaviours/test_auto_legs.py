"""drive: auto's leg behaviours tick by tick: the autopilot's mission set to the leg, and a mission that ran out before it."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.behaviours import AutopilotAtLeg, FollowAutoLeg
from executive.testing import AUTOPILOT, Harness
from executive.world.dialect import mavlink
from executive.world.state import MISSION_STATE_COMPLETE, GlobalPosition, MissionCurrent, MissionItemReached


@pytest.fixture
def at_leg(square_mission) -> Harness:
    return Harness.build(square_mission.model_copy(update={"drive": "auto"}), AutopilotAtLeg(), transfer=True)


def test_out_of_auto_the_autopilots_mission_is_set_to_the_leg_then_it_succeeds(at_leg: Harness) -> None:
    at_leg.mission_state.continue_from(2)
    at_leg.vehicle.set(vehicle__mode="HOLD", vehicle__mission_current=MissionCurrent(1, 4, mavlink.MISSION_STATE_ACTIVE, False, 0.0))
    assert at_leg.tick() == Status.RUNNING and at_leg.link.take() == []  # what the autopilot does now is heard first
    at_leg.vehicle.set(vehicle__mission_current=MissionCurrent(1, 4, mavlink.MISSION_STATE_ACTIVE, False, at_leg.clock.now() + 0.05))
    assert at_leg.tick() == Status.RUNNING
    [sent] = at_leg.link.take("MISSION_SET_CURRENT")
    assert sent.seq == 3  # leg 3's waypoint, after ArduPilot's home item 0
    at_leg.transfer.on_current(AUTOPILOT.mission_current(3, 4, mavlink.MISSION_STATE_ACTIVE, 0), at_leg.clock.now())  # ArduPilot's echo
    assert at_leg.tick() == Status.SUCCESS


def test_in_auto_it_succeeds_without_a_word(at_leg: Harness) -> None:
    at_leg.vehicle.set(vehicle__mode="AUTO", vehicle__mission_current=MissionCurrent(2, 4, mavlink.MISSION_STATE_ACTIVE, True, 0.0))
    assert at_leg.tick() == Status.SUCCESS and at_leg.link.take() == []


def test_a_mission_that_ran_out_before_the_leg_is_held_then_set_to_it(at_leg: Harness) -> None:
    """The executive behind (the link was down): the autopilot completed its horizon at item 2, the leg is 3: hold, set, AUTO."""
    at_leg.mission_state.continue_from(2)
    at_leg.vehicle.set(vehicle__mode="AUTO", vehicle__mission_current=MissionCurrent(2, 2, MISSION_STATE_COMPLETE, True, 0.0))
    assert at_leg.tick() == Status.RUNNING
    assert at_leg.asked("COMMAND_LONG") == [("mode", "HOLD")]


def test_a_mission_completed_at_the_legs_item_is_the_legs_end_not_a_run_out(at_leg: Harness) -> None:
    at_leg.mission_state.continue_from(3)
    at_leg.vehicle.set(vehicle__mode="AUTO", vehicle__mission_current=MissionCurrent(4, 4, MISSION_STATE_COMPLETE, True, 0.0))
    assert at_leg.tick() == Status.SUCCESS and at_leg.link.take() == []


def test_an_intermediate_leg_ends_on_the_autopilots_word_the_last_on_the_position(square_mission) -> None:
    h = Harness.build(square_mission.model_copy(update={"drive": "auto"}), FollowAutoLeg(1.5, 60.0))
    far = square_mission.waypoints[3]
    h.vehicle.set(vehicle__position=None)
    assert h.tick() == Status.RUNNING
    h.vehicle.set(vehicle__mission_reached=MissionItemReached(1, h.clock.now(), 1))
    assert h.tick() == Status.SUCCESS  # leg 1: item 1 reached, as AUTO counts it
    h.mission_state.continue_from(3)
    h.vehicle.set(vehicle__mission_reached=MissionItemReached(4, h.clock.now(), 4))
    assert h.tick() == Status.RUNNING  # the last: the autopilot's word is not enough
    assert "the autopilot says reached" in h.feedback("Follow the leg in AUTO")
    h.vehicle.set(vehicle__position=GlobalPosition(far.lat, far.lon + 1e-5, 0.0, 0.0, 0.0, 0.0, 90.0, h.clock.now()))  # ~0.8 m off
    assert h.tick() == Status.SUCCESS


def test_legs_the_autopilot_finished_unheard_are_caught_up(at_leg: Harness) -> None:
    """The link was down mid leg 1: back, MISSION_CURRENT says the mission COMPLETED at item 3: legs 1-3 are done, leg 4 is set."""
    at_leg.vehicle.set(vehicle__mode="AUTO")
    assert at_leg.tick() == Status.SUCCESS  # driving leg 1 in AUTO
    at_leg.vehicle.set(vehicle__mode="LOITER")  # the link-loss failsafe's
    assert at_leg.tick() == Status.RUNNING  # waiting to hear what the autopilot did
    assert at_leg.link.take("MISSION_SET_CURRENT") == []
    at_leg.vehicle.set(vehicle__mission_current=MissionCurrent(3, 3, MISSION_STATE_COMPLETE, False, at_leg.clock.now() + 0.05))
    assert at_leg.tick() == Status.RUNNING
    assert at_leg.mission_state.legs.leg_index == 3
    [sent] = at_leg.link.take("MISSION_SET_CURRENT")
    assert sent.seq == 4


def test_a_mission_completed_before_this_run_drove_in_auto_catches_nothing_up(at_leg: Harness) -> None:
    """The same route driven before without a reboot: ArduPilot still says COMPLETED at its last item until AUTO starts it again."""
    at_leg.vehicle.set(vehicle__mode="HOLD")
    at_leg.tick()
    at_leg.vehicle.set(vehicle__mission_current=MissionCurrent(4, 4, MISSION_STATE_COMPLETE, False, at_leg.clock.now() + 0.05))
    at_leg.tick()
    assert at_leg.mission_state.legs.leg_index == 0
    [sent] = at_leg.link.take("MISSION_SET_CURRENT")
    assert sent.seq == 1
