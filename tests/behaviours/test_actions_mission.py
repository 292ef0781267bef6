"""Mission actions tick by tick: the status on each tick and the exact commands sent.

HoldFor, ChangeSpeed, ChangeDepth / ChangeAltitude (sub), TakeOff / VtolTransition / Land (VTOL, on
ArduPilot and PX4), GoTo by DO_REPOSITION and with a sub's depth, GoToLocal (ENU in, NED out).
"""

from __future__ import annotations

import math

import pytest
from py_trees.common import Status

from executive.behaviours import ChangeAltitude, ChangeDepth, ChangeSpeed, GoTo, GoToLocal, HoldFor, Land, TakeOff, VtolTransition
from executive.io.mavlink.modes import ArduPilotModes
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.testing import START_S
from executive.world.dialect import mavlink
from executive.world.frames import Enu, local_to_global
from executive.world.geo import destination
from executive.world.state import GlobalPosition, HomePosition, Rangefinder
from executive.world.vehicles import PLANE_MODES, SUB_MODES

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
M = mavlink
HOME = (47.397742, 8.545594)
WAYPOINTS = [
    {"lat": 47.3980, "lon": 8.5456, "depth_m": 10.0, "control_mode": "depth", "speed_m_s": 0.5},  # leg 1
    {"lat": 47.3982, "lon": 8.5458, "altitude_m": 5.0, "control_mode": "altitude"},  # leg 2
    {"lat": 47.3990, "lon": 8.5470, "alt_m": 30.0},  # leg 3
    {"lat": 47.3995, "lon": 8.5480},  # leg 4: nothing but a position
]


@pytest.fixture
def mission_state() -> MissionState:
    """Replaces the shared square: four legs with a depth and speed, a height above the seabed, an altitude, nothing."""
    doc = {"version": 1, "name": "mixed", "vehicle": "sub", "waypoints": WAYPOINTS, "limits": {"leg_timeout_s": 300.0}}  # 125 m at 1 m/s
    mission = Mission.model_validate(doc)
    state = MissionState()
    state.upload(mission)
    state.start()
    return state


def on_leg(state: MissionState, leg: int) -> None:
    for _ in range(leg - 1):
        state.advance_leg()


def pos(lat: float = HOME[0], lon: float = HOME[1], alt: float = 0.0, heading: float | None = 0.0) -> GlobalPosition:
    return GlobalPosition(lat, lon, alt, 0.0, 0.0, 0.0, heading, 0.0)


def command(sent) -> tuple:
    """(type, command, params) of a COMMAND_LONG / COMMAND_INT."""
    if sent.get_type() == "COMMAND_INT":
        return ("COMMAND_INT", sent.command, sent.frame, sent.param1, sent.param2, sent.x, sent.y, sent.z)
    return ("COMMAND_LONG", sent.command, sent.param1, sent.param2, sent.param3, sent.param7)


class TestHoldFor:
    def test_sets_the_mode_then_holds_for_the_time_from_the_heartbeat(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED")
        node = HoldFor(2.0, "LOITER")
        h = harness(node)
        assert h.tick(0.5) == R
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 5.0, 0.0, 0.0)
        h.ack(M.MAV_CMD_DO_SET_MODE)
        assert h.tick(0.5) == R  # acked, not yet in the heartbeat: the hold has not begun
        vehicle.set(vehicle__mode="LOITER")
        statuses = [h.tick(0.5) for _ in range(5)]  # holding from the first of these: 0, 0.5 ... 2 s
        assert statuses == [R, R, R, R, S]
        assert node.feedback_message == "held LOITER for 2 s"
        assert h.link.take() == []

    def test_already_in_the_mode_holds_at_once(self, harness, vehicle):
        vehicle.set(vehicle__mode="LOITER")
        node = HoldFor(1.0)
        h = harness(node)
        assert [h.tick(0.5) for _ in range(3)] == [R, R, S]
        assert node.feedback_message == "held LOITER for 1 s" and h.link.take() == []

    def test_feedback_while_holding(self, harness, vehicle):
        vehicle.set(vehicle__mode="LOITER")
        node = HoldFor(10.0)
        h = harness(node)
        h.tick(1.0)
        h.tick(3.0)
        assert node.feedback_message == "holding LOITER: 3/10 s"

    def test_leaving_the_mode_during_the_hold_fails(self, harness, vehicle):
        vehicle.set(vehicle__mode="LOITER")
        node = HoldFor(5.0)
        h = harness(node)
        assert [h.tick(1.0), h.tick(1.0)] == [R, R]
        vehicle.set(vehicle__mode="MANUAL")
        assert h.tick(1.0) == F
        assert node.feedback_message == "left LOITER (now MANUAL) after 2.0 s"

    def test_a_refused_mode_fails(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED")
        node = HoldFor(5.0, "loiter")
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_SET_MODE, M.MAV_RESULT_FAILED)
        assert h.tick() == F
        assert node.feedback_message == "refused: FAILED"


