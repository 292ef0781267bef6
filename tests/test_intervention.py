"""A mode change the executive did not ask for, mid-mission: PAUSED in that tick with the reason, hands off, resumed three ways."""

from __future__ import annotations

import py_trees
import pytest

from executive.assembly import build_runtime
from executive.behaviours import SetMode
from executive.clock import ManualClock
from executive.io.mavlink.dialect import EXECUTIVE_COMPONENT, mavlink
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import AUTOPILOT, GCS, FakeLink, ObedientAutopilot
from trees._parts import mission_root

MANUAL, HOLD, LOITER, GUIDED = "MANUAL", "HOLD", "LOITER", "GUIDED"


class Rig:
    """A runtime whose mission puts the rover in GUIDED and drives (forever); the autopilot beats every tick."""

    def __init__(self, mission: Mission, link: FakeLink, clock: ManualClock) -> None:
        root = mission_root(mission, SetMode("GUIDED"), py_trees.behaviours.Running("Drive the leg"))
        self.runtime = build_runtime(mission, link, clock, root=root, safe_timeout_s=1.0)
        self.link, self.clock = link, clock
        self.autopilot = ObedientAutopilot(link)
        self.autopilot.mode = HOLD
        self.runtime.mission_state.start()

    def tick(self, n: int = 1) -> None:
        for _ in range(n):
            self.clock.advance(0.1)
            self.autopilot.beat()
            self.runtime.tick()

    def modes_sent(self) -> list[str]:
        modes = self.runtime.commander.modes
        return [modes.decode(int(m.param2)) for m in self.link.take("COMMAND_LONG") if m.command == mavlink.MAV_CMD_DO_SET_MODE]

    def texts(self) -> list[str]:
        return [m.text for m in self.link.take("STATUSTEXT")]

    @property
    def state(self) -> MissionStatus:
        return self.runtime.mission_state.status


@pytest.fixture
def rig(square_mission: Mission, link: FakeLink, clock: ManualClock) -> Rig:
    r = Rig(square_mission, link, clock)
    r.tick(3)
    assert r.autopilot.mode == GUIDED and r.modes_sent() == [GUIDED] and r.state is MissionStatus.RUNNING
    r.texts()
    return r


def test_a_ground_station_hold_pauses_the_mission_in_that_tick_with_the_reason_and_nothing_is_commanded(rig: Rig) -> None:
    leg = rig.runtime.mission_state.leg_index
    rig.autopilot.mode = HOLD  # QGroundControl's Pause on a rover
    rig.tick()
    assert rig.state is MissionStatus.PAUSED
    assert rig.runtime.mission_state.reason == "HOLD set by the ground station"
    assert rig.runtime.status.snapshot()["reason"] == "HOLD set by the ground station"
    assert py_trees.blackboard.Blackboard.get("/vehicle/mode_set_by") == "others"
    rig.tick()
    assert "mission PAUSED: HOLD set by the ground station" in rig.texts()
    rig.autopilot.mode = LOITER  # the person does something else: still theirs
    rig.tick(50)
    assert rig.modes_sent() == [] and rig.state is MissionStatus.PAUSED and rig.runtime.mission_state.leg_index == leg


def test_ctl_resume_puts_the_vehicle_back_in_the_legs_mode(rig: Rig) -> None:
    rig.autopilot.mode = HOLD
    rig.tick()
    reply = rig.runtime.operator.request("resume", source="ctl")
    assert reply.ok and reply.state == "RUNNING"
    rig.tick(2)
    assert rig.modes_sent() == [GUIDED] and rig.autopilot.mode == GUIDED and rig.state is MissionStatus.RUNNING
    assert py_trees.blackboard.Blackboard.get("/vehicle/mode_set_by") == "us"
    rig.tick(10)
    assert rig.state is MissionStatus.RUNNING  # the GUIDED it asked for is not an intervention


@pytest.mark.parametrize("command", [mavlink.MAV_CMD_MISSION_START, mavlink.MAV_CMD_DO_PAUSE_CONTINUE])
def test_a_ground_station_continue_resumes(rig: Rig, command: int) -> None:
    rig.autopilot.mode = HOLD
    rig.tick()
    rig.link.incoming.append(GCS.command_long(1, EXECUTIVE_COMPONENT, command, 0, 1, 0, 0, 0, 0, 0, 0))
    rig.tick(2)
    acks = [m for m in rig.link.take("COMMAND_ACK") if m.command == command]
    assert [a.result for a in acks] == [mavlink.MAV_RESULT_ACCEPTED]
    assert rig.state is MissionStatus.RUNNING and rig.modes_sent() == [GUIDED] and rig.autopilot.mode == GUIDED


def test_the_operator_switching_back_to_the_legs_mode_resumes(rig: Rig) -> None:
    rig.autopilot.mode = HOLD
    rig.tick(5)
    rig.autopilot.mode = GUIDED
    rig.tick()
    assert rig.state is MissionStatus.RUNNING and rig.runtime.mission_state.reason == "resumed at leg 1: GUIDED set again"
    rig.tick(5)
    assert rig.modes_sent() == []  # already in it


