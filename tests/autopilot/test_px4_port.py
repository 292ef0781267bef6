"""The PX4 back end, tick by tick: one test (or a few) per PX4 fact of issue 12."""

from __future__ import annotations

import itertools
import math

import pytest
from py_trees.common import Status

from executive.behaviours import Arm, DriveRouteInAuto, EkfOk, GpsNotGlitching, SetMode, TakeOff, VtolTransition, WaitUntil
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.mission_protocol import route_items
from executive.io.mavlink.modes import Px4Modes
from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.streams import rates_for
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.mission.rules import autopilot_errors
from executive.testing import AUTOPILOT, Harness, Peer
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import (
    GlobalPosition,
    HomePosition,
    MissionCurrent,
    MissionItemReached,
    MissionTransferStatus,
    TransferOperation,
    TransferState,
)

_M = mavlink
R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
HOME = HomePosition(47.397742, 8.545594, 488.0, 0.0)
LOITER, OFFBOARD = 0x03040000, 6 << 16


def pos(alt: float = 0.0, t: float = 100.0) -> GlobalPosition:
    return GlobalPosition(HOME.lat, HOME.lon, alt, 0.0, 0.0, 0.0, 0.0, t)


@pytest.fixture
def px4(autopilot):
    autopilot.adopt(_M.MAV_AUTOPILOT_PX4, _M.MAV_TYPE_VTOL_QUADROTOR)
    return autopilot


def px4_ack(command: int, result: int) -> object:
    return AUTOPILOT.command_ack(command, result, 0, 0, 1, 191)


def sent_modes(link) -> list[tuple[int, int]]:
    return [(int(m.param2), int(m.param3)) for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_DO_SET_MODE]


# -- DO_SET_MODE is acked twice: the first ACCEPTED is the receiver's, the commander's result decides -------------


def test_the_first_accepted_of_a_mode_change_is_not_its_result(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="AUTO.LOITER", link__last_heartbeat=99.0)
    node = SetMode("RTL", confirm_by_ack=True)
    h = harness(node)
    assert h.tick() == R
    assert sent_modes(link) == [(4, 5)]  # AUTO.RTL: main 4, sub 5
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_ACCEPTED))  # MAVLink receiver: received
    assert h.tick() == R  # not confirmed by that ack, even with confirm_by_ack
    assert blackboard.reader("t", ["/command/mode"]).get("/command/mode").state.name == "IN_PROGRESS"
    vehicle.set(vehicle__statustext=(4, "Switching to RTL is currently not available"))
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_TEMPORARILY_REJECTED))  # the commander's answer
    assert h.tick() == F
    assert node.feedback_message == "refused: TEMPORARILY_REJECTED (Switching to RTL is currently not available)"


def test_a_mode_change_is_confirmed_by_the_heartbeat(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="AUTO.LOITER")
    h = harness(SetMode("RTL"))
    h.tick()
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_ACCEPTED))
    assert h.tick() == R
    vehicle.set(vehicle__mode="AUTO.RTL")
    assert h.tick() == S


def test_on_ardupilot_the_first_accepted_is_the_result(autopilot, harness, vehicle):
    vehicle.set(vehicle__mode="HOLD", link__last_heartbeat=99.0)
    node = SetMode("GUIDED", confirm_by_ack=True)
    h = harness(node)
    h.tick()
    h.ack(_M.MAV_CMD_DO_SET_MODE)
    assert h.tick() == S


# -- OFFBOARD lives on a setpoint stream -------------------------------------------------------------------------