class TestChangeSpeed:
    def test_sends_the_leg_speed_and_succeeds_on_the_ack(self, harness):
        node = ChangeSpeed()
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_CHANGE_SPEED, 1.0, 0.5, -1.0, 0.0)  # ground speed, 0.5 m/s, throttle unchanged
        assert h.tick() == R
        h.ack(M.MAV_CMD_DO_CHANGE_SPEED)
        assert h.tick() == S
        assert node.feedback_message == "0.5 m/s"

    def test_airspeed(self, harness):
        h = harness(ChangeSpeed(airspeed=True))
        h.tick()
        assert h.link.take()[0].param1 == 0.0

    def test_a_leg_without_a_speed_succeeds_without_a_command(self, harness, mission_state):
        on_leg(mission_state, 4)
        node = ChangeSpeed()
        h = harness(node)
        assert h.tick() == S
        assert h.link.take() == [] and node.feedback_message == "no speed for this leg"

    def test_refused(self, harness):
        node = ChangeSpeed()
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_CHANGE_SPEED, M.MAV_RESULT_DENIED)
        assert h.tick() == F
        assert node.feedback_message == "refused: DENIED"

    def test_an_earlier_ack_does_not_confirm_a_new_request(self, harness):
        h = harness(ChangeSpeed())
        h.tick()
        h.ack(M.MAV_CMD_DO_CHANGE_SPEED)
        assert h.tick() == S
        again = harness(ChangeSpeed(name="Again"))
        assert [again.tick(), again.tick()] == [R, R]  # the ACCEPTED on the blackboard is the first request's
        again.ack(M.MAV_CMD_DO_CHANGE_SPEED)
        assert again.tick() == S

    def test_unanswered(self, harness):
        node = ChangeSpeed(confirm_timeout_s=10.0)
        h = harness(node)
        statuses = [h.tick(0.5) for _ in range(13)]  # sends at 0, 1.5, 3, 4.5; timed out at 6 s (the flush after tick 13)
        assert statuses == [R] * 13
        assert h.tick(0.5) == F
        assert node.feedback_message == "no ack after 4 attempts"


@pytest.fixture
def sub(commander):
    commander.modes = ArduPilotModes(SUB_MODES)


