"""What real PX4 said, recorded, read by the executive (issue 23): CI keeps our reading of the real firmware honest.

The recordings (tests/data/px4/, cut from one run of missions/vtol_transit.yaml, unmodified, against
PX4 main a70a558393 software-in-the-loop with SIH physics, standard VTOL, speed factor 1; the run
COMPLETED) go through the MAVLink reader, the PX4 autopilot port and the intervention watch
(tests/tlog_replay.py). Times are seconds from the first record of each file.
``vtol_climb_past_hagl.tlog`` (issue 44) is cut (seconds 54-70) from a run of vtol_transit.yaml with its first waypoint
at 120 m, same firmware, instance 2, speed factor 1, filtered to HEARTBEAT, GLOBAL_POSITION_INT, ESTIMATOR_STATUS,
SYS_STATUS, EXTENDED_SYS_STATE, STATUSTEXT and the commands; that run ABORTED on the NaN it records (fixed since).
"""

from __future__ import annotations

import pytest
from tlog_replay import PX4, Replay, records

from executive.behaviours import EkfOk
from executive.mission.lifecycle import MissionStatus
from executive.world import blackboard
from executive.world.dialect import mavlink


def test_at_rest_before_arming_px4_reports_constant_position_mode_with_its_gnss_position_and_the_ekf_guard_passes() -> None:
    """ekf_helper.cpp: CONST_POS_MODE for vehicle_at_rest: 0x3ff on the ground before arming, the real cause of issue 23's abort."""
    replay = Replay().play(PX4 / "vtol_at_rest_and_arming.tlog", until_s=3.5)
    ekf = replay.bb.get("/vehicle/ekf")
    assert ekf is not None and int(ekf.flags) == 0x3FF and replay.values("/vehicle/armed") == [False]
    assert EkfOk().check() is None


def test_armed_on_the_ground_the_flag_goes_and_offboard_is_ours() -> None:
    replay = Replay().play(PX4 / "vtol_at_rest_and_arming.tlog")
    assert replay.values("/vehicle/armed") == [False, True]
    assert int(replay.bb.get("/vehicle/ekf").flags) == 0x37F  # the motors shake the IMU: not at rest any more
    assert replay.values("/vehicle/mode") == [None, "AUTO.LOITER", "OFFBOARD"]  # AUTO.LOITER from boot, on the ground too
    assert replay.values("/vehicle/mode_set_by")[-1] == "us"
    sent = [msg for _, msg in records(PX4 / "vtol_at_rest_and_arming.tlog") if msg.get_type() == "COMMAND_LONG"]
    takeoff = next(msg for msg in sent if msg.command == mavlink.MAV_CMD_NAV_TAKEOFF)
    assert takeoff.param5 != takeoff.param5 and takeoff.param6 != takeoff.param6  # NaN: here (0, 0 never climbed)
    assert takeoff.param7 == pytest.approx(614.0, abs=1.0)  # home 584 m AMSL + 30 m


def test_the_take_off_is_seen_climbing_then_in_the_air_at_its_height() -> None:
    replay = Replay().play(PX4 / "vtol_takeoff.tlog")
    assert "Takeoff detected\t" in [text for _, text in filter(None, replay.values("/vehicle/statustext"))]
    assert replay.values("/vehicle/landed_state") == [None, "TAKEOFF", "IN_AIR"]
    assert replay.values("/vehicle/mode") == [None, "OFFBOARD", "AUTO.TAKEOFF", "AUTO.LOITER"]
    assert replay.when("/vehicle/landed_state", "IN_AIR") < replay.when("/vehicle/mode", "AUTO.LOITER")
    assert replay.bb.get("/vehicle/position").alt_rel_m > 29.0
    # the hover point's DO_REPOSITION went out as the take-off ended: its AUTO.LOITER is ours; never a person's
    assert replay.values("/vehicle/mode_set_by")[-1] == "us" and replay.state.status is MissionStatus.RUNNING


def test_without_our_reposition_the_loiter_after_the_take_off_is_the_autopilots_own() -> None:
    """Commander::checkForMissionUpdate: AUTO.TAKEOFF done, AUTO.LOITER; the height of our take-off tells it from a person's Hold."""
    replay = Replay(unasked=frozenset({mavlink.MAV_CMD_DO_REPOSITION})).play(PX4 / "vtol_takeoff.tlog")
    assert replay.values("/vehicle/mode_set_by")[-1] == "autopilot" and replay.state.status is MissionStatus.RUNNING


