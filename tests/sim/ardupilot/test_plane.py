"""The simulated VTOL (ArduPlane QuadPlane): take-off, transitions, fixed-wing circling, landing."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.sim import SimServer
from executive.sim.ardupilot.plane import AIRSPEED_MIN_M_S, ASSIST_SPEED_M_S, LOITER_RADIUS_M, TRANSITION_MS, VTOL_APPROACH_M
from executive.sim.physics.aircraft import QUADPLANE_LIMITS
from executive.world.clock import ScaledClock
from executive.world.dialect import mavlink as m
from executive.world.vehicles import profile_for_mav_type

if TYPE_CHECKING:
    from sim_support import Client, Gcs

MakeGcs = Callable[..., "Gcs"]
MC, FW, TO_FW, TO_MC = m.MAV_VTOL_STATE_MC, m.MAV_VTOL_STATE_FW, m.MAV_VTOL_STATE_TRANSITION_TO_FW, m.MAV_VTOL_STATE_TRANSITION_TO_MC
ON_GROUND, TAKEOFF, IN_AIR, LANDING = (
    m.MAV_LANDED_STATE_ON_GROUND, m.MAV_LANDED_STATE_TAKEOFF, m.MAV_LANDED_STATE_IN_AIR, m.MAV_LANDED_STATE_LANDING,
)  # fmt: skip


def ready(make_gcs: MakeGcs) -> Gcs:
    """EKF ready, EXTENDED_SYS_STATE requested at 2 Hz (ArduPlane does not stream it unasked)."""
    gcs = make_gcs("vtol", ekf_ready=True)
    assert gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 500_000).result == m.MAV_RESULT_ACCEPTED
    return gcs


def takeoff(gcs: Gcs, metres: float) -> int:
    return gcs.ack(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, metres).result


def airborne(make_gcs: MakeGcs, metres: float = 10.0) -> Gcs:
    gcs = ready(make_gcs)
    assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    assert takeoff(gcs, metres) == m.MAV_RESULT_ACCEPTED
    gcs.run(metres / QUADPLANE_LIMITS.climb_m_s + 4.0, step=0.5)
    return gcs


def states(messages: list) -> list[tuple[int, int]]:
    return [(msg.vtol_state, msg.landed_state) for msg in messages if msg.get_type() == "EXTENDED_SYS_STATE"]


def in_fixed_wing_flight(make_gcs: MakeGcs) -> Gcs:
    gcs = airborne(make_gcs, 30.0)
    assert gcs.reposition(*gcs.north(600.0), 30.0).result == m.MAV_RESULT_ACCEPTED
    gcs.run(20.0, step=0.5)
    assert gcs.ap.vtol_state == FW
    return gcs


def test_a_quadplane_says_it_is_a_fixed_wing(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("vtol", ekf_ready=True)
    heartbeat = gcs.last("HEARTBEAT")
    assert (heartbeat.type, heartbeat.custom_mode, heartbeat.system_status) == (m.MAV_TYPE_FIXED_WING, 0, m.MAV_STATE_STANDBY)
    assert profile_for_mav_type(heartbeat.type).kind == "vtol"
    assert heartbeat.base_mode == m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED  # MANUAL: not stabilized
    assert not gcs.of_type(gcs.log, "EXTENDED_SYS_STATE")  # not in ArduPlane's streams
    gcs.ack(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 1_000_000)
    out = gcs.run(10.0)
    assert states(out) == [(FW, ON_GROUND)] * 10  # MANUAL on the ground: fixed wing, the lift motors off


def test_takeoff_only_in_guided_armed_on_the_ground(make_gcs: MakeGcs) -> None:
    gcs = ready(make_gcs)
    gcs.set_mode("QLOITER")
    gcs.arm()
    replies = gcs.command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["User Takeoff only in GUIDED mode"])
    assert gcs.ack(m.MAV_CMD_NAV_VTOL_TAKEOFF, 0, 0, 0, 0, 0, 0, 10).result == m.MAV_RESULT_UNSUPPORTED  # a mission item only
    gcs.ack(m.MAV_CMD_COMPONENT_ARM_DISARM, 0)
    gcs.set_mode("GUIDED")
    replies = gcs.command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10)
    assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["Must be armed for takeoff"])
    gcs.run(5.0)
    assert gcs.ap.vehicle.alt_m == 0.0 and states(gcs.log)[-1] == (FW, ON_GROUND)


def test_takeoff_climbs_as_a_multicopter_and_hovers(make_gcs: MakeGcs) -> None:
    gcs = ready(make_gcs)
    gcs.set_mode("GUIDED")
    gcs.arm()
    assert takeoff(gcs, 12.0) == m.MAV_RESULT_ACCEPTED
    out = gcs.run(3.0, step=0.5)
    assert states(out)[-1] == (MC, TAKEOFF)
    assert max(-msg.vz for msg in gcs.of_type(out, "GLOBAL_POSITION_INT")) <= QUADPLANE_LIMITS.climb_m_s * 100
    out = gcs.run(10.0, step=0.5)
    assert states(out)[-1] == (MC, IN_AIR)
    assert gcs.last("GLOBAL_POSITION_INT").relative_alt == pytest.approx(12_000, abs=100)
    assert gcs.last("HEARTBEAT").system_status == m.MAV_STATE_ACTIVE
    assert takeoff(gcs, 12.0) == m.MAV_RESULT_FAILED  # "Already flying - no takeoff"
    gcs.run(20.0, step=0.5)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) < 0.01 and gcs.ap.vehicle.speed_m_s == 0.0  # hovering


def test_do_vtol_transition_is_refused_outside_auto(make_gcs: MakeGcs) -> None:
    gcs = ready(make_gcs)
    gcs.set_mode("QLOITER")
    gcs.arm()
    for _ in range(2):  # on the ground, then in the air
        replies = gcs.command(m.MAV_CMD_DO_VTOL_TRANSITION, MC)
        assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, ["VTOL transition only in AUTO"])
        assert gcs.ack(m.MAV_CMD_DO_VTOL_TRANSITION, FW).result == m.MAV_RESULT_FAILED
        out = gcs.run(5.0, step=0.5)
        assert {vtol for vtol, _ in states(out)} == {MC}
        gcs.set_mode("GUIDED")
        takeoff(gcs, 10.0)
        gcs.run(8.0, step=0.5)
        assert gcs.ap.landed_state == IN_AIR


def test_transition_to_fixed_wing_waits_for_the_assist_speed_then_the_transition_time(make_gcs: MakeGcs) -> None:
    """SLT_Transition::update(): the timer starts above AIRSPEED_MIN only once the lift motors stop assisting (Q_ASSIST_SPEED 18 in
    quadplane.parm: "Transition airspeed reached 18.2" on SITL), then Q_TRANSITION_MS; from a hover that is ~190 m."""
    gcs = airborne(make_gcs, 30.0)
    target = gcs.north(600.0)
    gcs.set_mode("QLOITER")
    assert gcs.reposition(*target, 30.0).result == m.MAV_RESULT_FAILED  # outside GUIDED without the change-mode flag
    log_from = len(gcs.log)
    assert gcs.reposition(*target, 30.0, m.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE).result == m.MAV_RESULT_ACCEPTED
    start, origin = gcs.ap.elapsed_s, (gcs.ap.vehicle.lat, gcs.ap.vehicle.lon)
    seen: list[tuple[float, int, float]] = []
    while gcs.ap.vtol_state != FW:
        assert gcs.ap.elapsed_s - start < 30.0, "no transition"
        out = gcs.run(0.5)
        seen += [(gcs.ap.elapsed_s - start, msg.vtol_state, gcs.ap.vehicle.speed_m_s) for msg in gcs.of_type(out, "EXTENDED_SYS_STATE")]
    assert {state for _, state, _ in seen[:-1]} == {TO_FW}
    assert not [t for t, state, speed in seen if state == TO_FW and speed > ASSIST_SPEED_M_S + 1.0 and t > 20.0]
    above_min = next(t for t, _, speed in seen if speed > AIRSPEED_MIN_M_S)
    reached = next(t for t, _, speed in seen if speed > ASSIST_SPEED_M_S)
    assert reached > above_min + 2.0  # above AIRSPEED_MIN but still assisted: no timer yet
    assert gcs.ap.elapsed_s - start >= reached + TRANSITION_MS / 1000  # FW only once the transition time has run too
    assert gcs.ap.elapsed_s - start == pytest.approx(14.0, abs=1.0)
    assert gcs.ap.vehicle.distance_to(*origin) == pytest.approx(195.0, abs=15.0)  # ~193 m, seen at 0.5 s steps (25 m/s)
    texts = gcs.texts(gcs.log[log_from:])
    assert "Transition airspeed wait" not in texts  # entered while assisting: should_assist set the start time already
    assert texts[-2].startswith("Transition airspeed reached 18.") and texts[-1] == "Transition done"
    assert gcs.ap.landed_state == IN_AIR


def test_with_q_guided_mode_a_reposition_300_m_ahead_from_a_hover_never_shows_fixed_wing(make_gcs: MakeGcs) -> None:
    """Issue 14, ArduPlane SITL with quadplane.parm: "Transition airspeed reached 18.2", then "VTOL Position1 d=143.4",
    the transition (~190 m from a hover) is not done when the VTOL approach begins ~140 m out: FW (4) is never reported."""
    gcs = airborne(make_gcs, 30.0)
    gcs.ap.q_guided_mode = 1
    target = gcs.north(300.0)
    log_from = len(gcs.log)
    assert gcs.reposition(*target, 30.0).result == m.MAV_RESULT_ACCEPTED
    out = gcs.run(90.0, step=0.5)
    seen = [vtol for vtol, _ in states(out)]
    assert FW not in seen
    assert [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s] == [TO_FW, TO_MC, MC]  # SITL's 1 -> 2 -> 3
    texts = gcs.texts(gcs.log[log_from:])
    reached = next(i for i, t in enumerate(texts) if t.startswith("Transition airspeed reached 18."))
    approach = next(i for i, t in enumerate(texts) if t.startswith("VTOL Position1 d="))
    assert reached < approach and "Transition done" not in texts
    assert float(texts[approach].removeprefix("VTOL Position1 d=")) == pytest.approx(VTOL_APPROACH_M, abs=15.0)
    assert gcs.ap.vehicle.distance_to(*target) < 0.5


def test_a_plane_cannot_hover_it_circles_the_guided_point(make_gcs: MakeGcs) -> None:
    gcs = in_fixed_wing_flight(make_gcs)
    target = gcs.north(600.0)
    distances = []
    for _ in range(60):
        gcs.run(2.0, step=0.5)
        distances.append(gcs.ap.vehicle.distance_to(*target))
        assert gcs.ap.vehicle.speed_m_s > AIRSPEED_MIN_M_S
    assert max(distances[-20:]) == pytest.approx(LOITER_RADIUS_M, rel=0.1)
    assert min(distances[-20:]) == pytest.approx(LOITER_RADIUS_M, rel=0.1)
    gcs.goto(0.0, 0.0, alt=60.0)  # ArduPlane takes only the altitude from SET_POSITION_TARGET_GLOBAL_INT
    gcs.run(30.0, step=0.5)
    assert gcs.ap.vehicle.distance_to(*target) == pytest.approx(LOITER_RADIUS_M, rel=0.1)
    assert gcs.last("GLOBAL_POSITION_INT").relative_alt == pytest.approx(60_000, abs=500)


def test_back_to_multicopter_in_qloiter(make_gcs: MakeGcs) -> None:
    gcs = in_fixed_wing_flight(make_gcs)
    assert gcs.set_mode("QLOITER") == m.MAV_RESULT_ACCEPTED
    out = gcs.run(1.0)
    assert set(states(out)) == {(MC, IN_AIR)}  # a standard QuadPlane is MC as soon as it is in a Q mode
    assert gcs.ap.vehicle.speed_m_s > QUADPLANE_LIMITS.mc_speed_m_s  # still braking
    gcs.run(15.0, step=0.5)
    assert gcs.ap.vehicle.speed_m_s == pytest.approx(0.0, abs=0.05)
    assert gcs.ap.vehicle.alt_m == pytest.approx(30.0, abs=0.5)


def test_with_q_guided_mode_a_near_target_is_flown_as_a_multicopter_a_far_one_as_a_plane(make_gcs: MakeGcs) -> None:
    gcs = airborne(make_gcs, 20.0)
    gcs.ap.q_guided_mode = 1  # Q_GUIDED_MODE=1
    near = gcs.east(40.0)  # inside WP_LOITER_RAD: L1 is "on the circle" at once, the lift motors fly it
    assert gcs.reposition(*near, 25.0).result == m.MAV_RESULT_ACCEPTED
    out = gcs.run(20.0, step=0.5)
    seen = [vtol for vtol, _ in states(out)]
    assert [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s] == [TO_MC, MC]  # POSITION1 until within 5 m, then POSITION2
    assert {landed for _, landed in states(out)} == {IN_AIR}
    assert gcs.ap.vehicle.distance_to(*near) < 0.5 and gcs.ap.vehicle.alt_m == pytest.approx(25.0, abs=0.5)
    far = gcs.north(400.0)
    assert gcs.reposition(*far, 25.0).result == m.MAV_RESULT_ACCEPTED
    out = gcs.run(90.0, step=0.5)
    seen = [vtol for vtol, _ in states(out)]
    assert [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s] == [TO_FW, FW, TO_MC, MC]  # a plane, then a hover
    assert gcs.ap.vehicle.distance_to(*far) < 0.5 and gcs.ap.vehicle.speed_m_s == pytest.approx(0.0, abs=0.05)


def test_qrtl_from_fixed_wing_brakes_then_returns_and_lands(make_gcs: MakeGcs) -> None:
    gcs = in_fixed_wing_flight(make_gcs)
    assert gcs.set_mode("QRTL") == m.MAV_RESULT_ACCEPTED
    out = gcs.run(4.0, step=0.5)
    assert states(out)[0][0] == TO_MC
    out = gcs.run(200.0, step=0.5)
    assert states(out)[-1] == (MC, ON_GROUND) and not gcs.ap.armed
    assert gcs.ap.vehicle.distance_to(*gcs.ap.home) < 2.5
    assert gcs.texts(out)[-4:] == ["Land descend started", "Land final started", "Land complete", "Throttle disarmed"]


def test_qland_lands_and_disarms(make_gcs: MakeGcs) -> None:
    gcs = airborne(make_gcs, 10.0)
    assert gcs.set_mode("QLAND") == m.MAV_RESULT_ACCEPTED
    out = gcs.run(4.0, step=0.5)
    assert states(out)[-1] == (MC, LANDING)
    assert gcs.texts(out) == ["Land final started"]  # below Q_LAND_FINAL_ALT (6 m) after 4 s at 1.5 m/s
    out = gcs.run(12.0, step=0.5)
    assert gcs.ap.vehicle.on_ground and gcs.ap.armed  # touched down; the land detector takes 4 s
    out = gcs.run(5.0, step=0.5)
    assert gcs.texts(out)[-2:] == ["Land complete", "Throttle disarmed"]
    heartbeat = gcs.last("HEARTBEAT")
    assert not heartbeat.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED and heartbeat.custom_mode == 20  # still QLAND
    assert states(gcs.run(2.0))[-1] == (MC, ON_GROUND)


def test_a_vtol_over_udp_takes_off(client_for: Callable[[str], Client]) -> None:
    with SimServer("vtol", clock=ScaledClock(50.0), ekf_ready_after_s=1.0) as server:
        client = client_for(server.url_for_client)
        client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert client.wait("HEARTBEAT").type == m.MAV_TYPE_FIXED_WING
        client.wait("EKF_STATUS_REPORT", lambda msg: msg.flags == 831)
        assert client.command(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 200_000).result == m.MAV_RESULT_ACCEPTED
        assert client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15).result == m.MAV_RESULT_ACCEPTED
        assert client.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == m.MAV_RESULT_ACCEPTED
        assert client.command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 5).result == m.MAV_RESULT_ACCEPTED
        client.wait("EXTENDED_SYS_STATE", lambda msg: (msg.vtol_state, msg.landed_state) == (MC, TAKEOFF))
        client.wait("EXTENDED_SYS_STATE", lambda msg: (msg.vtol_state, msg.landed_state) == (MC, IN_AIR))
        assert client.wait("GLOBAL_POSITION_INT").relative_alt > 4500


def test_with_q_guided_mode_a_wing_borne_guided_target_ends_in_a_vtol_approach_140_m_out(make_gcs: MakeGcs) -> None:
    """ArduPlane 4.7 SITL (issue 14): after a DO_REPOSITION ahead, "VTOL Position1 d=143.4": the last ~140 m are flown on the lift
    motors. A target 600 m ahead (the executive's transition) shows FW first; the approach then ends in a hover over the point."""
    gcs = airborne(make_gcs, 30.0)
    gcs.ap.q_guided_mode = 1
    target = gcs.north(600.0)
    assert gcs.reposition(*target, 30.0).result == m.MAV_RESULT_ACCEPTED
    out = gcs.run(120.0, step=0.5)
    seen = [vtol for vtol, _ in states(out)]
    assert [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s] == [TO_FW, FW, TO_MC, MC]
    assert any(t.startswith("VTOL position2 started") for t in gcs.texts(out))
    approach = next(t for t in gcs.texts(out) if t.startswith("VTOL Position1 d="))
    assert float(approach.removeprefix("VTOL Position1 d=")) == pytest.approx(VTOL_APPROACH_M, abs=15.0)
    assert gcs.ap.vehicle.distance_to(*target) < 0.5


def test_q_guided_mode_is_read_as_a_parameter(make_gcs: MakeGcs) -> None:
    gcs = ready(make_gcs)
    gcs.ap.q_guided_mode = 1
    (value,) = gcs.send(gcs.mav.param_request_read_encode(1, 1, b"Q_GUIDED_MODE", -1))
    assert (value.get_type(), value.param_id, value.param_value) == ("PARAM_VALUE", "Q_GUIDED_MODE", 1.0)
    assert make_gcs("vtol", q_guided_mode=1).ap.params["Q_GUIDED_MODE"] == 1  # the mission's simulator option
    assert gcs.send(gcs.mav.param_request_read_encode(1, 1, b"NO_SUCH_PARAM", -1)) == []  # ArduPilot does not answer
