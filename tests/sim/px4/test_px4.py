"""The simulated PX4 (standard VTOL): every quirk the real firmware showed over MAVLink (issue 12), on a manual clock."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.io.mavlink.modes import PX4_MODES
from executive.sim import SimServer, make_autopilot
from executive.sim.faults import EkfDegradation, FaultInjector, GpsGlitch
from executive.sim.px4.base import Px4Sim
from executive.sim.px4.parameters import (
    COM_DISARM_PRFLT,
    COM_FAIL_ACT_T,
    COM_OF_LOSS_T,
    COM_SPOOLUP_TIME,
    HOME_AMSL_M,
    MIS_TAKEOFF_ALT,
    MISSION_CHECK_S,
    TRANSITION_AIRSPEED_M_S,
)
from executive.sim.px4.streams import ESTIMATOR_AT_REST, ESTIMATOR_OK
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m
from sim_support import HOME, Gcs

if TYPE_CHECKING:
    from sim_support import Client

MC, FW, TO_FW, TO_MC = m.MAV_VTOL_STATE_MC, m.MAV_VTOL_STATE_FW, m.MAV_VTOL_STATE_TRANSITION_TO_FW, m.MAV_VTOL_STATE_TRANSITION_TO_MC
CUSTOM = m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
LOITER, OFFBOARD, TAKEOFF, MISSION, POSCTL, LAND = (
    PX4_MODES["AUTO.LOITER"], PX4_MODES["OFFBOARD"], PX4_MODES["AUTO.TAKEOFF"], PX4_MODES["AUTO.MISSION"], PX4_MODES["POSCTL"],
    PX4_MODES["AUTO.LAND"],
)  # fmt: skip
POSITION_ONLY = 0x0DF8  # type_mask: position, no velocity, acceleration or yaw


class Px4Gcs(Gcs):
    """A ground station for PX4: the commander answers on its next loop, so an ack comes from the next update."""

    ap: Px4Sim

    def command(self, command: int, *params: float, target: tuple[int, int] = (1, 1)) -> list[MAVLinkMessage]:
        """Send a COMMAND_LONG; returns the receiver's direct replies plus what the commander's next loop sends."""
        direct = super().command(command, *params, target=target)
        self.clock.advance(0.01)
        return direct + self.update()

    def acks(self, command: int, *params: float) -> list[int]:
        return [msg.result for msg in self.command(command, *params) if msg.get_type() == "COMMAND_ACK" and msg.command == command]

    def result(self, command: int, *params: float) -> int:
        results = self.acks(command, *params)
        assert len(results) == 1, results
        return results[0]

    def px4_mode(self, number: int) -> list[int]:
        """DO_SET_MODE with PX4's main mode (param2) and sub mode (param3); both acks."""
        return self.acks(m.MAV_CMD_DO_SET_MODE, CUSTOM, (number >> 16) & 0xFF, (number >> 24) & 0xFF)

    def heartbeat(self) -> MAVLinkMessage:
        self.run(1.0)
        return self.last("HEARTBEAT")

    def setpoint(self, lat: float, lon: float, rel_alt: float) -> None:
        x, y, frame = round(lat * 1e7), round(lon * 1e7), m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        self.send(self.mav.set_position_target_global_int_encode(0, 1, 1, frame, POSITION_ONLY, x, y, rel_alt, *[0.0] * 8))

    def stream(self, seconds: float, goal: tuple[float, float, float], rate_hz: float = 5.0) -> None:
        """Stream a position setpoint at ``rate_hz`` while ``seconds`` pass."""
        for _ in range(round(seconds * rate_hz)):
            self.setpoint(*goal)
            self.run(1.0 / rate_hz, step=1.0 / rate_hz / 2)


MakePx4 = Callable[..., Px4Gcs]


@pytest.fixture
def px4() -> MakePx4:
    """A simulated PX4 vehicle (VTOL by default), ``run_s`` seconds after boot, and a ground station talking to it."""

    def make(run_s: float = 5.0, kind: str = "vtol") -> Px4Gcs:
        clock = ManualClock()
        gcs = Px4Gcs(make_autopilot(kind, clock, HOME, autopilot="px4"), clock)
        gcs.update()
        gcs.run(run_s)
        return gcs

    return make


def airborne(px4: MakePx4, metres: float = 20.0) -> Px4Gcs:
    gcs = px4()
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_AMSL_M + metres) == m.MAV_RESULT_ACCEPTED
    gcs.run(metres / 2.0 + 6.0)
    assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.vehicle.alt_m == pytest.approx(metres, abs=0.6)
    return gcs


# -- identity and modes ------------------------------------------------------------------------


def test_heartbeat_is_px4_standard_vtol_in_auto_loiter_on_the_ground(px4: MakePx4) -> None:
    hb = px4().heartbeat()
    assert (hb.autopilot, hb.type) == (m.MAV_AUTOPILOT_PX4, 22)
    assert hb.custom_mode == 0x03040000 == LOITER  # main mode 4 in bits 16-23, sub mode 3 in bits 24-31
    assert hb.base_mode & CUSTOM and not hb.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED


def test_do_set_mode_is_acked_twice_and_confirmed_by_the_heartbeat(px4: MakePx4) -> None:
    gcs = airborne(px4)
    direct = gcs.send(gcs.mav.command_long_encode(1, 1, m.MAV_CMD_DO_SET_MODE, 0, CUSTOM, 4, 6, 0, 0, 0, 0))
    assert [(msg.command, msg.result) for msg in direct] == [(m.MAV_CMD_DO_SET_MODE, m.MAV_RESULT_ACCEPTED)]  # the receiver, at once
    assert gcs.ap.mode == "AUTO.LOITER"  # nothing changed yet
    gcs.clock.advance(0.01)
    later = gcs.update()
    assert [msg.result for msg in later if msg.get_type() == "COMMAND_ACK"] == [m.MAV_RESULT_ACCEPTED]  # the commander's
    assert gcs.heartbeat().custom_mode == LAND


def test_offboard_without_a_setpoint_stream_is_accepted_then_temporarily_rejected(px4: MakePx4) -> None:
    gcs = airborne(px4)
    replies = gcs.command(m.MAV_CMD_DO_SET_MODE, CUSTOM, 6, 0)
    acks = [msg.result for msg in replies if msg.get_type() == "COMMAND_ACK"]
    assert acks == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_TEMPORARILY_REJECTED]
    assert "Switching to Offboard is currently not available" in gcs.texts(replies)
    assert gcs.heartbeat().custom_mode == LOITER


def test_set_mode_message_is_answered_by_the_commander_as_do_set_mode(px4: MakePx4) -> None:
    gcs = airborne(px4)
    assert gcs.send(gcs.mav.set_mode_encode(1, CUSTOM, LAND)) == []
    gcs.clock.advance(0.01)
    assert [(msg.command, msg.result) for msg in gcs.update() if msg.get_type() == "COMMAND_ACK"] == [(m.MAV_CMD_DO_SET_MODE, 0)]


def test_pilot_modes_are_unavailable_without_rc(px4: MakePx4) -> None:
    gcs = airborne(px4)
    assert gcs.px4_mode(POSCTL) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_TEMPORARILY_REJECTED]


# -- arming and health ---------------------------------------------------------------------------


def test_arming_is_refused_until_the_estimator_has_a_position(px4: MakePx4) -> None:
    gcs = px4(run_s=1.5)
    replies = gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1, 21196)  # forced: the checks still run for an external command
    assert [msg.result for msg in replies if msg.get_type() == "COMMAND_ACK"] == [m.MAV_RESULT_TEMPORARILY_REJECTED]
    assert gcs.texts(replies) == ["Arming denied: Resolve system health failures first"]
    assert [msg.chunk_seq for msg in gcs.of_type(replies, "STATUSTEXT")] == [0, 1]  # 52 bytes: two chunks sharing an id
    assert gcs.of_type(replies, "STATUSTEXT")[0].id != 0
    assert not gcs.last("SYS_STATUS").onboard_control_sensors_health & m.MAV_SYS_STATUS_PREARM_CHECK
    gcs.run(2.0)
    status = gcs.last("SYS_STATUS")
    assert status.onboard_control_sensors_health & m.MAV_SYS_STATUS_PREARM_CHECK
    assert gcs.last("ESTIMATOR_STATUS").flags == ESTIMATOR_AT_REST  # a GNSS position, and at rest on the ground
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED


def test_the_estimator_flags_constant_position_mode_at_rest_on_the_ground_and_not_in_flight(px4: MakePx4) -> None:
    """ekf_helper.cpp get_ekf_soln_status: CONST_POS_MODE for vehicle_at_rest (LandDetector: landed, still for 1 s), GNSS in use."""
    gcs = px4()
    assert gcs.last("ESTIMATOR_STATUS").flags == 0x3FF  # what the real SITL reported before arming
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(1.5)
    assert gcs.of_type(out, "ESTIMATOR_STATUS")[-1].flags == 0x37F  # armed on the ground: the motors shake the IMU (real SITL)
    assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_AMSL_M + 10.0) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(3.0)
    flying = [msg.flags for msg in gcs.of_type(out, "ESTIMATOR_STATUS")][-1]
    assert flying == ESTIMATOR_OK == 0x37F and not flying & m.ESTIMATOR_CONST_POS_MODE
    gcs.run(10.0)
    assert gcs.px4_mode(LAND) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(20.0)
    assert {"Landing detected", "Disarmed by landing"} <= set(gcs.texts(out))
    assert gcs.of_type(out, "ESTIMATOR_STATUS")[-1].flags == 0x3FF  # landed, disarmed and still again


def test_no_ekf_status_report_but_estimator_status(px4: MakePx4) -> None:
    gcs = px4()
    kinds = {msg.get_type() for msg in gcs.log}
    assert "ESTIMATOR_STATUS" in kinds and "EKF_STATUS_REPORT" not in kinds
    assert gcs.of_type(gcs.log, "ESTIMATOR_STATUS")[0].flags & m.ESTIMATOR_CONST_POS_MODE  # before the position came