def test_px4s_own_end_of_the_take_off_is_told_by_its_altitude_above_sea_level_though_its_home_moved_up() -> None:
    """Issue 41: the real SIH ended its take-off by itself (no DO_REPOSITION of ours in that run) with GLOBAL_POSITION_INT
    28.22 m above home for a 30 m take-off: PX4 had corrected home's altitude 1.07 m up in the air (HomePosition.cpp). Its
    own test passed on its estimate above sea level (612.888 m > 613.686 - NAV_MC_ALT_RAD 0.8): the autopilot's, no pause."""
    path = PX4 / "vtol_takeoff_end_home_moved.tlog"
    homes = [msg.altitude / 1000 for _, msg in records(path) if msg.get_type() == "HOME_POSITION"]
    assert homes[0] == pytest.approx(583.686) and max(homes) - homes[0] > 1.0  # home moved in the air
    texts = [msg.text for _, msg in records(path) if msg.get_type() == "STATUSTEXT"]
    assert not any("akeoff" in text and "etected" not in text for text in texts)  # PX4 says nothing when its take-off ends
    replay = Replay().play(path)
    assert replay.values("/vehicle/mode") == [None, "AUTO.LOITER", "OFFBOARD", "AUTO.TAKEOFF", "AUTO.LOITER"]
    switched = replay.last_when("/vehicle/mode", "AUTO.LOITER")
    t0 = min(t for t, _ in records(path))
    judged = [msg for t, msg in records(path) if msg.get_type() == "GLOBAL_POSITION_INT" and t - t0 <= switched][-1]
    assert judged.relative_alt < 28_500 and judged.alt > 612_886  # the report the change was judged on (the one after: 29.60 m)
    assert replay.values("/vehicle/mode_set_by")[-1] == "autopilot" and replay.state.status is MissionStatus.RUNNING


def test_the_same_loiter_is_a_persons_on_a_vehicle_whose_nav_mc_alt_rad_it_could_not_have_passed() -> None:
    """The take-off's end is judged by the NAV_MC_ALT_RAD the vehicle answered (here 0.1 m): 0.70 m under the altitude asked,
    PX4 would still have been climbing, so the loiter is a person's and the mission pauses."""
    replay = Replay()
    blackboard.writer("test", ["/vehicle/params"]).set("/vehicle/params", {"NAV_MC_ALT_RAD": 0.1})
    replay.play(PX4 / "vtol_takeoff_end_home_moved.tlog")
    assert replay.values("/vehicle/mode_set_by")[-1] == "others" and replay.state.status is MissionStatus.PAUSED


def test_the_transitions_show_in_extended_sys_state_both_ways() -> None:
    replay = Replay().play(PX4 / "vtol_transitions.tlog")
    assert replay.values("/vehicle/vtol_state") == [None, "TRANSITION_TO_FW", "FW", "TRANSITION_TO_MC", "MC"]
    to_fw = replay.when("/vehicle/vtol_state", "FW") - replay.when("/vehicle/vtol_state", "TRANSITION_TO_FW")
    assert 2.0 < to_fw < 4.0  # 3 s at ~9.7 m/s airspeed; back to MC in 1 s
    acks = [(msg.command, msg.result) for _, msg in records(PX4 / "vtol_transitions.tlog") if msg.get_type() == "COMMAND_ACK"]
    assert acks.count((mavlink.MAV_CMD_DO_VTOL_TRANSITION, mavlink.MAV_RESULT_ACCEPTED)) == 2
    assert replay.values("/vehicle/mode")[-1] == "AUTO.RTL" and replay.values("/vehicle/mode_set_by")[-1] == "us"


def test_after_the_rtl_landing_px4_disarms_and_its_own_auto_loiter_is_not_a_persons() -> None:
    replay = Replay().play(PX4 / "vtol_landing.tlog")
    texts = [text for _, text in filter(None, replay.values("/vehicle/statustext"))]
    assert texts.index("Landing detected\t") < texts.index("Disarmed by landing\t")
    assert replay.values("/vehicle/landed_state")[-2:] == ["LANDING", "ON_GROUND"]
    assert replay.values("/vehicle/mode") == [None, "AUTO.LOITER", "AUTO.RTL", "AUTO.LOITER"]
    assert replay.values("/vehicle/mode_set_by") == [None, "us", "autopilot"]
    assert replay.last_when("/vehicle/armed", False) == replay.last_when("/vehicle/mode", "AUTO.LOITER")  # one heartbeat: disarmed, loitering
    assert replay.state.status is MissionStatus.RUNNING


def test_judged_by_ardupilots_rules_the_same_change_would_be_a_persons_and_pause() -> None:
    """A control: ArduPilot has no such transition, so the watch that let it pass is the one that would pause otherwise."""
    replay = Replay(judged_as="ardupilot").play(PX4 / "vtol_landing.tlog")
    assert replay.values("/vehicle/mode_set_by")[-1] == "others" and replay.state.status is MissionStatus.PAUSED


def test_climbing_past_the_height_above_ground_it_can_fuse_px4_reports_a_nan_hagl_ratio_and_the_ekf_stays_judged() -> None:
    """Issue 44, real PX4 SIH standard_vtol climbing to a 120 m waypoint: from 96.6 m ESTIMATOR_STATUS's hagl_ratio is NaN
    (estimator_status.hagl_test_ratio: no height above the ground fused). The whole report was dropped: 3 s later the EKF
    guard held the aircraft (failsafe ekf_loss) and the mission aborted 60 s on. A test not made is no broken report."""
    path = PX4 / "vtol_climb_past_hagl.tlog"
    hagl = [msg.hagl_ratio for _, msg in records(path) if msg.get_type() == "ESTIMATOR_STATUS"]
    assert any(r != r for r in hagl) and any(r == r for r in hagl)  # NaN from part-way through
    replay = Replay().play(path)
    ekf = replay.bb.get("/vehicle/ekf")
    last = max(t for t, _ in records(path)) - min(t for t, _ in records(path))
    assert ekf is not None and last - ekf.time < 1.0  # still read at 2 Hz to the end
    assert int(ekf.flags) == 0x37F and EkfOk().check() is None