class TestChangeDepth:
    def test_holds_where_it_is_and_goes_to_the_leg_depth(self, harness, vehicle, sub):
        vehicle.set(vehicle__position=pos(alt=-2.0))
        node = ChangeDepth()
        h = harness(node)
        assert h.tick(0.5) == R
        (sent,) = h.link.take()
        assert sent.get_type() == "SET_POSITION_TARGET_GLOBAL_INT"
        assert (sent.coordinate_frame, sent.type_mask, sent.alt) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, -10.0)
        assert (sent.lat_int, sent.lon_int) == (round(HOME[0] * 1e7), round(HOME[1] * 1e7))  # here, not the waypoint
        assert node.feedback_message == "depth 2.0 m -> 10 m"
        moved = destination(*HOME, 0.0, 3.0)
        vehicle.set(vehicle__position=pos(*moved, alt=-6.0))
        statuses, sends = [], []
        for _ in range(4):  # 0.5 ... 2 s: re-sent every second, at the same point
            statuses.append(h.tick(0.5))
            sends += h.link.take()
        assert statuses == [R] * 4
        assert [(m.lat_int, m.lon_int, m.alt) for m in sends] == [(round(HOME[0] * 1e7), round(HOME[1] * 1e7), -10.0)] * 2
        vehicle.set(vehicle__position=pos(alt=-9.6))
        assert h.tick(0.5) == S
        assert node.feedback_message == "depth 9.6 m (target 10 m)"

    def test_already_at_depth_still_sends_the_target_to_hold_it(self, harness, vehicle, sub):
        vehicle.set(vehicle__position=pos(alt=-10.2))
        h = harness(ChangeDepth())
        assert h.tick() == S
        assert [m.alt for m in h.link.take()] == [-10.0]

    def test_not_reached_in_time(self, harness, vehicle, sub):
        vehicle.set(vehicle__position=pos(alt=-3.0))
        node = ChangeDepth(timeout_s=5.0)
        h = harness(node)
        assert [h.tick(1.0) for _ in range(7)] == [R] * 6 + [F]
        assert node.feedback_message == "depth 3.0 m, target 10 m, not reached after 5 s"

    def test_no_position_waits_without_sending(self, harness, vehicle, sub):
        h = harness(ChangeDepth())
        assert h.tick() == R and h.link.take() == []
        vehicle.set(vehicle__position=pos(alt=0.0))
        assert h.tick() == R
        assert [m.alt for m in h.link.take()] == [-10.0]

    @pytest.mark.parametrize("leg", [2, 4])
    def test_legs_without_a_depth_succeed_at_once(self, harness, vehicle, mission_state, sub, leg):
        on_leg(mission_state, leg)
        vehicle.set(vehicle__position=pos(alt=-3.0))
        h = harness(ChangeDepth())
        assert h.tick() == S and h.link.take() == []


def sonar(distance_m: float, max_m: float = 30.0) -> dict:
    """What the reader writes for a downward DISTANCE_SENSOR of range 0.5 to ``max_m``, heard as the test starts."""
    status = "good" if 0.5 <= distance_m <= max_m else "too_far" if distance_m > max_m else "too_close"
    return {
        "vehicle__rangefinder": Rangefinder(distance_m, 0.5, max_m, status, START_S),
        "vehicle__altitude_above_bottom_m": distance_m if status == "good" else None,
    }


class TestChangeAltitude:
    def test_keeps_the_leg_height_above_the_seabed_with_depth_targets(self, harness, vehicle, mission_state, sub):
        """ArduSub drops terrain-frame targets: the height goes as the depth that gives it, from the measured depth and sonar."""
        on_leg(mission_state, 2)
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=pos(alt=-4.0), **sonar(12.0))
        node = ChangeAltitude()
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert (sent.coordinate_frame, sent.type_mask, sent.alt) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, -11.0)  # 4 + 12 - 5 m deep
        assert node.feedback_message == "altitude 12.0 m -> 5 m"
        vehicle.set(vehicle__position=pos(alt=-10.4), **sonar(5.6))
        assert h.tick(1.0) == R
        (sent,) = h.link.take()
        assert sent.alt == pytest.approx(-11.0)  # re-sent from the new reading: the seabed has not changed
        vehicle.set(**sonar(5.4))
        assert h.tick() == S

    def test_a_seabed_beyond_the_sonar_is_dived_to_without_overshooting(self, harness, vehicle, mission_state, sub):
        """5 m deep, the sonar reads to 30 m and sees nothing: the seabed is over 35 m down; 24 m above it is deeper than 11 m."""
        on_leg(mission_state, 2)
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=pos(alt=-5.0), **sonar(45.0))
        h = harness(ChangeAltitude())
        assert h.tick() == R
        (sent,) = h.link.take()
        assert sent.alt == pytest.approx(-(5.0 + 30.0 - 5.0 - 1.0))  # depth + max - target altitude - 1 m margin (the leg keeps 5 m)

    def test_no_rangefinder_reading_waits(self, harness, vehicle, mission_state, sub):
        on_leg(mission_state, 2)
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=pos(alt=-4.0))
        node = ChangeAltitude(timeout_s=1.0)
        h = harness(node)
        assert [h.tick(0.5) for _ in range(4)] == [R, R, R, F]
        assert h.link.take() == []  # nothing to compute a depth from
        assert node.feedback_message == "altitude unknown, target 5 m, not reached after 1 s"

    def test_a_depth_leg_succeeds_at_once(self, harness, vehicle, sub):
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=pos(alt=-4.0))
        h = harness(ChangeAltitude())
        assert h.tick() == S and h.link.take() == []