def test_armed_and_not_taking_off_disarms_itself_after_the_spool_up_and_com_disarm_prflt(px4: MakePx4) -> None:
    """Commander::handleAutoDisarm: COM_SPOOLUP_TIME + COM_DISARM_PRFLT (1 + 10 s, commander_params.c) without a take-off."""
    gcs = px4()
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    gcs.run(COM_SPOOLUP_TIME + COM_DISARM_PRFLT - 0.3)
    assert gcs.ap.armed
    out = gcs.run(0.5)
    assert "Disarmed by auto preflight disarming" in gcs.texts(out) and not gcs.ap.armed


def test_takeoff_to_latitude_0_longitude_0_is_accepted_and_never_climbs_then_it_disarms(px4: MakePx4) -> None:
    """navigator_main.cpp: finite param5/param6 are the take-off point. 0, 0 is ACCEPTED, AUTO.TAKEOFF, no climb (the real
    SITL's answer to the executive's old NAV_TAKEOFF), and COM_DISARM_PRFLT later "Disarmed by auto preflight disarming"."""
    gcs = px4()
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, HOME_AMSL_M + 30.0) == m.MAV_RESULT_ACCEPTED
    assert gcs.heartbeat().custom_mode == TAKEOFF
    out = gcs.run(COM_SPOOLUP_TIME + COM_DISARM_PRFLT)
    assert max(msg.relative_alt for msg in gcs.of_type(out, "GLOBAL_POSITION_INT")) < 100  # mm: never left the ground
    assert "Disarmed by auto preflight disarming" in gcs.texts(out) and not gcs.ap.armed
    assert gcs.last("EXTENDED_SYS_STATE").landed_state == m.MAV_LANDED_STATE_ON_GROUND


def test_takeoff_with_the_point_nan_or_here_climbs(px4: MakePx4) -> None:
    for lat, lon in ((math.nan, math.nan), HOME[:2]):
        gcs = px4()
        gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, lat, lon, HOME_AMSL_M + 10.0) == m.MAV_RESULT_ACCEPTED
        gcs.run(10.0)
        assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.vehicle.alt_m == pytest.approx(10.0, abs=0.6)


# -- take-off, reposition ------------------------------------------------------------------------


def test_takeoff_altitude_is_above_sea_level_then_it_loiters(px4: MakePx4) -> None:
    gcs = px4()
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_AMSL_M + 15.0) == m.MAV_RESULT_ACCEPTED
    assert gcs.heartbeat().custom_mode == TAKEOFF
    gcs.run(12.0)
    assert gcs.heartbeat().custom_mode == LOITER
    position = gcs.last("GLOBAL_POSITION_INT")
    assert position.relative_alt == pytest.approx(15_000, abs=600)
    assert position.alt == pytest.approx((HOME_AMSL_M + 15.0) * 1000, abs=600)
    assert gcs.last("HOME_POSITION").altitude == round(HOME_AMSL_M * 1000)


def test_takeoff_without_an_altitude_climbs_to_the_default_height(px4: MakePx4) -> None:
    gcs = px4()
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
    gcs.run(8.0)
    assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.vehicle.alt_m == pytest.approx(MIS_TAKEOFF_ALT, abs=0.6)


@pytest.mark.parametrize(("takeoff_m", "alt_rad_m", "ends_above_m"), [(15.0, None, 14.2), (15.0, 2.0, 13.0), (0.6, None, 0.3)])
def test_the_take_off_ends_as_the_vehicle_climbs_within_nav_mc_alt_rad_of_its_altitude(
    px4: MakePx4, takeoff_m: float, alt_rad_m: float | None, ends_above_m: float
) -> None:
    """navigator/mission_block.cpp: a rotary wing's take-off (a VTOL's) is reached above its altitude less NAV_MC_ALT_RAD
    (0.8 m, or as set), or less half the take-off's altitude when that is under the radius; then it loiters."""
    gcs = px4()
    if alt_rad_m is not None:
        gcs.send(gcs.mav.param_set_encode(1, 1, b"NAV_MC_ALT_RAD", alt_rad_m, m.MAV_PARAM_TYPE_REAL32))
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert gcs.result(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_AMSL_M + takeoff_m) == m.MAV_RESULT_ACCEPTED
    climbed = [gcs.ap.vehicle.alt_m]
    while gcs.ap.mode == "AUTO.TAKEOFF" and len(climbed) < 1500:
        gcs.run(0.02, step=0.02)
        climbed.append(gcs.ap.vehicle.alt_m)
    assert gcs.ap.mode == "AUTO.LOITER"
    assert climbed[-3] <= ends_above_m < climbed[-2]  # judged as the 20 ms loop starts: at the first loop above it


def test_the_take_offs_altitude_acceptance_is_read_at_its_default(px4: MakePx4) -> None:
    """NAV_MC_ALT_RAD, 0.8 m (navigator/navigator_params.c), a float: the executive judges PX4's end of take-off by it."""
    gcs = px4()
    (value,) = gcs.send(gcs.mav.param_request_read_encode(1, 1, b"NAV_MC_ALT_RAD", -1))
    assert (value.get_type(), value.param_id, value.param_type) == ("PARAM_VALUE", "NAV_MC_ALT_RAD", m.MAV_PARAM_TYPE_REAL32)
    assert value.param_value == pytest.approx(0.8)


