"""What the AUV survey added to the behaviours, tick by tick: PositionKnown, AltitudeWithin on altitude legs only,
Surface, a command action run again (the next leg's speed), and why ForEachLeg says a leg failed."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours import AltitudeWithin, ChangeSpeed, ForEachLeg, PositionKnown, Surface
from executive.io.mavlink.commander import Commander
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission, Range
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition
from executive.world.vehicles import PROFILES, SUB_MODES

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
M = mavlink
WAYPOINTS = [
    {"lat": 44.0951, "lon": 9.8630, "control_mode": "depth", "depth_m": 10.0, "speed_m_s": 0.5},
    {"lat": 44.0952, "lon": 9.8630, "control_mode": "altitude", "altitude_m": 20.0, "speed_m_s": 0.8},
]


@pytest.fixture
def commander(link, clock) -> Commander:
    return Commander(link, clock, PROFILES["sub"])


@pytest.fixture
def mission_state() -> MissionState:
    """Two legs: 10 m deep at 0.5 m/s, then 20 m above the seabed at 0.8 m/s."""
    state = MissionState()
    state.upload(Mission.model_validate({"version": 1, "name": "dive", "vehicle": "sub", "waypoints": WAYPOINTS}))
    state.start()
    return state


def depth(metres: float) -> GlobalPosition:
    return GlobalPosition(44.095, 9.863, -metres, 0.0, 0.0, 0.0, None, 0.0)


def test_position_known_fails_until_the_autopilot_reports_a_position(harness, vehicle):
    node = PositionKnown()
    h = harness(node)
    assert (h.tick(), node.feedback_message) == (F, "no position")
    vehicle.set(vehicle__position=depth(0.0))
    assert (h.tick(), node.feedback_message) == (S, "ok")


@pytest.mark.parametrize(
    ("leg", "altitude", "status", "why"),
    [
        (0, 1.0, S, "not an altitude leg"),  # a depth leg: the seabed's distance is not this guard's business
        (0, None, S, "not an altitude leg"),
        (1, 20.0, S, "ok"),
        (1, 1.4, F, "altitude 1.4 m above the seabed outside [2, 100] m"),
        (1, None, F, "no altitude above the seabed (no valid rangefinder reading)"),
    ],
)
def test_altitude_within_judges_only_altitude_legs_when_asked(harness, vehicle, mission_state, leg, altitude, status, why):
    for _ in range(leg):
        mission_state.advance_leg()
    vehicle.set(vehicle__altitude_above_bottom_m=altitude)
    node = AltitudeWithin(Range(min=2.0, max=100.0), altitude_legs_only=True)
    h = harness(node)
    assert (h.tick(), node.feedback_message) == (status, why)
    assert node.name == "Altitude within [2, 100] m on altitude legs?"


def test_altitude_within_judges_every_leg_by_default(harness, vehicle):
    vehicle.set(vehicle__altitude_above_bottom_m=1.0)
    node = AltitudeWithin(Range(min=2.0, max=100.0))
    assert harness(node).tick() == F


class TestSurface:
    def test_asks_for_surface_then_succeeds_once_up_and_the_firmware_has_handed_over_to_alt_hold(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=depth(10.0))
        node = Surface()
        h = harness(node)
        assert h.tick() == R
        (sent,) = h.link.take()
        assert (sent.command, sent.param2) == (M.MAV_CMD_DO_SET_MODE, SUB_MODES["SURFACE"])
        h.ack(M.MAV_CMD_DO_SET_MODE)
        vehicle.set(vehicle__mode="SURFACE", vehicle__position=depth(4.0))
        assert (h.tick(), node.feedback_message) == (R, "depth 4.0 m in SURFACE")
        vehicle.set(vehicle__position=depth(0.2))
        assert h.tick() == R  # up, but SURFACE has not finished
        vehicle.set(vehicle__mode="ALT_HOLD", vehicle__position=depth(0.1))
        assert h.tick() == S
        assert h.link.take() == []

    def test_already_at_the_surface_succeeds_without_a_command(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=depth(0.3))
        h = harness(Surface())
        assert h.tick() == S
        assert h.link.take() == []

    def test_refused_fails_with_the_reason(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=depth(5.0))
        node = Surface()
        h = harness(node)
        h.tick()
        h.ack(M.MAV_CMD_DO_SET_MODE, M.MAV_RESULT_DENIED)
        assert (h.tick(), node.feedback_message) == (F, "refused: DENIED")

    @pytest.mark.parametrize(("start_depth", "limit_s"), [(6.0, 42.0), (50.0, 130.0)])
    def test_gives_up_after_the_climb_time_from_its_depth_and_a_margin(self, harness, vehicle, start_depth, limit_s):
        vehicle.set(vehicle__mode="GUIDED", vehicle__position=depth(start_depth))
        node = Surface(margin_s=30.0, climb_m_s=0.5)
        h = harness(node)
        h.tick(0.0)
        h.ack(M.MAV_CMD_DO_SET_MODE)
        vehicle.set(vehicle__mode="SURFACE", vehicle__position=depth(3.0))  # stuck
        assert h.tick(limit_s) == R
        assert h.tick(0.125) == F
        assert node.feedback_message == f"not confirmed after {limit_s:g} s: depth 3.0 m in SURFACE"

    def test_run_again_from_another_depth_it_gives_up_after_that_depth_s_climb_time(self, harness, vehicle):
        """The time allowed, and the asking's rules with it, are worked out at each run: 42 s from 6 m, then 130 s from 50 m."""
        node = Surface(margin_s=30.0, climb_m_s=0.5)
        h = harness(node)
        for start_depth, limit_s in ((6.0, 42.0), (50.0, 130.0)):
            vehicle.set(vehicle__mode="GUIDED", vehicle__position=depth(start_depth))
            assert h.tick() == R
            h.ack(M.MAV_CMD_DO_SET_MODE)
            vehicle.set(vehicle__mode="SURFACE", vehicle__position=depth(3.0))  # stuck
            assert h.tick(limit_s) == R
            assert h.tick(0.125) == F
            assert node.feedback_message == f"not confirmed after {limit_s:g} s: depth 3.0 m in SURFACE"


def test_a_command_action_run_again_sends_its_command_again(harness, mission_state):
    """The next leg's speed: the ack of the previous leg's request does not confirm it."""
    node = ChangeSpeed()
    h = harness(node)
    assert h.tick() == R
    h.ack(M.MAV_CMD_DO_CHANGE_SPEED)
    assert h.tick() == S
    assert [m.param2 for m in h.link.take()] == [0.5]
    mission_state.advance_leg()
    assert [h.tick(), h.tick()] == [R, R]
    assert [m.param2 for m in h.link.take()] == [0.8]
    h.ack(M.MAV_CMD_DO_CHANGE_SPEED)
    assert h.tick() == S


def test_for_each_leg_says_which_action_of_a_leg_failed_and_why(harness):
    leg = py_trees.composites.Sequence("Leg", memory=True, children=[ChangeSpeed()])
    node = ForEachLeg(leg)
    h = harness(node)
    h.tick()
    h.ack(M.MAV_CMD_DO_CHANGE_SPEED, M.MAV_RESULT_DENIED)
    assert h.tick() == F
    assert node.feedback_message == "leg 1/2 failed: Change speed: refused: DENIED"
