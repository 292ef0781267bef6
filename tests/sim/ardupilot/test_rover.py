"""The simulated ArduRover at the message level: no sockets, a manual clock."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.sim.ardupilot.base import EKF_FLAGS_READY
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Gcs

MakeGcs = Callable[..., "Gcs"]
PREARM_AHRS = "PreArm: AHRS: not using configured AHRS type"


def last(gcs: Gcs, kind: str) -> m.MAVLink_message:
    return gcs.of_type(gcs.log, kind)[-1]


def armed_in_guided(make_gcs: MakeGcs, kind: str = "rover") -> Gcs:
    gcs = make_gcs(kind, ekf_ready=True)
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
    return gcs


def test_boots_initialising_then_manual(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(run_s=0.5)
    heartbeat = last(gcs, "HEARTBEAT")
    assert (heartbeat.type, heartbeat.autopilot, heartbeat.custom_mode) == (m.MAV_TYPE_GROUND_ROVER, m.MAV_AUTOPILOT_ARDUPILOTMEGA, 16)
    assert heartbeat.system_status == m.MAV_STATE_CALIBRATING
    assert gcs.texts(gcs.log) == ["ArduRover V4.7.0-dev (sim)"]
    assert not gcs.of_type(gcs.log, "GLOBAL_POSITION_INT")  # only heartbeats while initialising
    assert gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == []  # not listening yet

    gcs.run(1.0)
    heartbeat = last(gcs, "HEARTBEAT")
    assert (heartbeat.custom_mode, heartbeat.system_status) == (0, m.MAV_STATE_ACTIVE)
    assert heartbeat.base_mode == m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
    assert "Ready to drive" in gcs.texts(gcs.log)


def test_a_boat_says_it_is_a_boat(make_gcs: MakeGcs) -> None:
    assert last(make_gcs("boat"), "HEARTBEAT").type == m.MAV_TYPE_SURFACE_BOAT


def test_arming_is_refused_until_the_ekf_is_ready(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    replies = gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    ack = replies[0]
    assert (ack.command, ack.result, ack.target_system, ack.target_component) == (m.MAV_CMD_COMPONENT_ARM_DISARM, m.MAV_RESULT_FAILED, 255, 190)
    assert gcs.texts(replies) == [PREARM_AHRS]
    assert gcs.arm(force=False) == m.MAV_RESULT_FAILED  # 21196 forces a disarm only; an arm with it is still checked
    assert gcs.ack(m.MAV_CMD_COMPONENT_ARM_DISARM, 1, 21196).result == m.MAV_RESULT_FAILED

    gcs.run(1.0)
    flags = last(gcs, "EKF_STATUS_REPORT").flags
    assert not flags & m.EKF_POS_HORIZ_ABS and flags & m.EKF_CONST_POS_MODE
    position = last(gcs, "GLOBAL_POSITION_INT")
    assert (position.lat, position.lon, position.relative_alt) == (round(gcs.ap.start[0] * 1e7), round(gcs.ap.start[1] * 1e7), 9700)
    assert not last(gcs, "SYS_STATUS").onboard_control_sensors_health & m.MAV_SYS_STATUS_PREARM_CHECK  # arming is refused

    gcs.run(10.0)
    assert last(gcs, "EKF_STATUS_REPORT").flags == EKF_FLAGS_READY == 831
    assert last(gcs, "GLOBAL_POSITION_INT").relative_alt == 0
    assert {"EKF3 IMU0 is using GPS", PREARM_AHRS} <= set(gcs.texts(gcs.log))  # ArduPilot repeats failing pre-arm checks
    replies = gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert replies[0].result == m.MAV_RESULT_ACCEPTED
    assert gcs.texts(replies) == ["Throttle armed"]
    gcs.run(1.0)
    assert last(gcs, "HEARTBEAT").base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED


def test_forced_arm_skips_the_checks_but_position_modes_still_need_the_ekf(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    assert gcs.arm(force=True) == m.MAV_RESULT_ACCEPTED
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15)
    assert replies[0].result == m.MAV_RESULT_FAILED
    assert gcs.texts(replies) == ["Flight mode change failed"]
    assert gcs.set_mode("HOLD") == m.MAV_RESULT_ACCEPTED
    assert gcs.texts(gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 0)) == ["Throttle disarmed"]
    assert gcs.ack(m.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == m.MAV_RESULT_ACCEPTED  # already disarmed: fine


def test_mode_changes_before_the_ekf_is_ready(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4)
    assert replies[0].result == m.MAV_RESULT_ACCEPTED
    assert (replies[1].get_type(), replies[1].custom_mode, replies[1].system_status) == ("HEARTBEAT", 4, m.MAV_STATE_STANDBY)
    assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED  # disarmed, ArduRover lets any mode in
    for mode in ("LOITER", "RTL", "SMART_RTL"):  # these need a position or a home right away
        replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, gcs.ap.profile.modes[mode])
        assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["Flight mode change failed"])
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 10)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["No Mission. Can't set AUTO.", "Flight mode change failed"])
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 99)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["No such mode 99"])
    assert gcs.ack(m.MAV_CMD_DO_SET_MODE, 0, 4).result == m.MAV_RESULT_DENIED  # no custom-mode flag
    assert gcs.ap.mode == "GUIDED"


def test_legacy_set_mode_is_acked_with_its_message_id(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    ack = gcs.send(gcs.mav.set_mode_encode(1, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4))[0]
    assert (ack.get_type(), ack.command, ack.result, ack.target_system) == ("COMMAND_ACK", m.MAVLINK_MSG_ID_SET_MODE, m.MAV_RESULT_ACCEPTED, 255)
    assert gcs.ap.mode == "HOLD"


def test_mode_changes_once_the_ekf_is_ready(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    for mode in ("LOITER", "GUIDED", "RTL", "HOLD", "MANUAL"):
        assert gcs.set_mode(mode) == m.MAV_RESULT_ACCEPTED
        assert last(gcs, "HEARTBEAT").custom_mode == gcs.ap.profile.modes[mode]
    gcs.set_mode("RTL")
    replies = gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["PreArm: Mode not armable"])


def test_a_repeated_command_with_confirmation_is_answered_the_same(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    for confirmation in (0, 1, 2):
        replies = gcs.send(gcs.mav.command_long_encode(1, 1, m.MAV_CMD_DO_SET_MODE, confirmation, 1, 4, 0, 0, 0, 0, 0))
        assert replies[0].result == m.MAV_RESULT_ACCEPTED


def test_unknown_commands_and_other_systems(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    assert gcs.ack(m.MAV_CMD_DO_VTOL_TRANSITION, m.MAV_VTOL_STATE_FW).result == m.MAV_RESULT_UNSUPPORTED
    assert gcs.command(m.MAV_CMD_DO_SET_MODE, 1, 4, target=(2, 1)) == []  # for another vehicle
    assert gcs.command(m.MAV_CMD_DO_SET_MODE, 1, 4, target=(1, 99)) == []  # for another component
    assert gcs.ack(m.MAV_CMD_DO_SET_MODE, 1, 4).result == m.MAV_RESULT_ACCEPTED  # target (1, 1)
    assert gcs.command(m.MAV_CMD_DO_SET_MODE, 1, 0, target=(0, 0))[0].result == m.MAV_RESULT_ACCEPTED  # broadcast


def test_guided_target_is_ignored_outside_guided(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    gcs.arm()
    gcs.set_mode("HOLD")
    assert gcs.goto(*gcs.north(20.0)) == []
    out = gcs.run(10.0)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) == 0.0
    assert not gcs.of_type(out, "POSITION_TARGET_GLOBAL_INT")


def test_guided_drives_to_the_target_and_holds_there(make_gcs: MakeGcs) -> None:
    gcs = armed_in_guided(make_gcs)
    target = gcs.north(20.0)
    assert gcs.goto(*target) == []  # never acknowledged
    out = gcs.run(3.0)
    reported = gcs.of_type(out, "POSITION_TARGET_GLOBAL_INT")[-1]
    assert (reported.lat_int, reported.lon_int) == (round(target[0] * 1e7), round(target[1] * 1e7))
    assert 10 <= gcs.of_type(out, "NAV_CONTROLLER_OUTPUT")[-1].wp_dist <= 18
    out = gcs.run(12.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [0]
    gcs.run(30.0)
    # reached once the shaped target is at the point and the rover within WP_RADIUS of it, then it stops (Mode::stop_vehicle)
    assert gcs.ap.vehicle.distance_to(*target) <= 1.0
    assert last(gcs, "GLOBAL_POSITION_INT").vx == 0


def test_guided_target_masks_and_frames(make_gcs: MakeGcs) -> None:
    gcs = armed_in_guided(make_gcs)
    target = gcs.north(20.0)
    assert gcs.texts(gcs.goto(*target, type_mask=0x0C38)) == ["Ignoring SET_POSITION_TARGET_GLOBAL_INT; set ACC_IGNORE in mask"]
    gcs.goto(*target, type_mask=0x0DFC)  # z ignored: ArduRover then ignores the whole position
    gcs.goto(*target, frame=m.MAV_FRAME_LOCAL_NED)
    gcs.run(5.0)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) == 0.0
    gcs.goto(*target, frame=m.MAV_FRAME_GLOBAL_INT)
    gcs.run(5.0)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) > 3.0


def test_a_disarmed_vehicle_never_moves(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("boat", ekf_ready=True)
    gcs.set_mode("GUIDED")
    target = gcs.north(20.0)
    gcs.goto(*target)
    gcs.run(60.0)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) == 0.0
    gcs.arm()
    gcs.run(20.0)
    assert gcs.ap.vehicle.distance_to(*target) < 1.0


def test_do_reposition_switches_to_guided_only_when_asked(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    gcs.arm()
    lat, lon = gcs.north(10.0)

    def reposition(flags: int) -> int:
        x, y = round(lat * 1e7), round(lon * 1e7)
        replies = gcs.send(gcs.mav.command_int_encode(1, 1, m.MAV_FRAME_GLOBAL_INT, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, flags, 0, 0, x, y, 0))
        assert replies[0].command == m.MAV_CMD_DO_REPOSITION
        return replies[0].result

    assert reposition(0) == m.MAV_RESULT_DENIED
    assert reposition(m.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE) == m.MAV_RESULT_ACCEPTED
    assert gcs.ap.mode == "GUIDED"
    gcs.run(15.0)
    assert gcs.ap.vehicle.distance_to(lat, lon) <= 1.0


def test_rtl_drives_home_and_stays_in_rtl(make_gcs: MakeGcs) -> None:
    gcs = armed_in_guided(make_gcs)
    gcs.goto(*gcs.north(30.0))
    gcs.run(25.0)
    assert gcs.ack(m.MAV_CMD_NAV_RETURN_TO_LAUNCH).result == m.MAV_RESULT_ACCEPTED
    out = gcs.run(30.0)
    assert "Reached destination" in gcs.texts(out)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.home) <= 0.3
    assert last(gcs, "HEARTBEAT").custom_mode == 11


def test_a_boat_in_loiter_holds_its_point_against_the_current(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("boat", ekf_ready=True)
    gcs.arm()
    gcs.set_mode("LOITER")
    farthest = 0.0
    for _ in range(300):
        gcs.run(1.0, step=0.5)
        farthest = max(farthest, gcs.ap.vehicle.distance_to(*gcs.ap.start))
    assert 1.0 < farthest < 2.5  # drifts to the loiter radius (2 m), then comes back
    gcs.set_mode("HOLD")
    gcs.run(200.0, step=0.5)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) > 3.0  # HOLD does not fight the current


def test_message_intervals(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()

    def attitude_per_10_s() -> int:
        return len(gcs.of_type(gcs.run(10.0, step=0.05), "ATTITUDE"))

    assert attitude_per_10_s() == pytest.approx(40, abs=1)
    assert gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE, 1_000_000).result == m.MAV_RESULT_ACCEPTED
    assert attitude_per_10_s() == pytest.approx(10, abs=1)
    gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE, -1)
    assert attitude_per_10_s() == 0
    replies = gcs.command(m.MAV_CMD_GET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE)
    assert (replies[0].result, replies[1].message_id, replies[1].interval_us) == (m.MAV_RESULT_ACCEPTED, m.MAVLINK_MSG_ID_ATTITUDE, -1)
    gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE, 0)
    assert attitude_per_10_s() == pytest.approx(40, abs=1)
    replies = gcs.command(m.MAV_CMD_SET_MESSAGE_INTERVAL, 9999, 1_000_000)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["No ap_message for mavlink id (9999)"])


def test_an_interval_set_restarts_that_message_only_and_the_boot_starts_the_streams(make_gcs: MakeGcs) -> None:
    """SET_MESSAGE_INTERVAL sends the message at its next update and every interval after; the other streams keep their
    times (each stream keeps its own schedule). Before the boot only HEARTBEAT goes out."""
    gcs = make_gcs(run_s=0.0)
    booting = {msg.get_type() for msg in gcs.run(0.95, step=0.05)}
    assert booting <= {"HEARTBEAT", "STATUSTEXT"}  # booting: no stream but HEARTBEAT (sent at 0 s, next at 1 s)
    assert gcs.of_type(gcs.run(1.1, step=0.05), "VFR_HUD")  # booted at 1 s: the streams run, every 0.25 s
    assert not gcs.of_type(gcs.run(0.05, step=0.05), "VFR_HUD")  # between two of its times
    gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE, 1_000_000)
    sent = gcs.run(0.05, step=0.05)
    assert gcs.of_type(sent, "ATTITUDE") and not gcs.of_type(sent, "VFR_HUD")  # ATTITUDE at once; VFR_HUD kept its time
    assert len(gcs.of_type(gcs.run(3.0, step=0.05), "ATTITUDE")) == 3  # then once a second


def test_request_message_and_home(make_gcs: MakeGcs) -> None:
    gcs = make_gcs()
    replies = gcs.command(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_HOME_POSITION)
    assert [r.get_type() for r in replies] == ["COMMAND_ACK"]  # accepted, but there is no home yet
    assert gcs.ack(m.MAV_CMD_DO_SET_HOME, 1).result == m.MAV_RESULT_FAILED
    gcs.run(10.0)
    replies = gcs.command(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_HOME_POSITION)
    assert [r.get_type() for r in replies] == ["COMMAND_ACK", "HOME_POSITION"]
    assert replies[1].latitude == round(gcs.ap.start[0] * 1e7)
    lat, lon = gcs.north(5.0)
    replies = gcs.command(m.MAV_CMD_DO_SET_HOME, 0, 0, 0, 0, lat, lon, 0)
    assert (replies[0].result, replies[1].latitude, replies[1].longitude) == (m.MAV_RESULT_ACCEPTED, round(lat * 1e7), round(lon * 1e7))
    assert gcs.ap.home == pytest.approx((lat, lon))
    assert gcs.ack(m.MAV_CMD_REQUEST_MESSAGE, 9999).result == m.MAV_RESULT_FAILED


def test_battery_drains_faster_when_driving(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    start = last(gcs, "SYS_STATUS")
    assert 12_000 < start.voltage_battery <= 12_600 and start.battery_remaining == 100
    idle_mah = gcs.ap.consumed_mah
    gcs = armed_in_guided(make_gcs)
    gcs.goto(*gcs.north(100.0))
    gcs.run(10.0)
    status = last(gcs, "SYS_STATUS")
    assert status.current_battery > start.current_battery
    assert gcs.ap.consumed_mah > 2 * idle_mah


@pytest.mark.parametrize(("kind", "param"), [("rover", "MODE_CH"), ("boat", "MODE_CH"), ("vtol", "FLTMODE_CH")])
def test_the_mode_switch_channel_is_answered_as_the_firmware_does(make_gcs: MakeGcs, kind: str, param: str) -> None:
    """ArduRover MODE_CH and ArduPlane FLTMODE_CH are channel 8 by default; an unknown parameter gets no answer."""
    gcs = make_gcs(kind)
    (value,) = gcs.send(gcs.mav.param_request_read_encode(1, 1, param.encode(), -1))
    assert (value.param_id, value.param_value, value.param_type) == (param, 8.0, m.MAV_PARAM_TYPE_INT8)
    (by_index,) = gcs.send(gcs.mav.param_request_read_encode(1, 1, b"", value.param_index))
    assert (by_index.param_id, by_index.param_index) == (param, value.param_index)
    assert gcs.send(gcs.mav.param_request_read_encode(1, 1, b"NO_SUCH_PARAM", -1)) == []
    assert gcs.send(gcs.mav.param_request_read_encode(2, 1, param.encode(), -1)) == []  # another vehicle's


def test_a_parameter_set_for_the_simulator_is_answered() -> None:
    from executive.sim.registry import make_autopilot
    from executive.world.clock import ManualClock

    ap = make_autopilot("rover", ManualClock(), params={"MODE_CH": 0, "WP_SPEED": 3.5})
    assert (ap.params["MODE_CH"], ap.params["WP_SPEED"], ap.params["ATC_ACCEL_MAX"]) == (0, 3.5, 1.0)  # the rest: the firmware's defaults


def test_the_ekf_failsafe_latches_holds_and_refuses_position_modes_until_a_second_after_the_ekf_recovers(make_gcs: MakeGcs) -> None:
    """Rover/ekf_check.cpp at 10 Hz: 10 bad checks latch failsafe.ekf (HOLD, "EKF failsafe"); Mode::enter refuses
    position modes while it is latched; 10 good checks clear it ("EKF failsafe cleared")."""
    gcs = armed_in_guided(make_gcs)
    gcs.ap.ekf_position_lost = True
    gcs.run(0.85)
    assert gcs.ap.mode == "GUIDED" and not gcs.ap.failsafe_ekf  # 9 bad checks: not yet
    gcs.run(0.2)
    assert gcs.ap.mode == "HOLD" and gcs.ap.failsafe_ekf
    assert "EKF failsafe" in gcs.texts(gcs.log)
    gcs.ap.ekf_position_lost = False  # the EKF is healthy again...
    gcs.run(0.5)
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, gcs.ap.profile.modes["GUIDED"])
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["Flight mode change failed"])  # ...but still latched
    assert gcs.set_mode("MANUAL") == m.MAV_RESULT_ACCEPTED and gcs.set_mode("HOLD") == m.MAV_RESULT_ACCEPTED  # no position needed
    gcs.run(0.6)
    assert not gcs.ap.failsafe_ekf and "EKF failsafe cleared" in gcs.texts(gcs.log)
    assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