def test_reposition_as_command_int_flies_there_in_auto_loiter(px4: MakePx4) -> None:
    gcs = airborne(px4)
    lat, lon = gcs.north(60.0)
    frame = m.MAV_FRAME_GLOBAL_INT

    def reposition(flags: int) -> list[int]:
        x, y = round(lat * 1e7), round(lon * 1e7)
        msg = gcs.mav.command_int_encode(1, 1, frame, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, flags, 0, math.nan, x, y, HOME_AMSL_M + 25.0)
        direct = gcs.send(msg)
        gcs.clock.advance(0.01)
        return [ack.result for ack in direct + gcs.update() if ack.get_type() == "COMMAND_ACK"]

    assert reposition(0) == [m.MAV_RESULT_UNSUPPORTED]  # Commander.cpp: the change-mode flag is required
    assert reposition(m.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE) == [m.MAV_RESULT_ACCEPTED]
    gcs.run(25.0)
    assert gcs.heartbeat().custom_mode == LOITER
    assert gcs.ap.vehicle.distance_to(lat, lon) < 1.5 and gcs.ap.vehicle.alt_m == pytest.approx(25.0, abs=0.6)


# -- offboard ------------------------------------------------------------------------------------


def test_offboard_needs_the_stream_first_and_its_loss_is_the_failsafe(px4: MakePx4) -> None:
    gcs = airborne(px4)
    goal = (*gcs.north(30.0), 20.0)
    gcs.stream(1.0, goal)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.stream(15.0, goal)
    assert gcs.last("HEARTBEAT").custom_mode == OFFBOARD and gcs.ap.vehicle.distance_to(*goal[:2]) < 1.5
    out = gcs.run(COM_OF_LOSS_T + 0.2)  # the stream stops
    assert gcs.ap.mode == "POSCTL" and gcs.ap.in_failsafe
    assert any("no offboard signal" in text for text in gcs.texts(out))
    out = gcs.run(COM_FAIL_ACT_T + 0.5)
    assert gcs.last("HEARTBEAT").custom_mode == LAND
    gcs.run(25.0)
    assert not gcs.ap.armed and gcs.ap.vehicle.on_ground


def test_a_gap_shorter_than_the_loss_time_keeps_offboard(px4: MakePx4) -> None:
    gcs = airborne(px4)
    goal = (*gcs.north(10.0), 20.0)
    gcs.stream(1.0, goal)
    gcs.px4_mode(OFFBOARD)
    gcs.run(COM_OF_LOSS_T - 0.2)
    gcs.stream(1.0, goal, rate_hz=2.5)
    assert gcs.ap.mode == "OFFBOARD" and not gcs.ap.in_failsafe


def test_offboard_on_the_ground_takes_off_to_a_setpoint_above(px4: MakePx4) -> None:
    """MulticopterPositionControl.cpp want_takeoff (armed, the setpoint above the vehicle): the real SIH standard_vtol armed on the
    ground took off in OFFBOARD ("Takeoff detected", tests/data/px4/vtol-waypoints-guided.tlog)."""
    gcs = px4()
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    goal = (*gcs.north(30.0), 20.0)
    gcs.stream(1.0, goal)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.stream(20.0, goal)
    assert "Takeoff detected" in gcs.texts(gcs.log) and gcs.ap.armed
    assert gcs.ap.vehicle.distance_to(*goal[:2]) < 1.5 and gcs.ap.vehicle.alt_m == pytest.approx(20.0, abs=0.6)


def test_leaving_offboard_before_stopping_the_stream_is_no_failsafe(px4: MakePx4) -> None:
    gcs = airborne(px4)
    goal = (*gcs.north(10.0), 20.0)
    gcs.stream(1.0, goal)
    gcs.px4_mode(OFFBOARD)
    assert gcs.px4_mode(LOITER) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.run(COM_FAIL_ACT_T + 2.0)
    assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.armed and not gcs.ap.in_failsafe


# -- missions ------------------------------------------------------------------------------------


def upload(gcs: Px4Gcs, items: list[tuple[int, float, float, float]]) -> list[MAVLinkMessage]:
    """Upload (command, lat, lon, rel_alt) items answering each MISSION_REQUEST_INT; returns what the vehicle sent."""
    sent = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), m.MAV_MISSION_TYPE_MISSION))
    replies = list(sent)
    while sent and sent[-1].get_type() == "MISSION_REQUEST_INT":
        seq = sent[-1].seq
        command, lat, lon, alt = items[seq]
        frame = m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        item = gcs.mav.mission_item_int_encode(1, 1, seq, frame, command, 0, 1, 0, 0, 0, math.nan, round(lat * 1e7), round(lon * 1e7), alt, 0)
        sent = gcs.send(item)
        replies += sent
    return replies


