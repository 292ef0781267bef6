"""The built-in simulated vehicles: ArduPilot firmware behaviour over a real MAVLink link."""

from executive.sim.autopilot import AUTOPILOTS, DEFAULT_HOME, ArduPilotSim, ArduRoverSim, Home, make_autopilot
from executive.sim.server import SimServer
from executive.sim.vehicle import BOAT_LIMITS, ROVER_LIMITS, Limits, SurfaceVehicle, VehicleModel

__all__ = [
    "AUTOPILOTS",
    "BOAT_LIMITS",
    "DEFAULT_HOME",
    "ROVER_LIMITS",
    "ArduPilotSim",
    "ArduRoverSim",
    "Home",
    "Limits",
    "SimServer",
    "SurfaceVehicle",
    "VehicleModel",
    "make_autopilot",
]
