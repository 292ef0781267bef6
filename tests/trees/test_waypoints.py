"""The guarded waypoint tree, tick by tick, against a scripted autopilot on a fake link."""

from __future__ import annotations

from pathlib import Path

import pytest
from py_trees.common import Status

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.testing import EKF_READY, ScriptedAutopilot
from executive.tree import select as mission_tree
from executive.world.geo import destination
from executive.world.state import EkfFlags, EkfStatus

MISSIONS = Path(__file__).parents[2] / "missions"
EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)


@pytest.fixture
def mission_run(harness, vehicle, square_mission, mission_state):
    """The square mission's tree, started, with the autopilot 30 m south of the first corner."""
    first = square_mission.waypoints[0]
    mission_state.start()
    h = harness(mission_tree.build(square_mission))
    vehicle.set(link__up=True, vehicle__ekf=EKF_READY)
    return ScriptedAutopilot(h, destination(first.lat, first.lon, 180.0, 30.0))


def test_the_square_completes_and_ends_held(mission_run, mission_state):
    statuses = mission_run.run(200)
    assert statuses[-1] == Status.SUCCESS
    assert mission_state.legs.leg_index == 4
    assert mission_run.commands[0] == ("arm", 1.0)
    assert mission_run.commands[1] == ("mode", "GUIDED")
    assert mission_run.commands[-1] == ("mode", "HOLD")
    assert mission_run.mode == "HOLD"


def test_preflight_waits_for_the_ekf_before_arming(mission_run, vehicle):
    vehicle.set(vehicle__ekf=EKF_LOST)
    assert mission_run.run(20) == [Status.RUNNING] * 20
    assert mission_run.commands == []
    vehicle.set(vehicle__ekf=EKF_READY)
    mission_run.run(1)
    assert mission_run.commands == [("arm", 1.0)]
    mission_run.run(1)
    assert mission_run.commands == [("arm", 1.0), ("mode", "GUIDED")]


def test_preflight_retries_a_refused_arm_then_gives_up(mission_run, square_mission):
    mission_run.refuse.add("arm")
    statuses = mission_run.run(int(square_mission.limits.ekf_wait_s * 10) + 20)
    assert statuses[-1] == Status.FAILURE
    arms = [c for c in mission_run.commands if c[0] == "arm"]
    assert len(arms) == pytest.approx(square_mission.limits.ekf_wait_s / 2.0, abs=2)  # one try every 2 s


def test_rc_takeover_mid_leg_waits_hands_off_then_resumes_the_same_leg(mission_run, mission_state, vehicle):
    while mission_state.legs.leg_index < 2:
        assert mission_run.run(1) == [Status.RUNNING]
    vehicle.set(rc__channels=(1500,) * 5 + (1900,))  # the pilot flips the take-over switch
    mission_run.mode = "MANUAL"
    commands_before = len(mission_run.commands)
    mission_run.run(30)
    assert mission_run.commands[commands_before:] == []  # no HOLD, no GUIDED while the pilot drives
    assert mission_state.legs.leg_index == 2
    vehicle.set(rc__channels=(1500,) * 6)
    mission_run.run(10)
    assert mission_run.commands[commands_before:] == []  # the switch back for 1 s first
    mission_run.run(2)
    assert mission_run.commands[commands_before:] == [("mode", "GUIDED")]
    assert mission_state.legs.leg_index == 2
    assert mission_run.run(200)[-1] == Status.SUCCESS


def test_ekf_loss_holds_the_vehicle_and_resumes_after_recovery(mission_run, mission_state, vehicle):
    while mission_state.legs.leg_index < 1:
        mission_run.run(1)
    vehicle.set(vehicle__ekf=EKF_LOST)
    mission_run.run(5)
    assert mission_run.commands[-1] == ("mode", "HOLD")
    leg = mission_state.legs.leg_index
    vehicle.set(vehicle__ekf=EKF_READY)
    mission_run.run(28)
    assert mission_run.commands[-1] == ("mode", "HOLD")  # the EKF sane for 3 s first
    mission_run.run(4)
    assert mission_run.commands[-1] == ("mode", "GUIDED")
    assert mission_state.legs.leg_index == leg


