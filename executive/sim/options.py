"""How a mission sets up its simulated vehicle: where it starts and the firmware's options."""

from __future__ import annotations

from typing import Any

from executive.mission.model import Mission, SimulatorOptions
from executive.sim.firmware import DEFAULT_HOME, Home
from executive.sim.registry import simulated_model


def simulated_home(mission: Mission) -> Home:
    """Where a mission's simulated vehicle boots: the mission's home, else its first waypoint, else the default."""
    start = mission.home or (mission.waypoints[0] if mission.waypoints else None)
    return (start.lat, start.lon, getattr(start, "heading_deg", 0.0)) if start else DEFAULT_HOME


def where_it_starts(mission: Mission) -> str:
    """Where the simulated vehicle starts, for a person, when the mission has no ``home:`` (empty when it has one)."""
    if mission.home is not None or not mission.waypoints:
        return ""
    first = mission.waypoints[0]
    return (
        f"; the mission has no home: so it starts at waypoint 1 ({first.lat:.7f}, {first.lon:.7f}): the distance to the first "
        "waypoint and the reach of the others are not tried here as a real start would try them (set home: where the vehicle will be)"
    )


def firmware_options(mission: Mission) -> dict[str, Any]:
    """The simulated firmware's options a mission sets: ``q_guided_mode`` (ArduPlane), the seabed and rangefinder (ArduSub), parameters."""
    options = mission.simulator or SimulatorOptions()
    model = simulated_model(options.model or mission.vehicle)
    found: dict[str, Any] = {}
    if model == "vtol":
        found = {"q_guided_mode": options.q_guided_mode}
    elif model == "sub":
        found = {"seabed_depth_m": options.seabed_depth_m, "rangefinder_max_m": options.rangefinder_max_m}
    if options.params:
        found["params"] = dict(options.params)
    return found