def test_mission_upload_requests_int_items_from_zero_and_auto_mission_waits_for_the_check(px4: MakePx4) -> None:
    gcs = airborne(px4)
    gcs.ap.params["MIS_TKO_LAND_REQ"] = 0.0  # no landing asked of a mission (the VTOL default 2 refuses this one: test below)
    items = [(m.MAV_CMD_NAV_WAYPOINT, *gcs.north(40.0), 20.0), (m.MAV_CMD_NAV_WAYPOINT, *gcs.east(40.0), 20.0)]
    replies = upload(gcs, items)
    assert [msg.seq for msg in gcs.of_type(replies, "MISSION_REQUEST_INT")] == [0, 1]
    assert not gcs.of_type(replies, "MISSION_REQUEST")
    assert gcs.of_type(replies, "MISSION_ACK")[-1].type == m.MAV_MISSION_ACCEPTED
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_TEMPORARILY_REJECTED]  # still checking it
    gcs.run(MISSION_CHECK_S)
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(60.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [0, 1]
    current = gcs.last("MISSION_CURRENT")
    assert (current.mission_state, current.total) == (m.MISSION_STATE_COMPLETE, 2)
    assert gcs.last("HEARTBEAT").custom_mode == LOITER and gcs.ap.armed


@pytest.mark.parametrize(("required", "flies"), [(2, False), (4, True), (0, True)])
def test_a_mission_without_the_landing_mis_tko_land_req_asks_for_is_refused(px4: MakePx4, required: int, flies: bool) -> None:
    """The real SIH standard_vtol (MIS_TKO_LAND_REQ 2) refused AUTO.MISSION for two waypoints; 0 flew them."""
    gcs = airborne(px4)
    assert gcs.ap.params["MIS_TKO_LAND_REQ"] == 2.0  # the VTOL default
    gcs.ap.params["MIS_TKO_LAND_REQ"] = float(required)
    upload(gcs, [(m.MAV_CMD_NAV_WAYPOINT, *gcs.north(40.0), 20.0), (m.MAV_CMD_NAV_WAYPOINT, *gcs.east(40.0), 20.0)])
    gcs.run(MISSION_CHECK_S)
    expected = m.MAV_RESULT_ACCEPTED if flies else m.MAV_RESULT_TEMPORARILY_REJECTED
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, expected]


def test_a_window_uploaded_again_in_auto_mission_keeps_the_item_flown_to(px4: MakePx4) -> None:
    """mission_base.cpp updateMavlinkMission: no item flagged current, the navigator keeps its item (real SIH: item 1 kept
    through a 4-item upload, item 3 through a 5-item one, tests/data/px4/auto-mission-window.tlog); the end loiters."""
    gcs = px4()
    gcs.ap.params["MIS_TKO_LAND_REQ"] = 0.0
    points = [gcs.north(40.0), gcs.east(40.0), gcs.north(80.0)]
    upload(gcs, [(m.MAV_CMD_NAV_WAYPOINT, *points[0], 20.0), (m.MAV_CMD_NAV_WAYPOINT, *points[1], 20.0)])
    gcs.run(MISSION_CHECK_S)
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.run(5.0)
    assert gcs.ap.mission.current_seq == 0 and not gcs.ap.landed  # climbing first (Mission::handleTakeoff)
    while gcs.ap.mission.current_seq == 0:
        gcs.run(1.0)
    upload(gcs, [(m.MAV_CMD_NAV_WAYPOINT, *p, 20.0) for p in points])
    assert gcs.ap.mission.current_seq == 1 and gcs.ap.mode == "AUTO.MISSION"
    out = gcs.run(60.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [1, 2]
    assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.vehicle.distance_to(*points[2]) < 12.0


# -- VTOL ----------------------------------------------------------------------------------------


def test_transition_to_fixed_wing_and_back(px4: MakePx4) -> None:
    gcs = airborne(px4, 30.0)
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, FW) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(20.0)
    states = [msg.vtol_state for msg in gcs.of_type(out, "EXTENDED_SYS_STATE")]
    assert states[0] == TO_FW and states[-1] == FW and set(states) == {TO_FW, FW}
    assert gcs.ap.vehicle.speed_m_s >= TRANSITION_AIRSPEED_M_S
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, MC) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(10.0)
    states = [msg.vtol_state for msg in gcs.of_type(out, "EXTENDED_SYS_STATE")]
    assert states[0] == TO_MC and states[-1] == MC


def test_transition_is_refused_on_the_ground(px4: MakePx4) -> None:
    gcs = px4()
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, FW) == m.MAV_RESULT_TEMPORARILY_REJECTED
    assert gcs.ap.vtol_state == MC


# -- over a socket -------------------------------------------------------------------------------


def test_server_sends_messages_outside_the_dialect(client_for: Callable[[str], Client]) -> None:
    with SimServer("vtol", autopilot="px4", clock=ManualClock(), home=HOME) as server:
        client = client_for(server.url_for_client)
        client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        clock = server.clock
        assert isinstance(clock, ManualClock)
        for _ in range(30):
            clock.advance(0.1)
            server.step()
        hb = client.wait("HEARTBEAT")
        assert hb.autopilot == m.MAV_AUTOPILOT_PX4
        client.wait("UNKNOWN_411")  # CURRENT_EVENT_SEQUENCE, a raw MAVLink 2 frame pymavlink's dialect cannot decode
        client.wait("UNKNOWN_380")
        client.wait("OPEN_DRONE_ID_LOCATION")