def test_offboard_is_asked_only_after_the_stream_has_run_and_the_stream_goes_on_while_in_offboard(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="AUTO.LOITER", vehicle__position=pos(10.0))
    h = harness(SetMode("GUIDED"))
    setpoints: list[float] = []
    asked_at = None
    for _ in range(10):  # 1 s at 10 Hz
        h.tick()
        setpoints += [h.clock.now()] * len(link.take("SET_POSITION_TARGET_GLOBAL_INT"))
        if sent_modes(link) and asked_at is None:
            asked_at = h.clock.now()
    assert len(setpoints) == 10  # a setpoint every tick from the first one: 10 Hz, over PX4's 2 Hz
    assert asked_at is not None and 0.5 <= asked_at - setpoints[0] < 0.6  # OFFBOARD asked once the stream has run 0.5 s
    vehicle.set(vehicle__mode="OFFBOARD")
    assert h.tick() == S
    link.take()
    for _ in range(20):  # 2 s in OFFBOARD: the tree has moved on, the stream has not stopped (COM_OF_LOSS_T is 1 s)
        h.tick()
        assert len(link.take("SET_POSITION_TARGET_GLOBAL_INT")) == 1


def test_leaving_offboard_is_asking_for_loiter_first_and_the_stream_stops_once_the_heartbeat_shows_it(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="OFFBOARD", vehicle__position=pos(10.0))
    px4.set_mode("GUIDED")
    h = harness(SetMode("QLOITER"))  # the safe mode: AUTO.LOITER
    h.commander.flush()
    link.take()
    h.tick()
    assert sent_modes(link) == [(4, 3)]
    assert len(link.take("SET_POSITION_TARGET_GLOBAL_INT")) == 1
    for _ in range(5):  # PX4 has not switched yet: the stream goes on
        h.tick()
        assert len(link.take("SET_POSITION_TARGET_GLOBAL_INT")) == 1
    vehicle.set(vehicle__mode="AUTO.LOITER")
    assert h.tick() == S
    for _ in range(10):
        h.tick()
    assert link.take("SET_POSITION_TARGET_GLOBAL_INT") == []


def test_a_goto_in_offboard_streams_its_target(px4, harness, vehicle, link, mission_state):
    from executive.behaviours import GoTo

    mission_state.start()
    vehicle.set(vehicle__mode="OFFBOARD", vehicle__position=pos(10.0))
    h = harness(GoTo(1.5, 60.0, resend_s=1.0))
    target = mission_state.legs.target
    for _ in range(10):
        h.tick()
        sent = link.take("SET_POSITION_TARGET_GLOBAL_INT")
        assert [(m.lat_int, m.lon_int) for m in sent] == [(round(target.lat * 1e7), round(target.lon * 1e7))]


# -- custom_mode: main mode bits 16-23, sub mode 24-31 ------------------------------------------------------------


def test_custom_mode_packs_main_and_sub_modes() -> None:
    modes = Px4Modes()
    assert modes.decode(LOITER) == "AUTO.LOITER"  # where PX4 sits, on the ground too
    assert modes.decode(OFFBOARD) == "OFFBOARD"
    assert modes.encode("GUIDED") == (6.0, 0.0)
    assert modes.encode("AUTO") == (4.0, 4.0)
    assert modes.encode("QRTL") == (4.0, 5.0)
    assert modes.decode((4 << 16) | (42 << 24)) == "MODE(4.42)"


# -- NAV_TAKEOFF param7 is AMSL; DO_REPOSITION as COMMAND_INT x1e7 ------------------------------------------------


def test_takeoff_altitude_is_above_sea_level(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="OFFBOARD", vehicle__armed=True, vehicle__landed_state="ON_GROUND", vehicle__position=pos(), vehicle__home=HOME)
    harness(TakeOff(30.0)).tick()
    (cmd,) = [m for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_NAV_TAKEOFF]
    assert cmd.param7 == pytest.approx(518.0)
    # navigator_main.cpp VEHICLE_CMD_NAV_TAKEOFF: finite param5/param6 are the take-off point (0, 0 never climbed): NaN, here
    assert (cmd.param1, cmd.param2, cmd.param3) == (0.0, 0.0, 0.0) and all(map(math.isnan, (cmd.param4, cmd.param5, cmd.param6)))


