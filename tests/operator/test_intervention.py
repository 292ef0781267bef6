"""A mode change the executive did not ask for, mid-mission: PAUSED in that tick with the reason, hands off, resumed three ways."""

from __future__ import annotations

import py_trees
import pytest

from executive.behaviours import SetMode
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import AUTOPILOT, GCS, RuntimeOnLink
from executive.trees.parts import mission_root
from executive.world.dialect import EXECUTIVE_COMPONENT, mavlink

MANUAL, HOLD, LOITER, GUIDED = "MANUAL", "HOLD", "LOITER", "GUIDED"


@pytest.fixture
def driving(square_mission: Mission, runtime_on_link) -> RuntimeOnLink:
    """A runtime whose mission puts the rover (in HOLD) in GUIDED and drives (forever), the autopilot beating every tick; 3 ticks in."""
    root = mission_root(square_mission, SetMode("GUIDED"), py_trees.behaviours.Running("Drive the leg"))
    r = runtime_on_link(square_mission, root=root, safe_timeout_s=1.0, mode=HOLD, beat=True)
    r.runtime.mission_state.start()
    r.tick(3)
    assert r.autopilot.mode == GUIDED and r.modes_sent() == [GUIDED] and r.status is MissionStatus.RUNNING
    r.texts()
    return r


def test_a_ground_station_hold_pauses_the_mission_in_that_tick_with_the_reason_and_nothing_is_commanded(driving: RuntimeOnLink) -> None:
    leg = driving.runtime.mission_state.legs.leg_index
    driving.autopilot.mode = HOLD  # QGroundControl's Pause on a rover
    driving.tick()
    assert driving.status is MissionStatus.PAUSED
    assert driving.runtime.mission_state.reason == "HOLD set by the ground station"
    assert driving.runtime.status.snapshot()["reason"] == "HOLD set by the ground station"
    assert py_trees.blackboard.Blackboard.get("/vehicle/mode_set_by") == "others"
    driving.tick()
    assert "mission PAUSED: HOLD set by the ground station" in driving.texts()
    driving.autopilot.mode = LOITER  # the person does something else: still theirs
    driving.tick(50)
    assert driving.modes_sent() == [] and driving.status is MissionStatus.PAUSED and driving.runtime.mission_state.legs.leg_index == leg


def test_ctl_resume_puts_the_vehicle_back_in_the_legs_mode(driving: RuntimeOnLink) -> None:
    driving.autopilot.mode = HOLD
    driving.tick()
    reply = driving.runtime.operator.request("resume", source="ctl")
    assert reply.ok and reply.state == "RUNNING"
    driving.tick(2)
    assert driving.modes_sent() == [GUIDED] and driving.autopilot.mode == GUIDED and driving.status is MissionStatus.RUNNING
    assert py_trees.blackboard.Blackboard.get("/vehicle/mode_set_by") == "us"
    driving.tick(10)
    assert driving.status is MissionStatus.RUNNING  # the GUIDED it asked for is not an intervention


@pytest.mark.parametrize("command", [mavlink.MAV_CMD_MISSION_START, mavlink.MAV_CMD_DO_PAUSE_CONTINUE])
def test_a_ground_station_continue_resumes(driving: RuntimeOnLink, command: int) -> None:
    driving.autopilot.mode = HOLD
    driving.tick()
    driving.link.incoming.append(GCS.command_long(1, EXECUTIVE_COMPONENT, command, 0, 1, 0, 0, 0, 0, 0, 0))
    driving.tick(2)
    acks = [m for m in driving.link.take("COMMAND_ACK") if m.command == command]
    assert [a.result for a in acks] == [mavlink.MAV_RESULT_ACCEPTED]
    assert driving.status is MissionStatus.RUNNING and driving.modes_sent() == [GUIDED] and driving.autopilot.mode == GUIDED


def test_the_operator_switching_back_to_the_legs_mode_resumes(driving: RuntimeOnLink) -> None:
    driving.autopilot.mode = HOLD
    driving.tick(5)
    driving.autopilot.mode = GUIDED
    driving.tick()
    assert driving.status is MissionStatus.RUNNING and driving.runtime.mission_state.reason == "resumed at leg 1: GUIDED set again"
    driving.tick(5)
    assert driving.modes_sent() == []  # already in it


def test_the_autopilots_own_failsafe_does_not_pause_the_mission(driving: RuntimeOnLink, caplog) -> None:
    """Its notice ("EKF failsafe") comes with the change: our failsafe for the same condition holds and resumes the leg."""
    driving.link.incoming.append(AUTOPILOT.statustext(mavlink.MAV_SEVERITY_CRITICAL, b"EKF failsafe"))
    driving.autopilot.mode = HOLD
    driving.tick()
    assert driving.status is MissionStatus.RUNNING
    said = [(r.name, r.getMessage()) for r in caplog.records if "left to the failsafes" in r.getMessage()]
    # the logger names it (`WARNING intervention: HOLD set ...`): the message does not again (issue 43: `intervention: intervention:`)
    assert said == [("executive.intervention", "HOLD set by the autopilot (EKF failsafe): left to the failsafes, no pause")]