def test_reposition_altitude_is_above_sea_level_whatever_the_frame(px4: MakePx4) -> None:
    gcs = airborne(px4)
    x, y = (round(v * 1e7) for v in gcs.north(20.0))
    frame = m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT  # navigator_main.cpp takes param7 as AMSL all the same
    gcs.send(gcs.mav.command_int_encode(1, 1, frame, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, 1, 0, math.nan, x, y, HOME_AMSL_M + 25.0))
    gcs.run(20.0)
    assert gcs.ap.vehicle.alt_m == pytest.approx(25.0, abs=0.6)


def test_a_transit_flight_takeoff_transition_fly_back_transition_land(px4: MakePx4) -> None:
    gcs = airborne(px4, 30.0)
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, FW) == m.MAV_RESULT_ACCEPTED
    far = gcs.north(800.0)
    x, y = round(far[0] * 1e7), round(far[1] * 1e7)
    direct = gcs.send(
        gcs.mav.command_int_encode(1, 1, m.MAV_FRAME_GLOBAL_INT, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, 1, 0, math.nan, x, y, HOME_AMSL_M + 30.0)
    )
    assert direct == []  # the commander answers on its next loop
    gcs.run(90.0)
    assert gcs.ap.vtol_state == FW and gcs.ap.vehicle.distance_to(*far) == pytest.approx(80.0, abs=10.0)  # circling it
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, MC) == m.MAV_RESULT_ACCEPTED
    gcs.run(10.0)
    assert gcs.ap.vtol_state == MC
    assert gcs.px4_mode(LAND) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(60.0)
    assert {"Landing detected", "Disarmed by landing"} <= set(gcs.texts(out))
    assert not gcs.ap.armed and gcs.last("EXTENDED_SYS_STATE").landed_state == m.MAV_LANDED_STATE_ON_GROUND


def test_after_an_rtl_landing_it_disarms_and_goes_back_to_auto_loiter(px4: MakePx4) -> None:
    """Commander::handleAutoDisarm ("Disarmed by landing" after COM_DISARM_LAND), then UserModeIntention::onDisarm: the last
    mode a user asked for that does not prevent arming (AUTO.RTL does), here the AUTO.LOITER the take-off ended in."""
    gcs = airborne(px4)
    assert gcs.result(m.MAV_CMD_NAV_RETURN_TO_LAUNCH) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(90.0)
    texts = gcs.texts(out)
    assert texts.index("Landing detected") < texts.index("Disarmed by landing")
    beats = [(hb.custom_mode, bool(hb.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED)) for hb in gcs.of_type(out, "HEARTBEAT")]
    rtl = PX4_MODES["AUTO.RTL"]
    assert (rtl, True) in beats and beats[-1] == (LOITER, False)
    assert beats[beats.index((LOITER, False)) - 1] == (rtl, True)  # disarmed and back in AUTO.LOITER in one heartbeat
    assert gcs.last("EXTENDED_SYS_STATE").landed_state == m.MAV_LANDED_STATE_ON_GROUND


def test_after_disarming_it_goes_back_to_the_last_mode_a_user_asked_for_that_allows_arming(px4: MakePx4) -> None:
    """UserModeIntention::change keeps OFFBOARD (it does not prevent arming) and not AUTO.LAND (it does)."""
    gcs = airborne(px4, 5.0)
    goal = (*gcs.north(5.0), 5.0)
    gcs.stream(1.0, goal)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.stream(1.0, goal)
    assert gcs.px4_mode(LAND) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.run(30.0)
    assert not gcs.ap.armed and gcs.last("HEARTBEAT").custom_mode == OFFBOARD


def test_change_speed_sets_the_cruise_speed(px4: MakePx4) -> None:
    gcs = airborne(px4)
    assert gcs.result(m.MAV_CMD_DO_CHANGE_SPEED, 1, 3.0, -1) == m.MAV_RESULT_ACCEPTED
    x, y = (round(v * 1e7) for v in gcs.north(200.0))
    gcs.send(gcs.mav.command_int_encode(1, 1, m.MAV_FRAME_GLOBAL_INT, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, 1, 0, math.nan, x, y, HOME_AMSL_M + 20.0))
    gcs.run(20.0)
    assert gcs.ap.vehicle.speed_m_s == pytest.approx(3.0, abs=0.1)


# -- the rover -----------------------------------------------------------------------------------


def reposition_to(gcs: Px4Gcs, lat: float, lon: float) -> list[int]:
    x, y = round(lat * 1e7), round(lon * 1e7)
    direct = gcs.send(gcs.mav.command_int_encode(1, 1, m.MAV_FRAME_GLOBAL_INT, m.MAV_CMD_DO_REPOSITION, 0, 0, -1, 1, 0, math.nan, x, y, math.nan))
    gcs.clock.advance(0.01)
    return [ack.result for ack in direct + gcs.update() if ack.get_type() == "COMMAND_ACK"]