def test_takeoff_before_home_is_known_asks_for_the_default_height(px4, harness, vehicle, link):
    vehicle.set(vehicle__armed=True, vehicle__landed_state="ON_GROUND", vehicle__position=pos())
    harness(TakeOff(30.0)).tick()
    (cmd,) = [m for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_NAV_TAKEOFF]
    assert math.isnan(cmd.param7)


def test_reposition_is_a_command_int_with_the_change_mode_flag_and_an_altitude_above_sea_level(px4, vehicle, link, commander):
    vehicle.set(vehicle__home=HOME)
    request = px4.reposition(47.4, 8.55, 40.0)
    commander.flush()
    (cmd,) = link.take("COMMAND_INT")
    assert request.outcome == "reposition"
    assert (cmd.command, cmd.frame, cmd.x, cmd.y) == (_M.MAV_CMD_DO_REPOSITION, _M.MAV_FRAME_GLOBAL_INT, 474000000, 85500000)
    assert int(cmd.param2) & _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
    assert cmd.z == pytest.approx(528.0)


# -- arming is refused for a few seconds after boot: a refusal is retried -----------------------------------------


def test_an_arm_refused_after_boot_is_asked_again(px4, harness, vehicle, link):
    vehicle.set(vehicle__armed=False)
    h = harness(WaitUntil(Arm(), 60.0, retry_s=2.0))
    h.tick()
    arms = [m for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_COMPONENT_ARM_DISARM]
    assert len(arms) == 1
    vehicle.set(vehicle__statustext=(3, "Arming denied: Resolve system health failures first"))
    h.commander.on_ack(px4_ack(_M.MAV_CMD_COMPONENT_ARM_DISARM, _M.MAV_RESULT_TEMPORARILY_REJECTED))
    statuses = [h.tick() for _ in range(25)]
    assert F not in statuses
    arms = [m for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_COMPONENT_ARM_DISARM]
    assert len(arms) == 1  # asked again once, 2 s after the refusal
    vehicle.set(vehicle__armed=True)
    assert h.tick() == S


# -- estimator health: ESTIMATOR_STATUS flags and SYS_STATUS health bits ------------------------------------------

ESTIMATOR_GOOD = (
    _M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_VELOCITY_HORIZ | _M.ESTIMATOR_VELOCITY_VERT | _M.ESTIMATOR_POS_HORIZ_REL
    | _M.ESTIMATOR_POS_HORIZ_ABS | _M.ESTIMATOR_POS_VERT_ABS | _M.ESTIMATOR_PRED_POS_HORIZ_REL | _M.ESTIMATOR_PRED_POS_HORIZ_ABS
)  # fmt: skip


@pytest.fixture
def reader(link, clock, commander) -> MavlinkReader:
    reader = MavlinkReader(link, clock, commander, link_timeout_s=3.0)
    link.incoming.append(AUTOPILOT.heartbeat(_M.MAV_TYPE_VTOL_QUADROTOR, _M.MAV_AUTOPILOT_PX4, 0, LOITER, _M.MAV_STATE_STANDBY))
    reader.drain()
    return reader


def estimator(flags: int, ratio: float = 0.1) -> object:
    return AUTOPILOT.estimator_status(0, flags, ratio, ratio, ratio, ratio, 0.0, 0.0, 0.5, 0.8)


def sys_status(health: int) -> object:
    present = _M.MAV_SYS_STATUS_AHRS | _M.MAV_SYS_STATUS_SENSOR_GPS | _M.MAV_SYS_STATUS_SENSOR_3D_GYRO
    return AUTOPILOT.sys_status(present, present, health, 0, 12000, 100, 90, 0, 0, 0, 0, 0, 0)


def guard_says(guard, link, reader, *messages) -> str | None:
    link.incoming.extend(messages)
    reader.drain()
    return guard.check()