@pytest.fixture
def plane(commander):
    commander.modes = ArduPilotModes(PLANE_MODES)


@pytest.fixture
def px4(autopilot):
    autopilot.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_VTOL_QUADROTOR)


class TestTakeOff:
    def test_climbs_and_succeeds_in_the_air_near_the_altitude(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__armed=True, vehicle__landed_state="ON_GROUND", vehicle__position=pos())
        node = TakeOff(30.0)
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, 0.0, 30.0)
        # yaw and the point NaN: unchanged, here (ArduPlane reads only param7: GCS_MAVLink_Plane.cpp convert_MAV_CMD_NAV_TAKEOFF_to_COMMAND_INT)
        assert all(map(math.isnan, (sent.param4, sent.param5, sent.param6)))
        h.ack(M.MAV_CMD_NAV_TAKEOFF)
        statuses = []
        for landed, alt in [("TAKEOFF", 10.0), ("TAKEOFF", 29.0), ("IN_AIR", 28.4), ("IN_AIR", 28.5)]:
            vehicle.set(vehicle__landed_state=landed, vehicle__position=pos(alt=alt))
            statuses.append(h.tick())
        assert statuses == [R, R, R, S]
        assert h.link.take() == []

    def test_refused_with_the_reason(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__landed_state="ON_GROUND", vehicle__statustext=(6, "Must be armed for takeoff"))
        node = TakeOff(30.0)
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_NAV_TAKEOFF, M.MAV_RESULT_FAILED)
        assert h.tick() == F
        assert node.feedback_message == "refused: FAILED (Must be armed for takeoff)"

    def test_not_up_in_time_says_where_it_got(self, harness, vehicle, plane):
        vehicle.set(vehicle__landed_state="TAKEOFF", vehicle__position=pos(alt=12.0))
        node = TakeOff(30.0, confirm_timeout_s=4.0)
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_NAV_TAKEOFF)
        assert [h.tick(1.0) for _ in range(5)] == [R, R, R, R, F]
        assert node.feedback_message == "not confirmed after 4 s: TAKEOFF at 12.0/30 m"

    def test_already_up_there_sends_nothing(self, harness, vehicle, plane):
        vehicle.set(vehicle__landed_state="IN_AIR", vehicle__position=pos(alt=31.0))
        h = harness(TakeOff(30.0))
        assert h.tick() == S and h.link.take() == []

    def test_px4_takes_an_altitude_above_sea_level(self, harness, vehicle, px4):
        vehicle.set(vehicle__landed_state="ON_GROUND", vehicle__home=HomePosition(*HOME, 488.0, 0.0))
        h = harness(TakeOff(30.0))
        h.tick()
        assert h.link.take()[0].param7 == 518.0

    def test_px4_without_home_uses_its_default_altitude(self, harness, vehicle, px4):
        vehicle.set(vehicle__landed_state="ON_GROUND")
        h = harness(TakeOff(30.0))
        h.tick()
        assert math.isnan(h.link.take()[0].param7)


class TestLand:
    def test_qland_then_on_the_ground_and_disarmed(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="QLOITER", vehicle__armed=True, vehicle__landed_state="IN_AIR", vehicle__position=pos(alt=20.0))
        node = Land()
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 20.0, 0.0, 0.0)
        h.ack(M.MAV_CMD_DO_SET_MODE)
        statuses = []
        for landed, armed in [("LANDING", True), ("ON_GROUND", True), ("ON_GROUND", False)]:
            vehicle.set(vehicle__landed_state=landed, vehicle__armed=armed, vehicle__position=pos(alt=0.0))
            statuses.append(h.tick())
            if landed == "ON_GROUND" and armed:
                assert node.feedback_message == "ON_GROUND at 0.0 m, armed"  # the land detector is not sure yet
        assert statuses == [R, R, S]

    def test_px4_lands_in_auto_land(self, harness, vehicle, px4):
        vehicle.set(vehicle__armed=True, vehicle__landed_state="IN_AIR")
        h = harness(Land())
        h.tick()
        sent = h.link.take()[0]
        assert (sent.command, sent.param2, sent.param3) == (M.MAV_CMD_DO_SET_MODE, 4.0, 6.0)  # AUTO.LAND

    def test_refused(self, harness, vehicle, plane):
        vehicle.set(vehicle__armed=True, vehicle__landed_state="IN_AIR")
        node = Land()
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_SET_MODE, M.MAV_RESULT_FAILED)
        assert h.tick() == F and node.feedback_message == "refused: FAILED"

    def test_landing_too_long(self, harness, vehicle, plane):
        vehicle.set(vehicle__armed=True, vehicle__landed_state="LANDING", vehicle__position=pos(alt=7.5))
        node = Land(confirm_timeout_s=3.0)
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_SET_MODE)
        assert [h.tick(1.0) for _ in range(4)] == [R, R, R, F]
        assert node.feedback_message == "not confirmed after 3 s: LANDING at 7.5 m, armed"

    def test_already_landed_and_disarmed(self, harness, vehicle, plane):
        vehicle.set(vehicle__armed=False, vehicle__landed_state="ON_GROUND")
        h = harness(Land())
        assert h.tick() == S and h.link.take() == []


