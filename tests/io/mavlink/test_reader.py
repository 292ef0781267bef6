"""The reader: every message drained, decoded onto the blackboard; nonsense never becomes truth."""

from __future__ import annotations

import math

import py_trees
import pytest

from executive.io.mavlink.reader import MavlinkReader
from executive.testing import AUTOPILOT, GCS, Peer, ack
from executive.world.dialect import mavlink
from executive.world.state import CommandState, EkfFlags

ARMED = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


def heartbeat(custom_mode: int = 4, base_mode: int = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, source=AUTOPILOT, mav_type=None):
    mav_type = mavlink.MAV_TYPE_GROUND_ROVER if mav_type is None else mav_type
    return source.heartbeat(mav_type, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode, custom_mode, mavlink.MAV_STATE_STANDBY)


@pytest.fixture
def reader(link, clock, commander) -> MavlinkReader:
    return MavlinkReader(link, clock, commander, link_timeout_s=3.0)


def receive(reader, link, *messages) -> int:
    link.incoming.extend(messages)
    return reader.drain()


def test_adopts_the_autopilot_not_the_ground_station(reader, link, commander):
    gcs = GCS.heartbeat(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    assert receive(reader, link, gcs, heartbeat()) == 2
    assert reader.autopilot == (1, 1)
    assert (bb("/link/system_id"), bb("/link/component_id")) == (1, 1)
    assert (commander.target_system, commander.target_component) == (1, 1)


def test_a_target_system_binds_to_that_autopilot_alone(link, clock, commander):
    """Issue 13: with vehicles 1 and 2 on the link, --target-system 2 must not bind to the first heartbeat (vehicle 1's)."""
    reader = MavlinkReader(link, clock, commander, target_system=2)
    assert (commander.target_system, commander.target_component) == (2, 1)  # addressed from the start
    other, mine = Peer(1, 1), Peer(2, 1)
    receive(reader, link, heartbeat(custom_mode=15, source=other))
    assert reader.autopilot is None and bb("/vehicle/mode") is None
    receive(reader, link, heartbeat(custom_mode=4, source=mine), heartbeat(custom_mode=15, source=other))
    assert reader.autopilot == (2, 1)
    assert bb("/vehicle/mode") == "HOLD"  # vehicle 1's GUIDED, heard after, is not ours
    assert reader.autopilots_heard == {1: mavlink.MAV_TYPE_GROUND_ROVER, 2: mavlink.MAV_TYPE_GROUND_ROVER}
    receive(reader, link, other.command_ack(mavlink.MAV_CMD_DO_SET_MODE, 0, 0, 0, 1, 191))
    assert (commander.target_system, commander.target_component) == (2, 1)


def test_no_target_system_binds_to_the_first_autopilot_and_notes_every_other(reader, link):
    receive(reader, link, heartbeat(), heartbeat(source=Peer(3, 1)))
    assert reader.autopilot == (1, 1)
    assert sorted(reader.autopilots_heard) == [1, 3]


def test_heartbeat_gives_mode_by_name_armed_and_link_up(reader, link):
    receive(reader, link, heartbeat(custom_mode=15, base_mode=ARMED))
    assert (bb("/vehicle/mode"), bb("/vehicle/custom_mode"), bb("/vehicle/armed")) == ("GUIDED", 15, True)
    assert bb("/link/up") is True
    receive(reader, link, heartbeat(custom_mode=4))
    assert (bb("/vehicle/mode"), bb("/vehicle/armed")) == ("HOLD", False)


def test_unknown_vehicle_type_mode_is_shown_by_number(reader, link):
    receive(reader, link, heartbeat(custom_mode=3, mav_type=mavlink.MAV_TYPE_QUADROTOR))
    assert bb("/vehicle/mode") == "MODE(3)"


def test_link_goes_down_after_the_timeout_and_comes_back(reader, link, clock):
    receive(reader, link, heartbeat())
    clock.advance(2.9)
    reader.drain()
    assert bb("/link/up") is True
    clock.advance(0.2)
    reader.drain()
    assert bb("/link/up") is False
    receive(reader, link, heartbeat())
    assert bb("/link/up") is True


def test_vehicle_facts_from_other_systems_are_ignored(reader, link):
    receive(reader, link, heartbeat(custom_mode=4))
    receive(reader, link, heartbeat(custom_mode=15, source=Peer(2, 1)))
    assert bb("/vehicle/mode") == "HOLD"


def test_global_position(reader, link, clock):
    pos = AUTOPILOT.global_position_int(0, 473977420, 85455940, 500, 1234, 100, -200, 5, 9000)
    receive(reader, link, heartbeat(), pos)
    p = bb("/vehicle/position")
    assert (p.lat, p.lon, p.alt_rel_m) == (47.397742, 8.545594, 1.234)
    assert (p.vn_m_s, p.ve_m_s, p.heading_deg, p.time) == (1.0, -2.0, 90.0, clock.now())
    assert p.ground_speed_m_s == pytest.approx(math.hypot(1, 2))


@pytest.mark.parametrize(("lat", "lon"), [(0, 0), (910000000, 0), (0, -1810000000)], ids=["no fix", "lat off the globe", "lon off the globe"])
def test_impossible_positions_never_reach_the_blackboard(reader, link, lat, lon):
    receive(reader, link, heartbeat(), AUTOPILOT.global_position_int(0, lat, lon, 0, 0, 0, 0, 0, 65535))
    assert bb("/vehicle/position") is None


def test_attitude_in_degrees_and_nan_dropped(reader, link):
    receive(reader, link, heartbeat(), AUTOPILOT.attitude(0, 0.1, -0.2, -math.pi / 2, 0, 0, 0.5))
    a = bb("/vehicle/attitude")
    assert (a.roll_deg, a.pitch_deg, a.yaw_deg) == pytest.approx((5.7296, -11.4592, 270.0), abs=1e-3)
    receive(reader, link, AUTOPILOT.attitude(0, float("nan"), 0, 0, 0, 0, 0))
    assert bb("/vehicle/attitude") == a


def test_ekf_status(reader, link):
    receive(reader, link, heartbeat(), AUTOPILOT.ekf_status_report(831, 0.1, 0.2, 0.3, 0.4, 0.0))
    ekf = bb("/vehicle/ekf")
    assert ekf.flags == EkfFlags(831) and ekf.position_ok()
    assert (ekf.velocity_variance, ekf.compass_variance) == pytest.approx((0.1, 0.4))


def test_battery_unknowns_are_none(reader, link):
    sys_status = AUTOPILOT.sys_status(0, 0, 0, 0, 12600, 150, 80, 0, 0, 0, 0, 0, 0)
    receive(reader, link, heartbeat(), sys_status)
    assert (bb("/vehicle/battery").voltage_v, bb("/vehicle/battery").current_a, bb("/vehicle/battery").remaining_pct) == (12.6, 1.5, 80)
    receive(reader, link, AUTOPILOT.sys_status(0, 0, 0, 0, 65535, -1, -1, 0, 0, 0, 0, 0, 0))
    assert (bb("/vehicle/battery").voltage_v, bb("/vehicle/battery").current_a, bb("/vehicle/battery").remaining_pct) == (None, None, None)


def test_rc_channels(reader, link, clock):
    channels = [1500] * 5 + [1900] + [1000] * 12
    receive(reader, link, heartbeat(), AUTOPILOT.rc_channels(0, 8, *channels, 200))
    assert bb("/rc/channels") == (1500, 1500, 1500, 1500, 1500, 1900, *[1000] * 12)  # every field, whatever chancount says
    assert (bb("/rc/rssi"), bb("/rc/connected"), bb("/rc/last_update"), bb("/rc/chancount")) == (200, True, clock.now(), 8)
    receive(reader, link, AUTOPILOT.rc_channels(0, 8, *([0] * 18), 255))
    assert (bb("/rc/rssi"), bb("/rc/connected")) == (None, False)


def test_a_channel_past_chancount_is_read(reader, link):
    """Issue 13: ArduPilot reported chancount 8 and acted on chan9_raw 1500 (an RC override of the knob); the reader dropped it."""
    receive(reader, link, heartbeat(), AUTOPILOT.rc_channels(0, 8, *[1500] * 8, 1800, *[65535] * 9, 255))
    assert bb("/rc/channels")[8] == 1800
    assert bb("/rc/channels")[9:] == (0,) * 9  # UINT16_MAX: no such channel


def test_param_value_is_kept_by_name(reader, link):
    receive(reader, link, heartbeat(), AUTOPILOT.param_value(b"MODE_CH", 8.0, mavlink.MAV_PARAM_TYPE_INT8, 1, 0))
    receive(reader, link, AUTOPILOT.param_value(b"FS_ACTION", 2.0, mavlink.MAV_PARAM_TYPE_INT8, 1, 0))
    assert bb("/vehicle/params") == {"MODE_CH": 8.0, "FS_ACTION": 2.0}


def test_command_ack_reaches_the_commander(reader, link, commander):
    receive(reader, link, heartbeat())
    commander.set_mode("GUIDED")
    commander.flush()
    receive(reader, link, ack(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_RESULT_DENIED))
    assert bb("/command/mode").state is CommandState.REJECTED


def test_statustext(reader, link):
    receive(reader, link, heartbeat(), AUTOPILOT.statustext(3, b"PreArm: AHRS: not using configured AHRS type"))
    assert bb("/vehicle/statustext") == (3, "PreArm: AHRS: not using configured AHRS type")


def test_the_autopilots_ekf_failsafe_is_on_from_its_notice_until_it_says_cleared(reader, link):
    # Rover/ekf_check.cpp: failsafe_ekf_event "EKF failsafe", failsafe_ekf_off_event "EKF failsafe cleared"
    receive(reader, link, heartbeat())
    assert bb("/vehicle/ekf_failsafe") is False
    receive(reader, link, AUTOPILOT.statustext(2, b"EKF failsafe"))
    assert bb("/vehicle/ekf_failsafe") is True
    receive(reader, link, AUTOPILOT.statustext(6, b"PreArm: AHRS: not using configured AHRS type"))
    assert bb("/vehicle/ekf_failsafe") is True  # another text changes nothing
    receive(reader, link, AUTOPILOT.statustext(2, b"EKF failsafe cleared"))
    assert bb("/vehicle/ekf_failsafe") is False


def test_garbage_bytes_are_counted_not_believed(reader, link):
    bad = mavlink.MAVLink_bad_data(b"\x01\x02\x03", "invalid MAVLink prefix")
    assert receive(reader, link, bad, heartbeat()) == 2
    assert bb("/link/bad_data") == 1
    assert bb("/link/messages") == 1


def test_sequence_gaps_are_packet_loss(reader, link):
    link.incoming.append(heartbeat())
    reader.drain()
    for seq in (5, 9):  # three and then three more lost in between
        msg = heartbeat()
        msg._header.seq = seq
        link.incoming.append(msg)
    reader.drain()
    assert bb("/link/packets_lost") > 0
    assert bb("/link/loss_pct") > 0


def test_reconnect_is_signalled_on_first_contact_link_return_and_reboot(reader, link, clock):
    calls = []
    reader.on_reconnect = lambda: calls.append(clock.now())
    receive(reader, link, heartbeat())
    assert len(calls) == 1
    clock.advance(5.0)
    reader.drain()  # link lost
    receive(reader, link, heartbeat())
    assert len(calls) == 2
    receive(reader, link, AUTOPILOT.attitude(90_000, 0, 0, 0, 0, 0, 0), AUTOPILOT.attitude(2_000, 0, 0, 0, 0, 0, 0))
    assert len(calls) == 3 and bb("/link/reboots") == 1


def test_home_gps_speed_servos_and_extended_state(reader, link):
    receive(
        reader,
        link,
        heartbeat(),
        AUTOPILOT.home_position(-353632610, 1491652300, 584000, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0),
        AUTOPILOT.gps_raw_int(0, 3, 0, 0, 0, 120, 65535, 0, 0, 11),
        AUTOPILOT.vfr_hud(0.0, 2.5, 271, 50, 0.0, 0.0),
        AUTOPILOT.servo_output_raw(0, 0, 1900, 1500, 1100, 1500, 0, 0, 0, 0),
        AUTOPILOT.extended_sys_state(mavlink.MAV_VTOL_STATE_FW, mavlink.MAV_LANDED_STATE_IN_AIR),
    )
    home = bb("/vehicle/home")
    assert (home.lat, home.lon, home.alt_m) == (-35.363261, 149.16523, 584.0)
    gps = bb("/vehicle/gps")
    assert (gps.fix_type, gps.satellites, gps.hdop, gps.has_3d_fix) == (3, 11, 1.2, True)
    assert (bb("/vehicle/ground_speed_m_s"), bb("/vehicle/heading_deg")) == (2.5, 271.0)
    assert bb("/vehicle/servo_outputs")[:4] == (1900, 1500, 1100, 1500)
    assert (bb("/vehicle/vtol_state"), bb("/vehicle/landed_state")) == ("FW", "IN_AIR")


def test_a_heartbeat_saying_it_is_starting_again_is_a_reboot(reader, link):
    calls = []
    reader.on_reconnect = lambda: calls.append(1)
    boot = AUTOPILOT.heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, 3, 0, 16, mavlink.MAV_STATE_CALIBRATING)
    receive(reader, link, boot, boot, heartbeat())  # first contact while booting: one reconnect, no reboot
    assert (len(calls), bb("/link/reboots")) == (1, 0)
    receive(reader, link, boot)
    assert (len(calls), bb("/link/reboots")) == (2, 1)