def test_the_ekf_guard_reads_estimator_status_on_px4(reader, link):
    guard = EkfOk()
    assert guard_says(guard, link, reader) == "no EKF status yet"
    assert guard_says(guard, link, reader, estimator(_M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_CONST_POS_MODE)).startswith("EKF has no position")
    assert guard_says(guard, link, reader, estimator(ESTIMATOR_GOOD)) is None
    assert guard_says(guard, link, reader, estimator(ESTIMATOR_GOOD, ratio=1.2)) == "EKF variances over 0.8"


def test_constant_position_mode_at_rest_with_gnss_is_a_known_position_on_px4(reader, link):
    """ekf_helper.cpp get_ekf_soln_status: CONST_POS_MODE = fake_pos || valid_fake_pos || vehicle_at_rest; the real SITL
    reported 0x3ff at rest before take-off. With an aiding source fused (PRED_POS_HORIZ_REL) it is the vehicle at rest."""
    guard = EkfOk()
    assert guard_says(guard, link, reader, estimator(0x3FF)) is None
    # no aiding fused: the constant position is a faked one (fake_pos_control.cpp runs only while none is)
    no_aiding = 0x3FF & ~(_M.ESTIMATOR_PRED_POS_HORIZ_REL | _M.ESTIMATOR_PRED_POS_HORIZ_ABS)
    assert guard_says(guard, link, reader, estimator(no_aiding)) == f"EKF has no position estimate (flags 0x{no_aiding:x})"
    assert guard_says(guard, link, reader, estimator(0x3FF & ~(_M.ESTIMATOR_POS_HORIZ_ABS | _M.ESTIMATOR_POS_HORIZ_REL))).startswith(
        "EKF has no position"
    )


def test_constant_position_mode_on_ardupilot_is_still_no_position(link, clock, commander):
    """ArduRover's own test (ekf_position_ok): a position and not CONST_POS_MODE, whatever else is set."""
    reader = MavlinkReader(link, clock, commander, link_timeout_s=3.0)
    link.incoming.append(AUTOPILOT.heartbeat(_M.MAV_TYPE_GROUND_ROVER, _M.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, _M.MAV_STATE_STANDBY))
    link.incoming.append(AUTOPILOT.ekf_status_report(0x3FF, 0.1, 0.1, 0.1, 0.1, 0.0))
    reader.drain()
    assert EkfOk().check() == "EKF has no position estimate (flags 0x3ff)"


def test_estimator_gps_glitch_is_a_glitch_not_an_uninitialised_ekf(reader, link):
    glitch = GpsNotGlitching()
    assert guard_says(glitch, link, reader, estimator(ESTIMATOR_GOOD | _M.ESTIMATOR_GPS_GLITCH)) == "the EKF flags a GPS glitch (GPS_GLITCHING)"
    assert EkfOk().check() is None


def test_without_estimator_status_the_sys_status_health_bits_tell(reader, link, clock):
    guard = EkfOk()
    healthy = _M.MAV_SYS_STATUS_AHRS | _M.MAV_SYS_STATUS_SENSOR_GPS | _M.MAV_SYS_STATUS_SENSOR_3D_GYRO
    assert guard_says(guard, link, reader, sys_status(healthy)) is None
    assert guard_says(guard, link, reader, sys_status(_M.MAV_SYS_STATUS_AHRS)).startswith("EKF has no position")
    assert guard_says(guard, link, reader, estimator(ESTIMATOR_GOOD)) is None
    # a fresh ESTIMATOR_STATUS wins over the health bits; a stale one does not
    assert guard_says(guard, link, reader, sys_status(_M.MAV_SYS_STATUS_AHRS)) is None
    clock.advance(3.5)
    assert guard_says(guard, link, reader, sys_status(_M.MAV_SYS_STATUS_AHRS)).startswith("EKF has no position")


