"""How a mission sets up its simulated vehicle: where it starts and the firmware's options."""

from __future__ import annotations

from executive.mission.model import Mission, SimulatorOptions
from executive.sim.autopilot import DEFAULT_HOME, Home


def simulated_home(mission: Mission) -> Home:
    """Where a mission's simulated vehicle boots: the mission's home, else its first waypoint, else the default."""
    start = mission.home or (mission.waypoints[0] if mission.waypoints else None)
    return (start.lat, start.lon, getattr(start, "heading_deg", 0.0)) if start else DEFAULT_HOME


def firmware_options(mission: Mission) -> dict[str, float]:
    """The simulated firmware's options a mission sets (``q_guided_mode`` for the vtol's ArduPlane; the seabed and rangefinder for ArduSub)."""
    options = mission.simulator or SimulatorOptions()
    model = options.model or mission.vehicle
    if model == "vtol":
        return {"q_guided_mode": options.q_guided_mode}
    if model == "sub":
        return {"seabed_depth_m": options.seabed_depth_m, "rangefinder_max_m": options.rangefinder_max_m}
    return {}
