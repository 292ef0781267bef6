"""The built-in simulated vehicles: ArduPilot or PX4 firmware behaviour over a real MAVLink link.

:mod:`.firmware` is what every simulated autopilot does alike, :mod:`.ardupilot` and :mod:`.px4` a package per
firmware, :mod:`.physics` the vehicle models, :mod:`.registry` the simulators by name (:func:`make_autopilot`,
:func:`register_autopilot`), :mod:`.server` the MAVLink endpoint, :mod:`.faults` fault injection.
"""

import executive
from executive.sim.ardupilot.base import ArduPilotSim
from executive.sim.ardupilot.rover import ArduRoverSim
from executive.sim.firmware import DEFAULT_HOME, FirmwareSim, Home
from executive.sim.physics.vehicle import BOAT_LIMITS, ROVER_LIMITS, MotionLimits, SurfaceVehicle, VehicleModel
from executive.sim.registry import AUTOPILOTS, FIRMWARES, firmwares_for, make_autopilot, register_autopilot
from executive.sim.server import SimServer

__all__ = [
    "AUTOPILOTS",
    "BOAT_LIMITS",
    "DEFAULT_HOME",
    "FIRMWARES",
    "ROVER_LIMITS",
    "ArduPilotSim",
    "ArduRoverSim",
    "FirmwareSim",
    "Home",
    "MotionLimits",
    "SimServer",
    "SurfaceVehicle",
    "VehicleModel",
    "firmwares_for",
    "make_autopilot",
    "register_autopilot",
]


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Limits is MotionLimits
    return executive.moved_attribute(__name__, name)