def test_px4_streams_ask_for_estimator_status_not_ekf_status_report() -> None:
    rates = rates_for("vtol", "px4")
    assert "ESTIMATOR_STATUS" in rates and "EKF_STATUS_REPORT" not in rates
    assert "EKF_STATUS_REPORT" in rates_for("vtol") and "ESTIMATOR_STATUS" not in rates_for("vtol")


# -- missions: AUTO.MISSION waits out PX4's check of a new mission; a finished mission is state 5 ------------------


def test_the_route_is_started_a_second_after_the_upload_was_acked(px4, clock, link, commander):
    done = MissionTransferStatus(1, TransferOperation.UPLOAD, TransferState.DONE, 3, 3, "", 0, 0, False, clock.now())
    blackboard.writer("t", ["/link/mission_transfer"]).set("/link/mission_transfer", done)
    acked_at = clock.now()
    px4.start_route()
    sent_at = None
    for _ in range(20):
        commander.flush()
        if sent_modes(link):
            sent_at = clock.now()
            break
        clock.advance(0.1)
    assert sent_at is not None and 1.2 <= sent_at - acked_at < 1.3  # asked at once, PX4 refuses it while it checks the mission


MISSION_REFUSED = "Switching to Mission is currently not available"


def _route_start(px4, harness, vehicle, clock):
    """SetMode("AUTO") on PX4 just after an upload was acked: AUTO.MISSION, asked 1.2 s later (then again per ROUTE_START_RETRY)."""
    vehicle.set(vehicle__mode="AUTO.LOITER", vehicle__armed=True)
    done = MissionTransferStatus(1, TransferOperation.UPLOAD, TransferState.DONE, 3, 3, "", 0, 0, False, clock.now())
    blackboard.writer("t", ["/link/mission_transfer"]).set("/link/mission_transfer", done)
    node = SetMode("AUTO")
    return node, harness(node)


def _refuse(h, vehicle) -> None:
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_ACCEPTED))  # the MAVLink receiver: received
    vehicle.set(vehicle__statustext=(2, MISSION_REFUSED))
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_TEMPORARILY_REJECTED))  # the commander: still checking it


def test_a_refused_route_start_is_asked_again_every_second_and_the_third_ask_takes(px4, harness, vehicle, link, clock):
    node, h = _route_start(px4, harness, vehicle, clock)
    asks: list[float] = []
    said: list[str] = []
    for _ in range(60):  # 6 s at 10 Hz
        assert h.tick() == R
        said.append(node.feedback_message)
        if sent_modes(link) == [(4, 4)]:  # AUTO.MISSION: main 4, sub 4
            asks.append(clock.now())
            if len(asks) < 3:
                _refuse(h, vehicle)
            else:
                h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_ACCEPTED))
                h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_ACCEPTED))
                vehicle.set(vehicle__mode="AUTO.MISSION")
                break
    assert len(asks) == 3
    assert said.count(f"refused: TEMPORARILY_REJECTED ({MISSION_REFUSED}); asked again") == 2 * 11  # each refusal said until the next ask: 11 ticks
    assert all(1.0 <= b - a <= 1.1 + 1e-9 for a, b in itertools.pairwise(asks))  # a second after each refusal (the tick it falls due)
    assert h.tick() == S


def test_a_route_start_refused_for_10_s_fails_with_the_refusal(px4, harness, vehicle, link, clock):
    node, h = _route_start(px4, harness, vehicle, clock)
    asks: list[float] = []
    statuses = []
    for _ in range(150):  # 15 s at 10 Hz
        statuses.append(h.tick())
        if statuses[-1] != R:
            break
        if sent_modes(link):
            asks.append(clock.now())
            _refuse(h, vehicle)
    assert statuses[-1] == F and R in statuses and len(statuses) > 100  # held on to while PX4 checks, then let go
    assert asks[-1] - asks[0] <= 10.0 and len(asks) == 10  # asked every second, for 10 s from the first ask
    assert node.feedback_message == f"refused: TEMPORARILY_REJECTED ({MISSION_REFUSED})"


