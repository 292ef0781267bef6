"""The built-in simulated vehicles: ArduPilot or PX4 firmware behaviour over a real MAVLink link."""

from executive.sim.ardupilot.base import AUTOPILOTS, DEFAULT_HOME, FIRMWARES, ArduPilotSim, ArduRoverSim, Home, firmwares_for, make_autopilot
from executive.sim.physics.vehicle import BOAT_LIMITS, ROVER_LIMITS, Limits, SurfaceVehicle, VehicleModel
from executive.sim.server import SimServer

__all__ = [
    "AUTOPILOTS",
    "BOAT_LIMITS",
    "DEFAULT_HOME",
    "FIRMWARES",
    "ROVER_LIMITS",
    "ArduPilotSim",
    "ArduRoverSim",
    "Home",
    "Limits",
    "SimServer",
    "SurfaceVehicle",
    "VehicleModel",
    "firmwares_for",
    "make_autopilot",
]