class TestVtolTransition:
    def test_ardupilot_to_fw_by_a_reposition_ahead(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC", vehicle__position=pos(alt=30.0, heading=90.0))
        node = VtolTransition("FW")
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        lat, lon = destination(*HOME, 90.0, 300.0)
        assert command(sent) == (
            "COMMAND_INT", M.MAV_CMD_DO_REPOSITION, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, -1.0, 1.0, round(lat * 1e7), round(lon * 1e7), 30.0,
        )  # fmt: skip
        h.ack(M.MAV_CMD_DO_REPOSITION)
        assert h.tick() == R  # acked: the transition has not begun
        vehicle.set(vehicle__vtol_state="TRANSITION_TO_FW")
        assert h.tick() == R
        assert node.feedback_message == "TRANSITION_TO_FW -> FW (by reposition 300 m ahead)"
        vehicle.set(vehicle__vtol_state="FW")
        assert h.tick() == S
        assert h.link.take() == []

    def test_ardupilot_to_mc_by_qloiter(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="FW", vehicle__position=pos(alt=30.0))
        node = VtolTransition("MC")
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 19.0, 0.0, 0.0)
        h.ack(M.MAV_CMD_DO_SET_MODE)
        vehicle.set(vehicle__mode="QLOITER")
        assert h.tick() == R  # the mode is not the state: wait for EXTENDED_SYS_STATE
        vehicle.set(vehicle__vtol_state="MC")
        assert h.tick() == S
        assert node.feedback_message == "MC (by QLOITER)"

    @pytest.mark.parametrize(("to", "state"), [("FW", 4.0), ("MC", 3.0)])
    def test_ardupilot_in_auto_uses_the_command(self, harness, vehicle, plane, to, state):
        vehicle.set(vehicle__mode="AUTO", vehicle__vtol_state="MC" if to == "FW" else "FW", vehicle__position=pos(alt=30.0))
        h = harness(VtolTransition(to))
        h.tick()
        (sent,) = h.link.take()
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_VTOL_TRANSITION, state, 0.0, 0.0, 0.0)

    @pytest.mark.parametrize(("to", "state"), [("FW", 4.0), ("MC", 3.0)])
    def test_px4_uses_the_command(self, harness, vehicle, px4, to, state):
        vehicle.set(vehicle__mode="OFFBOARD", vehicle__vtol_state="MC" if to == "FW" else "FW", vehicle__position=pos(alt=30.0))
        node = VtolTransition(to)
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take("COMMAND_LONG")  # in OFFBOARD the setpoint stream goes on beside it
        assert len(h.link.take("SET_POSITION_TARGET_GLOBAL_INT")) == 1
        assert command(sent) == ("COMMAND_LONG", M.MAV_CMD_DO_VTOL_TRANSITION, state, 0.0, 0.0, 0.0)
        h.ack(M.MAV_CMD_DO_VTOL_TRANSITION)
        vehicle.set(vehicle__vtol_state=to)
        assert h.tick() == S

    def test_already_there_sends_nothing(self, harness, vehicle, plane):
        vehicle.set(vehicle__vtol_state="FW")
        h = harness(VtolTransition("FW"))
        assert h.tick() == S and h.link.take() == []

    def test_refused_says_the_last_state(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="QLOITER", vehicle__vtol_state="MC", vehicle__position=pos(alt=0.0))
        node = VtolTransition("FW")
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_DENIED)
        assert h.tick() == F
        assert node.feedback_message == "reposition 300 m ahead refused: DENIED; still MC"

    def test_timeout_says_the_last_state_seen(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC", vehicle__position=pos(alt=30.0))
        node = VtolTransition("FW", timeout_s=3.0)
        h = harness(node)
        h.tick(1.0)
        h.ack(M.MAV_CMD_DO_REPOSITION)
        vehicle.set(vehicle__vtol_state="TRANSITION_TO_FW")
        assert [h.tick(1.0) for _ in range(2)] == [R, R]
        vehicle.set(vehicle__vtol_state=None)  # EXTENDED_SYS_STATE stopped: the last state seen is kept
        assert [h.tick(1.0) for _ in range(2)] == [R, F]
        assert node.feedback_message == "still TRANSITION_TO_FW after 3 s (by reposition 300 m ahead)"

    # The transition's asking (the one Asker, a command's rules judged at timeout_s): one ask, confirmed by EXTENDED_SYS_STATE
    # alone, judged failed at a refusal, at the commander's last resend unanswered, or when timeout_s has passed.

    def test_a_slow_transition_is_confirmed_within_its_time_on_one_ask(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC", vehicle__position=pos(alt=30.0))
        node = VtolTransition("FW", timeout_s=30.0)
        h = harness(node)
        h.tick(1.0)
        h.ack(M.MAV_CMD_DO_REPOSITION)
        vehicle.set(vehicle__vtol_state="TRANSITION_TO_FW")
        assert [h.tick(1.0) for _ in range(29)] == [R] * 29  # 29 s asked, accepted, not there yet: not judged before 30 s
        vehicle.set(vehicle__vtol_state="FW")
        assert h.tick(1.0) == S
        assert len(h.link.take("COMMAND_INT")) == 1

    def test_not_there_is_judged_on_the_first_tick_past_timeout_s(self, harness, vehicle, px4):
        vehicle.set(vehicle__mode="AUTO.LOITER", vehicle__vtol_state="FW", vehicle__position=pos(alt=30.0))
        node = VtolTransition("MC", timeout_s=10.0)
        h = harness(node)
        h.tick(0.5)
        h.ack(M.MAV_CMD_DO_VTOL_TRANSITION)
        vehicle.set(vehicle__vtol_state="TRANSITION_TO_MC")
        assert [h.tick(0.5) for _ in range(21)] == [R] * 20 + [F]  # RUNNING at 10 s exactly, FAILURE at 10.5 s
        assert node.feedback_message == "still TRANSITION_TO_MC after 10 s (by DO_VTOL_TRANSITION)"
        assert len(h.link.take("COMMAND_LONG")) == 1

    def test_a_late_refusal_is_the_refusal(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC", vehicle__position=pos(alt=30.0))
        node = VtolTransition("FW", timeout_s=30.0)
        h = harness(node)
        assert [h.tick(0.5) for _ in range(5)] == [R] * 5  # 2 s without an answer (the commander resends it meanwhile)
        h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_FAILED)
        assert h.tick(0.5) == F
        assert node.feedback_message == "reposition 300 m ahead refused: FAILED; still MC"

    def test_unanswered_fails_once_the_commander_gives_up_before_the_timeout(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC", vehicle__position=pos(alt=30.0))
        node = VtolTransition("FW", timeout_s=30.0)
        h = harness(node)
        statuses = [h.tick(0.5) for _ in range(14)]
        # the commander sends at 0, 1.5, 3 and 4.5 s (its ack time-out) and gives up at 6 s: judged at the next tick
        assert statuses == [R] * 13 + [F]
        assert len(h.link.take("COMMAND_INT")) == 4
        assert node.feedback_message == "reposition 300 m ahead no ack after 4 attempts; still MC"

    def test_no_position_no_fw_transition_on_ardupilot(self, harness, vehicle, plane):
        vehicle.set(vehicle__mode="GUIDED", vehicle__vtol_state="MC")
        node = VtolTransition("FW")
        h = harness(node)
        assert h.tick() == F and h.link.take() == []
        assert node.feedback_message == "no position to transition from"

    def test_only_fw_or_mc(self):
        with pytest.raises(ValueError, match="FW or MC"):
            VtolTransition("HOVER")  # type: ignore[arg-type]


class TestGoToReposition:
    def test_sent_once_and_not_again_while_accepted(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0))
        node = GoTo(80.0, 120.0, method="reposition")
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        wp = WAYPOINTS[2]
        assert command(sent) == (
            "COMMAND_INT", M.MAV_CMD_DO_REPOSITION, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, -1.0, 1.0,
            round(wp["lat"] * 1e7), round(wp["lon"] * 1e7), 30.0,
        )  # fmt: skip
        assert h.tick(0.5) == R
        h.ack(M.MAV_CMD_DO_REPOSITION)
        assert [h.tick(0.5) for _ in range(10)] == [R] * 10
        assert h.link.take() == []  # no re-send every second: the autopilot has its target
        vehicle.set(vehicle__position=pos(*destination(wp["lat"], wp["lon"], 0.0, 70.0), alt=30.0))  # on the loiter circle
        assert h.tick() == S

    def test_refused_is_sent_again_after_resend_s(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0))
        h = harness(GoTo(80.0, 120.0, method="reposition"))
        sends = []
        for i in range(8):  # 0.25 s ticks
            sends.append(len(h.link.take("COMMAND_INT")))
            h.tick(0.25)
            if i == 0:
                h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_DENIED)
        sends.append(len(h.link.take("COMMAND_INT")))
        assert sends == [0, 1, 0, 0, 0, 1, 0, 0, 0]  # first on tick 1; refused; again 1 s later (tick 5)

    def test_unanswered_is_asked_again_after_the_commander_gives_up(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0))
        h = harness(GoTo(80.0, 120.0, method="reposition"))
        confirmations_ticks = []
        for tick in range(1, 61):  # 0.125 s ticks, 7.5 s
            h.tick(0.125)
            if h.link.take("COMMAND_INT"):
                confirmations_ticks.append(tick)
        # the commander sends on ticks 1, 13, 25, 37 (1.5 s ack timeout) and gives up on 49; GoTo asks again on 50
        assert confirmations_ticks == [1, 13, 25, 37, 50]

    def test_refused_again_and_again_is_asked_again_each_resend_s_without_end(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0))
        node = GoTo(80.0, 120.0, method="reposition")
        h = harness(node)
        asked_at = []
        for tick in range(1, 41):  # 0.25 s ticks, 10 s; each ask refused at once
            h.tick(0.25)
            if h.link.take("COMMAND_INT"):
                asked_at.append(tick * 0.25)
                h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_DENIED)
        assert asked_at == [0.25 + n for n in range(10)]  # never given up, replaced or slowed: the leg's timeout ends it
        assert node.status == R

    def test_a_refusal_is_named_until_an_ask_stands_resend_s_then_not(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0), vehicle__statustext=(4, "Mode change to GUIDED failed"))
        node = GoTo(80.0, 2.5, method="reposition")
        h = harness(node)
        h.tick(0.5)
        h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_FAILED)
        assert [h.tick(0.5) for _ in range(2)] == [R, R]  # asked again 1 s after the first ask
        assert len(h.link.take("COMMAND_INT")) == 2
        h.ack(M.MAV_CMD_DO_REPOSITION)  # the second is accepted: the autopilot has the target
        assert [h.tick(0.5) for _ in range(4)] == [R, R, R, F]
        assert h.link.take("COMMAND_INT") == []
        assert node.feedback_message == "leg 3/4: timed out after 2.5 s, 175.6 m short"  # the refusal no longer says why

    def test_a_waypoint_without_altitude_is_flown_at_the_current_height(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 4)
        vehicle.set(vehicle__position=pos(alt=42.0))
        h = harness(GoTo(80.0, 120.0, method="reposition"))
        h.tick()
        assert h.link.take()[0].z == 42.0

    def test_the_timeout_says_why(self, harness, vehicle, mission_state, plane):
        on_leg(mission_state, 3)
        vehicle.set(vehicle__position=pos(alt=30.0), vehicle__statustext=(4, "Mode change to GUIDED failed"))
        node = GoTo(80.0, 2.0, method="reposition")
        h = harness(node)
        for _ in range(3):
            h.tick(1.0)
            h.ack(M.MAV_CMD_DO_REPOSITION, M.MAV_RESULT_FAILED)
        assert h.tick(1.0) == F
        assert node.feedback_message.endswith("(DO_REPOSITION refused: FAILED (Mode change to GUIDED failed))")

    def test_only_known_methods(self):
        with pytest.raises(ValueError, match="setpoint or reposition"):
            GoTo(1.0, 1.0, method="teleport")  # type: ignore[arg-type]