def test_on_ardupilot_a_refused_auto_is_not_asked_again(autopilot, harness, vehicle, link):
    vehicle.set(vehicle__mode="HOLD")
    h = harness(SetMode("AUTO"))
    assert h.tick() == R
    assert len(link.take("COMMAND_LONG")) == 1
    h.commander.on_ack(AUTOPILOT.command_ack(_M.MAV_CMD_DO_SET_MODE, _M.MAV_RESULT_TEMPORARILY_REJECTED, 0, 0, 1, 191))
    assert h.tick() == F
    assert h.commander.idle  # nothing left to ask again: the refusal was the answer


def driving_in_auto(legs: int, px4, vehicle, clock, link, commander) -> tuple[Harness, MissionState]:
    """A PX4 rover's route of ``legs`` waypoints started, uploaded, in AUTO.MISSION and armed, driven by DriveRouteInAuto."""
    waypoints = [{"lat": 47.3978 + 0.0001 * n, "lon": 8.5456 + 0.0001 * n} for n in range(legs)]
    mission = Mission.model_validate({"version": 1, "name": "r", "vehicle": "rover", "waypoints": waypoints})
    state = MissionState()
    state.upload(mission)
    state.start()
    h = Harness(DriveRouteInAuto(60.0), clock, link, commander, state, px4)
    vehicle.set(vehicle__mode="AUTO.MISSION", vehicle__armed=True, vehicle__mission_items=route_items(mission.waypoints))
    return h, state


def test_a_finished_px4_mission_ends_the_drive(px4, vehicle, clock, link, commander):
    h, state = driving_in_auto(2, px4, vehicle, clock, link, commander)
    assert h.tick() == R
    vehicle.set(vehicle__mission_current=MissionCurrent(1, 2, 2, True, clock.now()))
    assert h.tick() == R
    vehicle.set(vehicle__mission_current=MissionCurrent(2, 2, 5, True, clock.now()))  # MISSION_STATE_COMPLETE: PX4 loiters
    assert h.tick() == S
    assert state.legs.leg_index == 2


# -- VTOL: DO_VTOL_TRANSITION in flight, vtol_state 3 -> 1 -> 4 ------------------------------------------------------


def test_a_transition_is_a_command_in_any_mode_and_counts_once_extended_sys_state_says_fw(px4, harness, vehicle, link):
    vehicle.set(vehicle__mode="AUTO.LOITER", vehicle__vtol_state="MC", vehicle__position=pos(30.0))
    node = VtolTransition("FW")
    h = harness(node)
    assert h.tick() == R
    (cmd,) = [m for m in link.take("COMMAND_LONG") if m.command == _M.MAV_CMD_DO_VTOL_TRANSITION]
    assert cmd.param1 == _M.MAV_VTOL_STATE_FW
    h.commander.on_ack(px4_ack(_M.MAV_CMD_DO_VTOL_TRANSITION, _M.MAV_RESULT_ACCEPTED))
    vehicle.set(vehicle__vtol_state="TRANSITION_TO_FW")
    assert h.tick() == R
    vehicle.set(vehicle__vtol_state="FW")
    assert h.tick() == S


# -- messages outside the dialect, chunked STATUSTEXT, our heartbeat -----------------------------------------------


def _raw(msg_id: int, seq: int, payload: bytes = b"\x05\x00\x00") -> object:
    """A MAVLink 2 frame of a message our dialect lacks (its CRC is not checked for an unknown id), parsed by pymavlink."""
    header = bytes([0xFD, len(payload), 0, 0, seq, 1, 1, msg_id & 0xFF, (msg_id >> 8) & 0xFF, msg_id >> 16])
    return mavlink.MAVLink(None).parse_buffer(header + payload + b"\x00\x00")[0]


