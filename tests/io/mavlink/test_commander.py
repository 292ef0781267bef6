"""The commander: queue, send after the tick, match acks, retry, time out; all on the blackboard."""

from __future__ import annotations

import py_trees
import pytest

from executive import blackboard
from executive.io.mavlink.dialect import mavlink
from executive.state import CommandState
from tests_support import ack

DO_SET_MODE = mavlink.MAV_CMD_DO_SET_MODE


def status(name: str = "DO_SET_MODE"):
    return py_trees.blackboard.Blackboard.get(blackboard.command_key(name))


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
    assert status("COMPONENT_ARM_DISARM").state is CommandState.REJECTED
    assert status("COMPONENT_ARM_DISARM").result == mavlink.MAV_RESULT_FAILED
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
    assert status("COMPONENT_ARM_DISARM").state is CommandState.TIMED_OUT
    assert status("COMPONENT_ARM_DISARM").attempts == 4


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
    assert status("DO_REPOSITION").state is CommandState.SENT


def test_commands_go_to_the_autopilot_that_was_found(commander, link):
    commander.target_system, commander.target_component = 7, 1
    commander.disarm(force=True)
    commander.flush()
    (msg,) = link.take()
    assert (msg.target_system, msg.target_component, msg.param1, msg.param2) == (7, 1, 0.0, 21196.0)