def test_battery_status_of_battery_0_read_as_energy_its_unknowns_none(reader, link):
    """ArduPilot's (GCS_Common.cpp send_battery_status): the pack's voltage in cell 0, energy_consumed in hJ (consumed_wh * 36)."""
    cells = [12345] + [65535] * 9
    receive(reader, link, heartbeat(), AUTOPILOT.battery_status(0, 0, 0, 32767, cells, 550, 1200, 540, 88, 0, 1))
    status = bb("/vehicle/battery_status")
    assert (status.consumed_mah, status.consumed_wh, status.remaining_pct, status.time_remaining_s) == (1200.0, 15.0, 88, None)
    assert (status.voltage_v, status.current_a, status.charge_state) == (12.345, 5.5, 1)
    # PX4's (BATTERY_STATUS.hpp): energy_consumed -1; a voltage-only monitor: no current, nothing consumed, no remaining
    receive(reader, link, AUTOPILOT.battery_status(0, 0, 0, 32767, cells, -1, -1, -1, -1, 0, 0))
    status = bb("/vehicle/battery_status")
    assert (status.consumed_mah, status.consumed_wh, status.remaining_pct, status.current_a) == (None, None, None, None)
    receive(reader, link, AUTOPILOT.battery_status(1, 0, 0, 32767, cells, 100, 100, 100, 10, 0, 0))  # a second battery: not the main one
    assert bb("/vehicle/battery_status") is status


def test_px4s_integer_parameters_are_read_from_their_bytes_ardupilots_as_cast(reader, link):
    """PX4 copies an INT32 parameter's bytes into param_value (mavlink_parameters.cpp send_param): BAT1_N_CELLS 4 is 4,
    not 5.6e-45; ArduPilot casts it to a float (MODE_CH 8.0)."""
    import struct

    px4 = AUTOPILOT.heartbeat(mavlink.MAV_TYPE_VTOL_TILTROTOR, mavlink.MAV_AUTOPILOT_PX4, 0, 0, mavlink.MAV_STATE_STANDBY)
    as_float = struct.unpack("<f", struct.pack("<i", 4))[0]
    receive(reader, link, px4, AUTOPILOT.param_value(b"BAT1_N_CELLS", as_float, mavlink.MAV_PARAM_TYPE_INT32, 1, 0))
    receive(reader, link, AUTOPILOT.param_value(b"BAT1_CAPACITY", 5000.0, mavlink.MAV_PARAM_TYPE_REAL32, 1, 0))
    assert bb("/vehicle/params") == {"BAT1_N_CELLS": 4.0, "BAT1_CAPACITY": 5000.0}
