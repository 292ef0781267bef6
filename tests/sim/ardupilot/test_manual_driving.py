"""MANUAL on the simulated ArduRover: the pilot's sticks (steering channel 1, throttle channel 3) drive it."""

from __future__ import annotations

import pytest

from executive.world.dialect import mavlink


@pytest.fixture
def rover(make_gcs):
    gcs = make_gcs("rover", ekf_ready=True)
    assert gcs.set_mode("MANUAL") == mavlink.MAV_RESULT_ACCEPTED
    return gcs


def position(gcs):
    return gcs.ap.vehicle.lat, gcs.ap.vehicle.lon


def test_throttle_drives_forward_when_armed(rover):
    assert rover.arm() == mavlink.MAV_RESULT_ACCEPTED
    heading = rover.ap.vehicle.heading_deg
    rover.ap.rc_channels[2] = 2000  # full throttle
    rover.run(5.0)
    assert rover.ap.vehicle.speed_m_s == pytest.approx(rover.ap.vehicle.limits.max_m_s, rel=0.05)
    assert rover.ap.vehicle.heading_deg == pytest.approx(heading, abs=0.5)
    rover.ap.rc_channels[2] = 1500
    rover.run(5.0)
    assert rover.ap.vehicle.speed_m_s == pytest.approx(0.0, abs=0.01)


def test_steering_turns(rover):
    rover.arm()
    heading = rover.ap.vehicle.heading_deg
    rover.ap.rc_channels[0] = 1750  # half right
    rover.ap.rc_channels[2] = 1700
    rover.run(1.0)
    assert (rover.ap.vehicle.heading_deg - heading) % 360 == pytest.approx(rover.ap.vehicle.limits.turn_rate_deg_s / 2, abs=3)


def test_sticks_in_the_deadzone_or_disarmed_do_not_move_it(rover):
    start = position(rover)
    rover.ap.rc_channels[2] = 1520  # inside RC_DZ
    rover.arm()
    rover.run(3.0)
    assert position(rover) == pytest.approx(start, abs=1e-9)
    rover.ap.rc_channels[2] = 2000
    rover.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0)
    rover.run(3.0)
    assert position(rover) == pytest.approx(start, abs=1e-9)


def test_guided_ignores_the_sticks(rover):
    rover.arm()
    rover.set_mode("GUIDED")
    rover.ap.rc_channels[2] = 2000
    start = position(rover)
    rover.run(3.0)
    assert position(rover) == pytest.approx(start, abs=1e-7)


def test_change_speed_applies_in_autonomous_modes_only(rover):
    assert rover.ack(mavlink.MAV_CMD_DO_CHANGE_SPEED, 1, 1.0).result == mavlink.MAV_RESULT_FAILED  # MANUAL
    rover.arm()
    rover.set_mode("GUIDED")
    assert rover.ack(mavlink.MAV_CMD_DO_CHANGE_SPEED, 1, 1.0).result == mavlink.MAV_RESULT_ACCEPTED
    rover.goto(*rover.north(100.0))
    rover.run(10.0)
    assert rover.ap.vehicle.speed_m_s == pytest.approx(1.0, abs=0.01)
    assert rover.ack(mavlink.MAV_CMD_DO_CHANGE_SPEED, 1, 3.0).result == mavlink.MAV_RESULT_ACCEPTED
    rover.run(5.0)
    assert rover.ap.vehicle.speed_m_s == pytest.approx(3.0, abs=0.01)
    assert rover.ack(mavlink.MAV_CMD_DO_CHANGE_SPEED, 1, 50.0).result == mavlink.MAV_RESULT_FAILED  # beyond what it can do
