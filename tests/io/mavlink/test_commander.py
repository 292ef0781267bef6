"""The commander: queue, send after the tick, match acks, retry, time out; all on the blackboard."""

from __future__ import annotations

import py_trees
import pytest

from executive.io.mavlink.commander import COMMAND_OUTCOMES
from executive.testing import ack
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import CommandState, Outcome

DO_SET_MODE = mavlink.MAV_CMD_DO_SET_MODE


def status(outcome: str = Outcome.MODE):
    return py_trees.blackboard.Blackboard.get(blackboard.command_key(outcome))


def test_requests_are_queued_until_flush(commander, link):
    ticket = commander.set_mode("HOLD")
    assert link.sent == []
    assert status().state is CommandState.QUEUED and status().ticket == ticket
    assert commander.flush() == 1
    assert status().state is CommandState.SENT and status().attempts == 1


def test_mode_by_name_or_number(commander, link):
    commander.set_mode("guided")
    commander.flush()
    commander.set_mode(4)
    commander.flush()
    assert [m.param2 for m in link.take()] == [15, 4]
    with pytest.raises(KeyError):
        commander.set_mode(99)


def test_ack_is_matched_on_the_command(commander, link):
    commander.set_mode("HOLD")
    commander.arm()
    commander.flush()
    commander.on_ack(ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_FAILED))
    assert status(Outcome.ARMING).state is CommandState.REJECTED
    assert status(Outcome.ARMING).result == mavlink.MAV_RESULT_FAILED
    assert status().state is CommandState.SENT
    commander.on_ack(ack(DO_SET_MODE))
    assert status().state is CommandState.ACCEPTED
    assert commander.idle


def test_in_progress_waits_longer_without_resending(commander, link, clock):
    commander.set_mode("HOLD")
    commander.flush()
    commander.on_ack(ack(DO_SET_MODE, mavlink.MAV_RESULT_IN_PROGRESS))
    assert status().state is CommandState.IN_PROGRESS
    clock.advance(3.0)  # past the plain ack timeout, within the in-progress allowance
    assert commander.flush() == 0
    commander.on_ack(ack(DO_SET_MODE))
    assert status().state is CommandState.ACCEPTED


def test_retries_carry_increasing_confirmation_then_time_out(commander, link, clock):
    commander.arm()
    for _ in range(40):
        commander.flush()
        clock.advance(0.25)
    sent = link.take("COMMAND_LONG")
    assert [m.confirmation for m in sent] == [0, 1, 2, 3]
    assert status(Outcome.ARMING).state is CommandState.TIMED_OUT
    assert status(Outcome.ARMING).attempts == 4


def test_a_newer_request_supersedes_the_one_in_flight(commander, link):
    first = commander.set_mode("HOLD")
    commander.flush()
    second = commander.set_mode("GUIDED")
    commander.flush()
    commander.on_ack(ack(DO_SET_MODE))
    assert status().ticket == second != first
    assert status().state is CommandState.ACCEPTED


def test_late_ack_for_nothing_in_flight_is_ignored(commander):
    commander.on_ack(ack(DO_SET_MODE))
    assert status() is None


def test_goto_is_a_setpoint_without_ack_tracking(commander, link):
    commander.goto(47.1, 8.2, 0.0)
    commander.flush()
    (msg,) = link.take()
    assert msg.get_type() == "SET_POSITION_TARGET_GLOBAL_INT"
    assert (msg.lat_int, msg.lon_int, msg.type_mask) == (471000000, 82000000, 0x0DF8)
    assert commander.idle


def test_command_int_scales_coordinates(commander, link):
    commander.command_int(mavlink.MAV_CMD_DO_REPOSITION, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, (-1, 0, 0, 0, 47.5, 8.25, 10))
    commander.flush()
    (msg,) = link.take()
    assert (msg.get_type(), msg.x, msg.y, msg.z) == ("COMMAND_INT", 475000000, 82500000, 10.0)
    assert status(Outcome.REPOSITION).state is CommandState.SENT


def test_commands_go_to_the_autopilot_that_was_found(commander, link):
    commander.target_system, commander.target_component = 7, 1
    commander.disarm(force=True)
    commander.flush()
    (msg,) = link.take()
    assert (msg.target_system, msg.target_component, msg.param1, msg.param2) == (7, 1, 0.0, 21196.0)


