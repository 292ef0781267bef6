"""The simulated tracked UGV (AgileX Bunker on ArduRover): skid-steer track outputs on SERVO1 and SERVO3."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.sim import SimServer
from executive.sim.ardupilot.bunker import BunkerSim
from executive.sim.physics.vehicle import BUNKER_LIMITS, SkidSteerVehicle, skid_steer_mix
from executive.world.clock import ScaledClock
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Client, Gcs

MakeGcs = Callable[..., "Gcs"]


def driving(make_gcs: MakeGcs) -> Gcs:
    gcs = make_gcs("bunker", ekf_ready=True)
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
    return gcs


def tracks(gcs: Gcs) -> tuple[int, int]:
    servos = gcs.last("SERVO_OUTPUT_RAW")
    return servos.servo1_raw, servos.servo3_raw


@pytest.mark.parametrize(
    ("throttle", "steering", "left", "right"),
    [
        (0.5, 0.0, 0.5, 0.5),
        (0.0, 0.3, 0.3, -0.3),  # turn right in place: left track forward, right track back
        (-0.4, -0.2, -0.6, -0.2),
        (0.9, 0.5, 1.0, 0.9 / 1.4 - 0.5 / 1.4),  # saturated: steering scaled back by 1.4, throttle gets the rest
    ],
)
def test_the_skid_steer_mixer(throttle: float, steering: float, left: float, right: float) -> None:
    assert skid_steer_mix(throttle, steering) == pytest.approx((left, right))


def test_a_bunker_is_an_ardurover_rover(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("bunker")
    heartbeat = gcs.last("HEARTBEAT")
    assert (heartbeat.type, heartbeat.custom_mode) == (m.MAV_TYPE_GROUND_ROVER, 0)
    assert isinstance(gcs.ap, BunkerSim) and gcs.ap.profile.kind == "rover"
    assert gcs.ap.FIRMWARE == "ArduRover"


def test_disarmed_tracks_are_neutral(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("bunker", ekf_ready=True)
    gcs.set_mode("GUIDED")
    gcs.goto(*gcs.north(20.0))
    gcs.run(5.0)
    assert tracks(gcs) == (1500, 1500) == gcs.ap.track_pwm
    assert gcs.ap.servo_outputs[:4] == (1500, 0, 1500, 0)  # only SERVO1 and SERVO3 are used


def test_straight_ahead_both_tracks_drive_forward_alike(make_gcs: MakeGcs) -> None:
    gcs = driving(make_gcs)  # heading north
    gcs.goto(*gcs.north(30.0))
    gcs.run(1.0)
    left, right = tracks(gcs)
    assert left == right > 1500
    gcs.run(6.0)
    left, right = tracks(gcs)
    assert left == right == pytest.approx(1833, abs=1)  # WP_SPEED 1.0 m/s of a 1.5 m/s track
    assert gcs.ap.vehicle.speed_m_s == pytest.approx(gcs.ap.motion.speed_m_s, abs=0.01)


@pytest.mark.parametrize(("east_m", "faster"), [(20.0, "left"), (-20.0, "right")], ids=["right-turn", "left-turn"])
def test_turning_drives_the_outer_track_faster(make_gcs: MakeGcs, east_m: float, faster: str) -> None:
    # heading north, the target abeam: more than WP_PIVOT_ANGLE (60 degrees) off, so it pivots on the spot first
    # (AR_PivotTurn), then drives with both tracks forward (ArduRover's GUIDED, Rover/mode_guided.cpp via AR_WPNav)
    gcs = driving(make_gcs)
    gcs.goto(*gcs.east(east_m))
    gcs.run(0.5)
    left, right = tracks(gcs)
    outer, inner = (left, right) if faster == "left" else (right, left)
    assert outer > 1500 > inner and abs(gcs.ap.vehicle.speed_m_s) < 0.01
    gcs.run(3.5)
    left, right = tracks(gcs)
    assert min(left, right) > 1500  # driving forward now
    assert gcs.ap.vehicle.heading_deg == pytest.approx(90.0 if faster == "left" else 270.0, abs=6.0)


def test_stopping_gives_neutral_tracks(make_gcs: MakeGcs) -> None:
    gcs = driving(make_gcs)
    target = gcs.north(10.0)
    gcs.goto(*target)
    gcs.run(4.0)
    assert tracks(gcs) != (1500, 1500)
    gcs.run(16.0)
    assert gcs.ap.vehicle.distance_to(*target) <= BUNKER_LIMITS.arrive_m
    assert tracks(gcs) == (1500, 1500)
    gcs.goto(*gcs.north(40.0))
    gcs.run(3.0)
    assert gcs.set_mode("HOLD") == m.MAV_RESULT_ACCEPTED
    gcs.run(3.0)
    assert tracks(gcs) == (1500, 1500)
    gcs.goto(*gcs.north(40.0))  # ignored outside GUIDED
    gcs.set_mode("GUIDED")
    gcs.goto(*gcs.north(40.0))
    gcs.run(3.0)
    gcs.ack(m.MAV_CMD_COMPONENT_ARM_DISARM, 0)
    gcs.run(0.5)
    assert tracks(gcs) == (1500, 1500)  # disarmed while driving: neutral at once


def test_tracks_slip_in_a_turn() -> None:
    vehicle = SkidSteerVehicle(47.0, 8.0, 0.0)
    vehicle.powered = True
    vehicle.drive_to(47.0, 8.0 + 20.0 / 75_900.0)  # 20 m east: a pivot turn to the right
    vehicle.step(0.5)
    left, right = vehicle.track_throttles
    t = vehicle.tracks
    rigid_rate = (left - right) * t.max_m_s / t.width_m  # what tracks that did not slip would turn at
    assert 0.0 < vehicle.yaw_rate_rad_s == pytest.approx(rigid_rate / t.slip_factor)
    assert vehicle.yaw_rate_rad_s < rigid_rate


def test_a_bunker_over_udp_reports_its_tracks(client_for: Callable[[str], Client]) -> None:
    with SimServer("bunker", clock=ScaledClock(50.0), ekf_ready_after_s=1.0) as server:
        client = client_for(server.url_for_client)
        client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        client.wait("EKF_STATUS_REPORT", lambda msg: msg.flags == 831)
        assert client.wait("SERVO_OUTPUT_RAW").servo1_raw == 1500
        assert client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15).result == m.MAV_RESULT_ACCEPTED
        assert client.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == m.MAV_RESULT_ACCEPTED
        x, y = round((server.autopilot.start[0] + 30 / 111_319.49) * 1e7), round(server.autopilot.start[1] * 1e7)
        client.conn.mav.set_position_target_global_int_send(0, 1, 1, m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, x, y, 0, *[0.0] * 8)
        client.wait("SERVO_OUTPUT_RAW", lambda msg: msg.servo1_raw > 1600 and msg.servo3_raw > 1600)  # on its way
        with server.lock:
            assert server.autopilot.servo_outputs[0] > 1500
        assert client.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == m.MAV_RESULT_ACCEPTED
        client.wait("SERVO_OUTPUT_RAW", lambda msg: msg.servo1_raw == msg.servo3_raw == 1500)