def test_rover_is_a_px4_ground_rover_that_cannot_take_off_or_transition(px4: MakePx4) -> None:
    gcs = px4(kind="rover")
    hb = gcs.heartbeat()
    assert (hb.autopilot, hb.type, hb.custom_mode) == (m.MAV_AUTOPILOT_PX4, m.MAV_TYPE_GROUND_ROVER, LOITER)
    assert gcs.last("EXTENDED_SYS_STATE").vtol_state == m.MAV_VTOL_STATE_UNDEFINED
    replies = gcs.command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_AMSL_M + 5.0)
    assert [msg.result for msg in gcs.of_type(replies, "COMMAND_ACK")] == [m.MAV_RESULT_TEMPORARILY_REJECTED]
    assert "Switching to Takeoff is currently not available" in gcs.texts(replies)
    assert gcs.result(m.MAV_CMD_DO_VTOL_TRANSITION, FW) == m.MAV_RESULT_UNSUPPORTED


def test_rover_armed_is_not_landed_so_it_never_disarms_itself_on_the_ground(px4: MakePx4) -> None:
    gcs = px4(kind="rover")
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    gcs.run(COM_DISARM_PRFLT + 5.0)
    assert gcs.ap.armed and "Takeoff detected" in gcs.texts(gcs.log)  # RoverLandDetector: armed means not landed
    assert gcs.last("EXTENDED_SYS_STATE").landed_state == m.MAV_LANDED_STATE_IN_AIR


def test_rover_reposition_drives_there_and_stops(px4: MakePx4) -> None:
    gcs = px4(kind="rover")
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    target = gcs.north(20.0)
    assert reposition_to(gcs, *target) == [m.MAV_RESULT_ACCEPTED]
    gcs.run(25.0)
    assert gcs.ap.mode == "AUTO.LOITER" and gcs.ap.vehicle.distance_to(*target) < 0.5 and gcs.ap.vehicle.speed_m_s == 0.0


def test_rover_offboard_loss_stops_it_then_land_mode_disarms_it(px4: MakePx4) -> None:
    gcs = px4(kind="rover")
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    goal = (*gcs.east(15.0), 0.0)
    gcs.stream(1.0, goal)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    gcs.stream(15.0, goal)
    assert gcs.ap.vehicle.distance_to(*goal[:2]) < 0.5
    gcs.run(COM_OF_LOSS_T + 0.2)
    assert gcs.ap.mode == "POSCTL"
    out = gcs.run(COM_FAIL_ACT_T + 3.0)
    beats = [(hb.custom_mode, bool(hb.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED)) for hb in gcs.of_type(out, "HEARTBEAT")]
    assert (LAND, True) in beats and not gcs.ap.armed
    assert beats[-1] == (OFFBOARD, False)  # disarmed, no failsafe: the user's mode again (UserModeIntention::onDisarm)
    assert {"Landing detected", "Disarmed by landing"} <= set(gcs.texts(out))


def test_rover_rtl_drives_home_and_arriving_is_a_landing_it_disarms_after(px4: MakePx4) -> None:
    """RoverLandDetector: in AUTO.RTL within NAV_ACC_RAD (0.5 m) of the return point it is landed; COM_DISARM_LAND later
    "Disarmed by landing", then the user's AUTO.LOITER again (UserModeIntention::onDisarm)."""
    gcs = px4(kind="rover")
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert reposition_to(gcs, *gcs.north(15.0)) == [m.MAV_RESULT_ACCEPTED]
    gcs.run(20.0)
    assert gcs.px4_mode(PX4_MODES["AUTO.RTL"]) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(25.0)
    texts = gcs.texts(out)
    assert texts.index("Landing detected") < texts.index("Disarmed by landing")
    assert gcs.ap.vehicle.distance_to(*HOME[:2]) < 0.5 and not gcs.ap.armed and gcs.last("HEARTBEAT").custom_mode == LOITER