class TestGoToSubSetpoint:
    def test_a_depth_leg_goes_with_its_depth(self, harness, vehicle, sub):
        vehicle.set(vehicle__position=pos(alt=-10.0))
        h = harness(GoTo(1.5, 60.0))
        h.tick()
        (sent,) = h.link.take()
        wp = WAYPOINTS[0]
        assert (sent.lat_int, sent.lon_int, sent.alt) == (round(wp["lat"] * 1e7), round(wp["lon"] * 1e7), -10.0)
        assert (sent.coordinate_frame, sent.type_mask) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8)

    def test_an_altitude_leg_goes_as_the_depth_that_keeps_its_height_as_the_seabed_changes(self, harness, vehicle, mission_state, sub):
        """Not in the terrain frame, which ArduSub drops without terrain data: the depth from the measured depth and sonar, each second."""
        on_leg(mission_state, 2)
        vehicle.set(vehicle__position=pos(alt=-11.0), **sonar(5.0))
        h = harness(GoTo(1.5, 60.0))
        h.tick()
        (sent,) = h.link.take()
        assert (sent.coordinate_frame, sent.type_mask, sent.alt) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, -11.0)
        vehicle.set(**sonar(7.0))  # the seabed falls away 2 m
        h.tick(1.0)
        (sent,) = h.link.take()
        assert sent.alt == pytest.approx(-13.0)
        vehicle.set(vehicle__rangefinder=Rangefinder(7.0, 0.5, 30.0, "invalid", 0.0), vehicle__altitude_above_bottom_m=None)
        h.tick(1.0)
        (sent,) = h.link.take()
        assert sent.alt == pytest.approx(-13.0)  # an invalid ping says nothing: the last depth again

    def test_other_legs_keep_their_altitude(self, harness, mission_state):
        on_leg(mission_state, 3)
        h = harness(GoTo(1.5, 60.0))
        h.tick()
        (sent,) = h.link.take()
        assert (sent.coordinate_frame, sent.type_mask, sent.alt) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, 30.0)


