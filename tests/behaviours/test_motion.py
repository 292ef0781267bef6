"""The port's plain target for a mission waypoint (behaviours.motion.leg_target)."""

from executive.autopilot import Target
from executive.behaviours.motion import leg_target
from executive.mission.model import Waypoint


def test_a_surface_waypoint_goes_with_its_altitude_above_home() -> None:
    assert leg_target(Waypoint(lat=1.0, lon=2.0, alt_m=15.0)) == Target(1.0, 2.0, 15.0)


def test_a_depth_leg_goes_with_its_depth_even_when_it_names_a_height_above_the_seabed() -> None:
    waypoint = Waypoint(lat=1.0, lon=2.0, depth_m=5.0, altitude_m=3.0, control_mode="depth")
    assert leg_target(waypoint) == Target(1.0, 2.0, 0.0, depth_m=5.0)


def test_an_altitude_leg_goes_with_its_height_above_the_seabed_alone() -> None:
    waypoint = Waypoint(lat=1.0, lon=2.0, depth_m=5.0, altitude_m=3.0, control_mode="altitude")
    assert leg_target(waypoint) == Target(1.0, 2.0, 0.0, altitude_m=3.0)