def test_rover_mission_drives_every_waypoint_then_holds(px4: MakePx4) -> None:
    gcs = px4(kind="rover")
    gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    items = [(m.MAV_CMD_NAV_WAYPOINT, *gcs.north(10.0), 0.0), (m.MAV_CMD_NAV_WAYPOINT, *gcs.east(10.0), 0.0)]
    upload(gcs, items)
    gcs.run(MISSION_CHECK_S)
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(40.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [0, 1]
    assert gcs.last("MISSION_CURRENT").mission_state == m.MISSION_STATE_COMPLETE
    assert gcs.last("HEARTBEAT").custom_mode == LOITER and gcs.ap.vehicle.distance_to(*gcs.east(10.0)) < 0.5


def test_heartbeat_loss_of_a_mission_computer_and_of_a_ground_station_is_reported(px4: MakePx4) -> None:
    gcs = px4()
    for kind in (m.MAV_TYPE_ONBOARD_CONTROLLER, m.MAV_TYPE_GCS):
        gcs.send(gcs.mav.heartbeat_encode(kind, m.MAV_AUTOPILOT_INVALID, 0, 0, 0))
    out = gcs.run(5.5)
    assert gcs.texts(out) == ["Connection to mission computer lost"]  # COM_OBC_LOSS_T: 5 s
    out = gcs.run(5.0)
    assert gcs.texts(out) == ["Connection to ground station lost"]  # COM_DL_LOSS_T: 10 s
    assert gcs.texts(gcs.send(gcs.mav.heartbeat_encode(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0))) == ["GCS connection regained"]
    assert gcs.ap.mode == "AUTO.LOITER"  # NAV_DLL_ACT disabled: nothing else


def test_injected_estimator_faults_show_in_estimator_status(px4: MakePx4) -> None:
    gcs = px4()
    faults = FaultInjector(
        [
            EkfDegradation(kind="ekf_degradation", at_s=1.0, for_s=3.0, variance=1.5, lose_position=True),
            GpsGlitch(kind="gps_glitch", at_s=1.0, for_s=3.0, offset_m=20.0),
        ],
        gcs.clock,
    )
    faults.attach(gcs.ap)
    seen: list[MAVLinkMessage] = []
    before = 0
    for step in range(20):
        gcs.clock.advance(0.1)
        faults.update(gcs.ap)
        seen += faults.transform(gcs.update())
        before = len(seen) if step == 10 else before  # 1.1 s: the faults are on
    status = gcs.of_type(seen, "ESTIMATOR_STATUS")[-1]
    assert status.flags & m.ESTIMATOR_GPS_GLITCH and not status.flags & m.ESTIMATOR_POS_HORIZ_ABS
    assert min(status.vel_ratio, status.pos_horiz_ratio, status.pos_vert_ratio) >= 1.5
    health = gcs.of_type(seen, "SYS_STATUS")[-1].onboard_control_sensors_health
    assert not health & (m.MAV_SYS_STATUS_AHRS | m.MAV_SYS_STATUS_PREARM_CHECK)
    assert gcs.of_type(seen[:before], "GLOBAL_POSITION_INT") and not gcs.of_type(seen[before:], "GLOBAL_POSITION_INT")  # none without a position


def test_a_setpoint_with_any_non_finite_value_is_dropped_whole(px4: MakePx4) -> None:
    gcs = airborne(px4)
    velocity_only = 0x0DC7  # position, acceleration and yaw ignored
    for _ in range(5):  # position fields NaN though ignored: mavlink_receiver.cpp drops the message
        gcs.send(
            gcs.mav.set_position_target_local_ned_encode(
                0, 1, 1, m.MAV_FRAME_LOCAL_NED, velocity_only, math.nan, math.nan, math.nan, 1, 0, 0, 0, 0, 0, 0, 0
            )
        )
        gcs.run(0.2)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_TEMPORARILY_REJECTED]
    for _ in range(5):  # the same with zeros keeps the offboard signal alive
        gcs.send(gcs.mav.set_position_target_local_ned_encode(0, 1, 1, m.MAV_FRAME_LOCAL_NED, velocity_only, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0))
        gcs.run(0.2)
    assert gcs.px4_mode(OFFBOARD) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]


def test_a_vtol_mission_takes_off_transitions_flies_and_lands(px4: MakePx4) -> None:
    gcs = px4()
    far = gcs.north(600.0)
    items = [
        (m.MAV_CMD_NAV_VTOL_TAKEOFF, 0.0, 0.0, 25.0),  # here
        (m.MAV_CMD_DO_VTOL_TRANSITION, 0.0, 0.0, 0.0),  # param1 set below: FW
        (m.MAV_CMD_NAV_WAYPOINT, *far, 25.0),
        (m.MAV_CMD_DO_VTOL_TRANSITION, 0.0, 0.0, 0.0),  # MC
        (m.MAV_CMD_NAV_LAND, *far, 0.0),
    ]
    params = {1: FW, 3: MC}
    sent = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), m.MAV_MISSION_TYPE_MISSION))
    while sent and sent[-1].get_type() == "MISSION_REQUEST_INT":
        seq = sent[-1].seq
        command, lat, lon, alt = items[seq]
        x, y = round(lat * 1e7), round(lon * 1e7)
        frame = m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        sent = gcs.send(gcs.mav.mission_item_int_encode(1, 1, seq, frame, command, 0, 1, params.get(seq, 0), 0, 0, math.nan, x, y, alt, 0))
    assert sent[-1].get_type() == "MISSION_ACK" and sent[-1].type == m.MAV_MISSION_ACCEPTED
    gcs.run(MISSION_CHECK_S)
    assert gcs.result(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
    assert gcs.px4_mode(MISSION) == [m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_ACCEPTED]
    out = gcs.run(150.0, step=0.2)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [0, 1, 2, 3, 4]
    assert {TO_FW, FW, TO_MC} <= {msg.vtol_state for msg in gcs.of_type(out, "EXTENDED_SYS_STATE")}
    assert not gcs.ap.armed and gcs.ap.vehicle.on_ground and gcs.ap.vehicle.distance_to(*far) < 15.0
    assert gcs.last("MISSION_CURRENT").mission_state == m.MISSION_STATE_COMPLETE