class TestGoToLocal:
    TARGET = Enu(east=10.0, north=20.0, up=5.0)

    def test_enu_in_ned_out_resent_every_second(self, harness, vehicle):
        vehicle.set(vehicle__home=HomePosition(*HOME, 488.0, 0.0), vehicle__position=pos(alt=0.0))
        node = GoToLocal(self.TARGET, acceptance_radius_m=1.0, timeout_s=30.0)
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert sent.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
        assert (sent.coordinate_frame, sent.type_mask) == (M.MAV_FRAME_LOCAL_NED, 0x0DF8)
        assert (sent.x, sent.y, sent.z) == (20.0, 10.0, -5.0)  # north, east, down
        assert node.feedback_message == f"{math.dist((0, 0, 0), (20, 10, -5)):.1f} m"
        sends = 0
        for _ in range(8):  # 2 s, in steps exact in binary
            h.tick(0.25)
            sends += len(h.link.take("SET_POSITION_TARGET_LOCAL_NED"))
        assert sends == 2

    def test_succeeds_near_the_point(self, harness, vehicle):
        vehicle.set(vehicle__home=HomePosition(*HOME, 488.0, 0.0))
        h = harness(GoToLocal(self.TARGET, acceptance_radius_m=1.0, timeout_s=30.0))
        statuses = []
        for north, east, up in [(20.0, 10.0, 3.0), (20.5, 10.5, 4.5)]:  # 2 m low; then 0.87 m off
            vehicle.set(vehicle__position=pos(*local_to_global(*HOME, north, east), alt=up))
            statuses.append(h.tick())
        assert statuses == [R, S]

    def test_no_home_cannot_judge_and_times_out(self, harness, vehicle):
        vehicle.set(vehicle__position=pos(alt=5.0))
        node = GoToLocal(self.TARGET, acceptance_radius_m=1.0, timeout_s=2.0)
        h = harness(node)
        assert [h.tick(1.0) for _ in range(4)] == [R, R, R, F]
        assert node.feedback_message == "timed out after 2 s: no position or home"