def test_a_person_in_manual_is_not_taken_back_when_the_mission_ends(driving: RuntimeOnLink) -> None:
    driving.autopilot.mode = MANUAL  # a ground station hands the vehicle to a driver
    driving.tick()
    assert driving.status is MissionStatus.PAUSED
    driving.runtime.request_stop("SIGTERM")
    outcome = driving.runtime.run(start=False)
    assert outcome.status is MissionStatus.ABORTED and driving.autopilot.mode == MANUAL and driving.modes_sent() == []


def test_a_pause_asked_by_the_operator_still_holds_the_vehicle(driving: RuntimeOnLink) -> None:
    assert driving.runtime.operator.request("pause", source="ctl").ok
    driving.tick(3)
    assert driving.modes_sent() == [HOLD] and driving.status is MissionStatus.PAUSED  # its own HOLD: no intervention
    assert driving.runtime.operator.request("resume", source="ctl").ok
    driving.tick(3)
    assert driving.modes_sent() == [GUIDED] and driving.status is MissionStatus.RUNNING


def test_the_autopilots_rc_failsafe_does_not_pause_the_mission(driving: RuntimeOnLink, vehicle, caplog) -> None:
    """ArduRover reports every RC channel 0 once its own RC failsafe has put the vehicle in FS_ACTION's mode: not a person."""
    vehicle.set(rc__connected=True)
    driving.tick()
    vehicle.set(rc__connected=False)
    driving.autopilot.mode = HOLD
    driving.tick()
    assert driving.status is MissionStatus.RUNNING
    assert "HOLD set by the autopilot (RC failsafe: the transmitter is gone): left to the failsafes, no pause" in caplog.text


# -- a person's commands through the operator path (ctl arm, disarm, mode) ---------------------------


def outcome(driving: RuntimeOnLink, reply) -> dict:
    return driving.runtime.operator.request("command", ticket=reply.command["ticket"], name=reply.command["name"]).command


def test_an_operators_mode_is_obeyed_and_the_mission_pauses_rather_than_undoing_it(driving: RuntimeOnLink) -> None:
    reply = driving.runtime.operator.request("mode", source="ctl", mode="hold")
    assert reply.ok and reply.state == "RUNNING" and reply.command["what"] == "mode HOLD"  # the vehicle decides, not the request
    assert (
        reply.reason == "ctl: mode HOLD; the mission pauses, hands off, once the vehicle shows it (refused: nothing changes), sent to the autopilot"
    )
    driving.tick(2)
    assert driving.modes_sent() == [HOLD] and driving.autopilot.mode == HOLD
    assert driving.status is MissionStatus.PAUSED and driving.runtime.mission_state.reason == "HOLD set by a person (ctl: mode HOLD)"
    assert outcome(driving, reply) == {"ticket": reply.command["ticket"], "state": "ACCEPTED", "result": "ACCEPTED", "final": True}
    driving.tick(50)
    assert driving.modes_sent() == [] and driving.status is MissionStatus.PAUSED  # never taken back to GUIDED
    assert driving.runtime.operator.request("resume", source="ctl").ok
    driving.tick(2)
    assert driving.modes_sent() == [GUIDED] and driving.status is MissionStatus.RUNNING


def test_an_operators_disarm_mid_mission_is_obeyed_and_reported_and_the_mission_pauses(driving: RuntimeOnLink) -> None:
    reply = driving.runtime.operator.request("disarm", source="ctl", force=True)
    assert reply.ok and reply.state == "RUNNING"
    assert reply.command == {"ticket": reply.command["ticket"], "name": "arming", "what": "force disarm"}
    driving.tick(2)
    assert driving.status is MissionStatus.PAUSED and driving.runtime.mission_state.reason == "disarmed by a person (ctl: force disarm)"
    assert ("arm", 0.0) in driving.autopilot.commands and not driving.autopilot.armed
    assert outcome(driving, reply)["state"] == "ACCEPTED"
    driving.tick(50)
    assert driving.modes_sent() == [] and not driving.autopilot.armed and driving.status is MissionStatus.PAUSED
    assert driving.texts() == ["mission PAUSED: disarmed by a person (ctl: force d"]  # the ground station is told (50 characters)


def test_an_operators_arm_does_not_pause_the_mission(driving: RuntimeOnLink) -> None:
    driving.autopilot.armed = False
    reply = driving.runtime.operator.request("arm", source="ctl")
    assert reply.ok and reply.state == "RUNNING"
    driving.tick(2)
    assert driving.autopilot.armed and outcome(driving, reply)["state"] == "ACCEPTED"


def test_a_refused_command_is_reported_as_the_autopilot_answered(driving: RuntimeOnLink) -> None:
    driving.autopilot.refuse = {"arm"}
    reply = driving.runtime.operator.request("disarm", source="ctl")
    driving.tick(2)
    assert outcome(driving, reply) == {"ticket": reply.command["ticket"], "state": "REJECTED", "result": "FAILED", "final": True}
    driving.tick(20)
    assert driving.status is MissionStatus.RUNNING and driving.autopilot.armed  # a refused command changes nothing
    assert driving.texts() == ["ctl: disarm refused (FAILED)"]


def test_an_unknown_mode_is_refused_and_nothing_is_sent_or_paused(driving: RuntimeOnLink) -> None:
    reply = driving.runtime.operator.request("mode", source="ctl", mode="WARP")
    assert (reply.ok, reply.reason, reply.state) == (False, "mode WARP: not a mode of this vehicle's autopilot", "RUNNING")
    driving.tick(2)
    assert driving.modes_sent() == [] and driving.status is MissionStatus.RUNNING