def test_messages_outside_the_dialect_neither_break_the_reader_nor_count_as_lost(reader, link):
    peer = Peer(1, 1)
    before = reader.health.lost
    seq = AUTOPILOT.heartbeat(_M.MAV_TYPE_VTOL_QUADROTOR, _M.MAV_AUTOPILOT_PX4, 0, LOITER, 3).get_seq()
    frames = [_raw(411, seq + 1), _raw(380, seq + 2), _raw(410, seq + 3), _raw(8, seq + 4)]
    assert [f.get_type() for f in frames] == ["UNKNOWN_411", "UNKNOWN_380", "UNKNOWN_410", "UNKNOWN_8"]
    reader._autopilot = (1, 1)
    reader.health._last_seq = seq
    link.incoming.extend(frames)
    link.incoming.append(peer.open_drone_id_system(0, 0, bytes(20), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0))
    reader.drain()
    assert reader.health.lost == before
    assert blackboard.reader("t", ["/link/bad_data"]).get("/link/bad_data") in (0, None)


def test_a_long_statustext_comes_in_chunks_and_is_said_once_whole(reader, link):
    text = "Preflight Fail: ekf2 missing data, check sensors (accel, gyro, mag, baro) and wait for them"
    chunks = [text[i : i + 50] for i in range(0, len(text), 50)]
    link.incoming.extend(AUTOPILOT.statustext(3, chunk.encode(), 7, n) for n, chunk in enumerate(chunks))
    seen = blackboard.reader("t", ["/vehicle/statustext"])
    link.incoming.append(AUTOPILOT.statustext(3, chunks[0].encode(), 7, 0))
    reader.dispatch(link.incoming.popleft(), 0.0)
    assert seen.get("/vehicle/statustext") in (None, (0, ""))  # the first chunk alone says nothing yet
    reader.drain()
    assert seen.get("/vehicle/statustext")[1].startswith(text[:50])


def test_a_lost_chunk_shows_as_an_ellipsis(reader, link):
    first, last = "a" * 50, "the end"
    link.incoming.extend([AUTOPILOT.statustext(4, first.encode(), 9, 0), AUTOPILOT.statustext(4, last.encode(), 9, 2)])
    reader.drain()
    assert blackboard.reader("t", ["/vehicle/statustext"]).get("/vehicle/statustext") == (4, first + "..." + last)


def test_to_px4_we_are_a_ground_station_at_1_hz(link, clock):
    heartbeat = Heartbeat(link, clock)
    heartbeat.mav_type = _M.MAV_TYPE_GCS  # what the assembly sets once the heartbeat says PX4
    for _ in range(30):  # 3 s at 10 Hz
        heartbeat.service()
        clock.advance(0.1)
    sent = link.take("HEARTBEAT")
    assert len(sent) == 3 and {m.type for m in sent} == {_M.MAV_TYPE_GCS}


# -- what PX4 cannot fly is refused before anything is sent -------------------------------------------------------


def test_a_sub_or_an_rc_route_on_px4_is_refused_with_the_reason() -> None:
    sub = Mission.model_validate({"version": 1, "name": "s", "vehicle": "sub", "waypoints": [{"lat": 1.0, "lon": 1.0}]})
    assert autopilot_errors(sub, "px4") == ["px4 drives rover, vtol here, not a sub"]
    assert autopilot_errors(sub, "ardupilot") == []


def test_on_px4_the_route_s_item_k_is_its_leg_k(px4, vehicle, clock, link, commander):
    """No home slot: MISSION_CURRENT seq 1 means leg 1 done; MISSION_ITEM_REACHED seq 1, two legs done."""
    h, state = driving_in_auto(3, px4, vehicle, clock, link, commander)
    assert h.tick() == R
    vehicle.set(vehicle__mission_current=MissionCurrent(1, 3, 2, True, clock.now() + 0.05))  # heard after the drive began
    assert (h.tick(), state.legs.leg_index) == (R, 1)
    vehicle.set(vehicle__mission_reached=MissionItemReached(1, clock.now(), 1))
    assert (h.tick(), state.legs.leg_index) == (R, 2)