def test_the_autopilots_own_failsafe_does_not_pause_the_mission(rig: Rig, caplog) -> None:
    """Its notice ("EKF failsafe") comes with the change: our failsafe for the same condition holds and resumes the leg."""
    rig.link.incoming.append(AUTOPILOT.statustext(mavlink.MAV_SEVERITY_CRITICAL, b"EKF failsafe"))
    rig.autopilot.mode = HOLD
    rig.tick()
    assert rig.state is MissionStatus.RUNNING
    assert "intervention: HOLD set by the autopilot (EKF failsafe): left to the failsafes, no pause" in caplog.text


def test_a_person_in_manual_is_not_taken_back_when_the_mission_ends(rig: Rig) -> None:
    rig.autopilot.mode = MANUAL  # a ground station hands the vehicle to a driver
    rig.tick()
    assert rig.state is MissionStatus.PAUSED
    rig.runtime.request_stop("SIGTERM")
    outcome = rig.runtime.run(start=False)
    assert outcome.status is MissionStatus.ABORTED and rig.autopilot.mode == MANUAL and rig.modes_sent() == []


def test_a_pause_asked_by_the_operator_still_holds_the_vehicle(rig: Rig) -> None:
    assert rig.runtime.operator.request("pause", source="ctl").ok
    rig.tick(3)
    assert rig.modes_sent() == [HOLD] and rig.state is MissionStatus.PAUSED  # its own HOLD: no intervention
    assert rig.runtime.operator.request("resume", source="ctl").ok
    rig.tick(3)
    assert rig.modes_sent() == [GUIDED] and rig.state is MissionStatus.RUNNING


def test_the_autopilots_rc_failsafe_does_not_pause_the_mission(rig: Rig, vehicle, caplog) -> None:
    """ArduRover reports every RC channel 0 once its own RC failsafe has put the vehicle in FS_ACTION's mode: not a person."""
    vehicle.set(rc__connected=True)
    rig.tick()
    vehicle.set(rc__connected=False)
    rig.autopilot.mode = HOLD
    rig.tick()
    assert rig.state is MissionStatus.RUNNING
    assert "HOLD set by the autopilot (RC failsafe: the transmitter is gone): left to the failsafes, no pause" in caplog.text


# -- a person's commands through the operator path (ctl arm, disarm, mode) ---------------------------


def outcome(rig: Rig, reply) -> dict:
    return rig.runtime.operator.request("command", ticket=reply.command["ticket"], name=reply.command["name"]).command


def test_an_operators_mode_is_obeyed_and_the_mission_pauses_rather_than_undoing_it(rig: Rig) -> None:
    reply = rig.runtime.operator.request("mode", source="ctl", mode="hold")
    assert reply.ok and reply.state == "PAUSED" and reply.command["what"] == "mode HOLD"
    assert reply.reason == "ctl: mode HOLD; mission paused at leg 1, hands off until resumed, sent to the autopilot"
    assert rig.runtime.mission_state.reason == "ctl: mode HOLD by a person: hands off"
    rig.tick(2)
    assert rig.modes_sent() == [HOLD] and rig.autopilot.mode == HOLD
    assert outcome(rig, reply) == {"ticket": reply.command["ticket"], "state": "ACCEPTED", "result": "ACCEPTED", "final": True}
    rig.tick(50)
    assert rig.modes_sent() == [] and rig.state is MissionStatus.PAUSED  # never taken back to GUIDED
    assert rig.runtime.operator.request("resume", source="ctl").ok
    rig.tick(2)
    assert rig.modes_sent() == [GUIDED] and rig.state is MissionStatus.RUNNING


def test_an_operators_disarm_mid_mission_is_obeyed_and_reported_and_the_mission_pauses(rig: Rig) -> None:
    reply = rig.runtime.operator.request("disarm", source="ctl", force=True)
    assert reply.ok and reply.state == "PAUSED"
    assert reply.command == {"ticket": reply.command["ticket"], "name": "COMPONENT_ARM_DISARM", "what": "force disarm"}
    rig.tick(2)
    assert ("arm", 0.0) in rig.autopilot.commands and not rig.autopilot.armed
    assert outcome(rig, reply)["state"] == "ACCEPTED"
    rig.tick(50)
    assert rig.modes_sent() == [] and not rig.autopilot.armed and rig.state is MissionStatus.PAUSED
    assert rig.texts() == ["mission PAUSED: ctl: force disarm by a person: han"]  # the ground station is told (50 characters)


def test_an_operators_arm_does_not_pause_the_mission(rig: Rig) -> None:
    rig.autopilot.armed = False
    reply = rig.runtime.operator.request("arm", source="ctl")
    assert reply.ok and reply.state == "RUNNING"
    rig.tick(2)
    assert rig.autopilot.armed and outcome(rig, reply)["state"] == "ACCEPTED"


def test_a_refused_command_is_reported_as_the_autopilot_answered(rig: Rig) -> None:
    rig.autopilot.refuse = {"arm"}
    reply = rig.runtime.operator.request("disarm", source="ctl")
    rig.tick(2)
    assert outcome(rig, reply) == {"ticket": reply.command["ticket"], "state": "REJECTED", "result": "FAILED", "final": True}


def test_an_unknown_mode_is_refused_and_nothing_is_sent_or_paused(rig: Rig) -> None:
    reply = rig.runtime.operator.request("mode", source="ctl", mode="WARP")
    assert (reply.ok, reply.reason, reply.state) == (False, "mode WARP: not a mode of this vehicle's autopilot", "RUNNING")
    rig.tick(2)
    assert rig.modes_sent() == [] and rig.state is MissionStatus.RUNNING