def test_a_guard_that_never_recovers_fails_the_mission(mission_run, square_mission, vehicle):
    mission_run.run(10)
    vehicle.set(link__up=False)
    statuses = mission_run.run(int(square_mission.limits.recovery_timeout_s * 10) + 20)
    assert statuses[-1] == Status.FAILURE


def test_a_leg_that_times_out_fails_the_mission(mission_run, square_mission):
    mission_run.step_m = 0.01  # the vehicle barely moves
    statuses = mission_run.run(int(square_mission.limits.leg_timeout_s * 10) + 30)
    assert statuses[-1] == Status.FAILURE


def test_pause_holds_the_vehicle_and_resume_continues_the_same_leg(mission_run, mission_state):
    while mission_state.legs.leg_index < 2:
        mission_run.run(1)
    mission_run.run(1)  # under way on leg 3
    mission_state.pause("operator: pause")
    statuses = mission_run.run(20)
    assert statuses == [Status.RUNNING] * 20
    assert mission_run.commands[-1] == ("mode", "HOLD")  # asked once, then held
    assert [c for c in mission_run.commands if c == ("mode", "HOLD")] == [("mode", "HOLD")]
    held_at = (mission_run.lat, mission_run.lon)
    mission_run.run(10)
    assert (mission_run.lat, mission_run.lon) == held_at
    assert mission_state.legs.leg_index == 2
    mission_state.resume()
    mission_run.run(2)
    assert mission_run.commands[-1] == ("mode", "GUIDED")  # back to GUIDED, same leg
    assert mission_state.legs.leg_index == 2
    assert mission_run.run(300)[-1] == Status.SUCCESS
    assert mission_state.legs.leg_index == 4


def test_a_loiter_of_our_own_delivered_late_mid_leg_is_undone_and_the_survey_completes(lockstep):
    """An overloaded companion computer: a mode it asked for (a link-loss failsafe's LOITER) reaches the boat late,
    in the middle of a leg. ArduRover drops GUIDED targets silently in LOITER: before GUIDED was checked every tick,
    the leg sat out its 90 s timeout 30 m short of the waypoint (the shape of the stressed run's abort: "leg 6/8
    failed: Go to waypoint: leg 6/8: timed out after 90 s, 3.7 m short")."""
    mission = load_mission(MISSIONS / "boat_survey.yaml")
    sim = lockstep(mission, ekf_ready_after_s=2.0)
    leg_6: list[float] = []
    sim.observers.append(lambda s: leg_6.append(s.clock.now()) if s.runtime.mission_state.legs.leg_index == 5 else None)
    sim.at(100.0, lambda s: s.runtime.link.commander.set_mode("LOITER"))  # leg 6 runs from ~84 s to ~113 s of vehicle time
    modes: list[str] = []
    sim.observers.append(lambda s: modes.append(s.autopilot.mode) if s.runtime.mission_state.legs.leg_index == 5 else None)
    outcome = sim.run_to_end(limit_s=400)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert "LOITER" in modes and modes[-1] == "GUIDED"  # it went to LOITER mid-leg and was taken back to GUIDED
    assert leg_6[0] < 100.0 < leg_6[-1] < leg_6[0] + 40.0  # leg 6 (60 m) barely longer than its ~30 s


def test_a_loiter_set_by_a_ground_station_mid_leg_is_a_person_s_and_guided_is_not_asked_for_again(lockstep):
    mission = load_mission(MISSIONS / "boat_survey.yaml")
    sim = lockstep(mission, ekf_ready_after_s=2.0)
    at_s = 25.0  # mid leg 2 (~12 s to ~43 s of vehicle time)
    sim.at(at_s, lambda s: s.autopilot.set_mode(s.autopilot.profile.modes["LOITER"]))  # not asked for by the executive
    modes: set[str] = set()
    sim.observers.append(lambda s: modes.add(s.autopilot.mode) if s.clock.now() > at_s else None)
    assert sim.run(limit_s=300, until=lambda: sim.clock.now() > at_s + 30.0) is None
    assert sim.status is MissionStatus.PAUSED and "ground station" in sim.runtime.mission_state.reason
    assert modes == {"LOITER"}  # the leg checks GUIDED every tick, but a person's mode wins
    assert sim.runtime.mission_state.legs.leg_index == 1  # set mid leg 2, paused there
