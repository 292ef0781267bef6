"""PX4 on a rover in the simulated autopilot: what PX4's rover modules and their land detector do."""

from __future__ import annotations

import math
from collections.abc import Sequence

from executive.sim.firmware import DEFAULT_HOME, Command, CommandHandler, Home
from executive.sim.physics.vehicle import ROVER_LIMITS, MotionLimits, SurfaceVehicle, VehicleModel
from executive.sim.px4.base import Px4Sim
from executive.sim.px4.parameters import ROVER_NAV_ACC_RAD
from executive.world.clock import Clock
from executive.world.dialect import mavlink
from executive.world.vehicles import VehicleProfile

_M = mavlink


class Px4RoverSim(Px4Sim):
    """PX4 on a rover (a :class:`SurfaceVehicle`): AUTO.LOITER stops, the other modes drive to their point and stop there.

    What PX4's rover modules do (src/modules/rover_differential, rover_ackermann, rover_mecanum; PX4 main
    a70a558393): RoverDifferential::generateSetpoints drives in AUTO.MISSION, AUTO.LOITER and AUTO.RTL
    (the auto mode), OFFBOARD and the manual modes, nothing in other modes. Its land detector
    (src/modules/land_detector/RoverLandDetector.cpp) says landed when disarmed, in AUTO.LAND or DESCEND,
    and in AUTO.RTL within NAV_ACC_RAD (0.5 m, ROMFS rc.rover_*_defaults) of the return point: so arming
    is a "take-off" (no pre-flight auto-disarm), and AUTO.LAND, or arriving home in AUTO.RTL, is a landing
    that disarms it after COM_DISARM_LAND. It has no take-off mode and no transitions (UNSUPPORTED).
    """

    MAV_TYPE = _M.MAV_TYPE_GROUND_ROVER
    FLIES = False
    UNAVAILABLE_MODES = frozenset({"AUTO.TAKEOFF"})

    vehicle: SurfaceVehicle

    def __init__(
        self, profile: VehicleProfile, clock: Clock, home: Home = DEFAULT_HOME, *, limits: MotionLimits = ROVER_LIMITS, **options: float
    ) -> None:
        self._limits = limits
        self._speed: float | None = None
        super().__init__(profile, clock, home, **options)

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return SurfaceVehicle(home[0], home[1], home[2], self._limits)

    def _throttle(self) -> float:
        return min(1.0, abs(self.vehicle.speed_m_s) / self._limits.max_m_s) if self.armed else 0.0

    def _servo_outputs(self) -> Sequence[int]:
        """MAIN1 steering, MAIN2 throttle."""
        steer = max(-1.0, min(1.0, self.vehicle.yaw_rate_rad_s / math.radians(self._limits.turn_rate_deg_s)))
        outputs = [0] * 16
        outputs[0], outputs[1] = round(1500 + 500 * steer), round(1500 + 500 * self._throttle())
        return outputs

    def _detect_landed(self) -> bool:
        """RoverLandDetector::_get_landed_state."""
        if self.mode == "AUTO.RTL" and self.home is not None:
            return self.vehicle.distance_to(*self.home) < ROVER_NAV_ACC_RAD
        return self.mode == "AUTO.LAND" or not self.armed

    def _hold_here(self) -> None:
        v = self.vehicle
        self._goal = (*v.stopping_point(), 0.0)
        v.hold()

    def _steer(self) -> None:
        if self._goal is not None and not self._landing:
            self.vehicle.drive_to(*self._goal[:2], self._speed)

    def _start_landing(self) -> None:
        self._landing, self._goal = True, None
        self.vehicle.hold()

    def _reached(self, lat: float, lon: float, alt: float) -> bool:
        return self.vehicle.arrived

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {**super()._command_handlers(), _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed}

    def _cmd_change_speed(self, cmd: Command) -> int:
        """The navigator's cruise speed (param2, m/s), capped at the rover's top speed."""
        if not cmd.params[1] > 0:
            return _M.MAV_RESULT_DENIED
        self._speed = min(cmd.params[1], self._limits.max_m_s)
        self._steer()
        return _M.MAV_RESULT_ACCEPTED