@pytest.mark.parametrize(
    ("request_", "command", "params"),
    [
        (lambda c: c.set_home(), mavlink.MAV_CMD_DO_SET_HOME, (1.0, 0.0)),
        (lambda c: c.change_speed(1.5), mavlink.MAV_CMD_DO_CHANGE_SPEED, (1.0, 1.5)),
        (lambda c: c.change_speed(18.0, airspeed=True), mavlink.MAV_CMD_DO_CHANGE_SPEED, (0.0, 18.0)),
        (lambda c: c.vtol_transition("fw"), mavlink.MAV_CMD_DO_VTOL_TRANSITION, (mavlink.MAV_VTOL_STATE_FW, 0.0)),
        (lambda c: c.vtol_transition("MC"), mavlink.MAV_CMD_DO_VTOL_TRANSITION, (mavlink.MAV_VTOL_STATE_MC, 0.0)),
        (lambda c: c.land(), mavlink.MAV_CMD_NAV_LAND, (0.0, 0.0)),
    ],
    ids=["set home here", "ground speed", "airspeed", "to FW", "to MC", "land"],
)
def test_command_helpers(commander, link, request_, command, params):
    request_(commander)
    commander.flush()
    (msg,) = link.take()
    assert (msg.command, msg.param1, msg.param2) == (command, *params)


def test_takeoff_altitude_is_param7(commander, link):
    commander.takeoff(30.0, vtol=True)
    commander.flush()
    (msg,) = link.take()
    assert (msg.command, msg.param7) == (mavlink.MAV_CMD_NAV_VTOL_TAKEOFF, 30.0)


def test_set_home_at_a_point_and_reposition_use_command_int(commander, link):
    commander.set_home(-35.1, 149.2, 584.0)
    commander.reposition(-35.2, 149.3, 10.0)
    commander.flush()
    home, reposition = link.take()
    assert (home.command, home.frame, home.x, home.y, home.z) == (
        mavlink.MAV_CMD_DO_SET_HOME,
        mavlink.MAV_FRAME_GLOBAL,
        -351000000,
        1492000000,
        584.0,
    )
    assert (reposition.command, reposition.x, reposition.param2) == (mavlink.MAV_CMD_DO_REPOSITION, -352000000, 1.0)


def test_every_command_result_is_on_the_blackboard_even_undocumented_ones(commander, link):
    commander.command_long(mavlink.MAV_CMD_DO_DIGICAM_CONTROL, ())
    commander.flush()
    commander.on_ack(ack(mavlink.MAV_CMD_DO_DIGICAM_CONTROL, mavlink.MAV_RESULT_UNSUPPORTED))
    assert status("DO_DIGICAM_CONTROL").state is CommandState.REJECTED
    assert blackboard.command_key("DO_DIGICAM_CONTROL") in blackboard.KEYS


def test_mode_name_wins_over_number(commander, link):
    commander.set_mode("GUIDED", number=4)
    commander.set_mode(number=4)
    commander.flush()
    assert [m.param2 for m in link.take()] == [4]  # the second request superseded the first before sending
    commander.set_mode("GUIDED", number=4)
    commander.flush()
    assert [m.param2 for m in link.take()] == [15]
    with pytest.raises(KeyError):
        commander.set_mode()


def test_a_cancelled_request_is_not_retried_and_its_late_ack_is_ignored(commander, link, clock):
    ticket = commander.set_mode("HOLD")
    commander.flush()
    assert commander.cancel(ticket)
    assert status().state is CommandState.CANCELLED
    for _ in range(20):
        clock.advance(0.5)
        commander.flush()
    assert len(link.take("COMMAND_LONG")) == 1  # the first send only, no retries
    commander.on_ack(ack(DO_SET_MODE))
    assert status().state is CommandState.CANCELLED
    assert not commander.cancel(ticket)  # nothing pending any more


def test_cancel_leaves_a_newer_request_alone(commander):
    first = commander.set_mode("HOLD")
    second = commander.set_mode("GUIDED")
    assert not commander.cancel(first)
    assert status().ticket == second and status().state is CommandState.QUEUED


def test_each_outcome_is_carried_by_one_mav_cmd_and_its_ack_has_a_documented_key():
    assert sorted(COMMAND_OUTCOMES.values()) == sorted(Outcome)
    assert all(blackboard.command_key(outcome) in blackboard.KEYS for outcome in Outcome)
    mav_cmds = {entry.name.removeprefix("MAV_CMD_") for entry in mavlink.enums["MAV_CMD"].values()}
    assert not [outcome for outcome in Outcome if outcome.upper() in mav_cmds]  # the keys name outcomes, not MAVLink's commands


def test_a_command_s_ack_goes_to_its_outcome_s_key(commander, link):
    ticket = commander.arm()
    commander.flush()
    commander.on_ack(ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_ACCEPTED))
    arming = py_trees.blackboard.Blackboard.get("/command/arming")
    assert (arming.ticket, arming.name, arming.state) == (ticket, "COMPONENT_ARM_DISARM", CommandState.ACCEPTED)
