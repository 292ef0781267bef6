"""The AgileX Bunker tracked UGV on ArduRover: ArduRover's modes on a skid-steered vehicle model.

ArduRover's skid-steer frame drives the left track from SERVO1 (SERVO1_FUNCTION=73, ThrottleLeft)
and the right one from SERVO3 (SERVO3_FUNCTION=74, ThrottleRight); here those outputs span
1000..2000 us around a 1500 us trim, and a disarmed vehicle outputs the trim (MOT_SAFE_DISARM=0).
A CAN drive bridge reads them from :attr:`BunkerSim.track_pwm` (holding the server's lock), as the
real one reads SERVO_OUTPUT_RAW. With a CAN bus, the server adds the base's own controller on it
(:class:`~executive.sim.agilex_base.SimulatedBase`): in CAN command mode the tracks obey its motion
commands, not these outputs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import ClassVar

from executive.sim.ardupilot.rover import ArduRoverSim
from executive.sim.firmware import Home
from executive.sim.physics.vehicle import BUNKER_LIMITS, MotionLimits, SkidSteerVehicle

#: The Bunker's tracks respond quickly; it turns on the spot.
BUNKER_RESPONSE = {"speed_lag_s": 0.2, "min_turn_radius_m": 0.0}

PWM_TRIM, PWM_SPAN = 1500, 500  # SERVOn_TRIM, and SERVOn_MAX - SERVOn_TRIM (MIN 1000, MAX 2000)


def throttle_pwm(throttle: float) -> int:
    """A track throttle in [-1, 1] as the PWM ArduPilot outputs for it."""
    return round(PWM_TRIM + PWM_SPAN * max(-1.0, min(1.0, throttle)))


class BunkerSim(ArduRoverSim):
    """ArduRover (MAV_TYPE_GROUND_ROVER) on a tracked, skid-steered base."""

    vehicle: SkidSteerVehicle
    SKID_STEERING = True
    #: ArduRover's defaults, with WP_SPEED set for the Bunker's 1.5 m/s tracks (the firmware's 2 m/s is beyond them).
    #: SERVO1_FUNCTION 73 and SERVO3_FUNCTION 74: the skid-steer frame's ThrottleLeft and ThrottleRight.
    PARAMS: ClassVar[Mapping[str, float]] = {
        **ArduRoverSim.PARAMS, "WP_SPEED": 1.0, "CRUISE_SPEED": 1.0, "SERVO1_FUNCTION": 73.0, "SERVO3_FUNCTION": 74.0,
    }  # fmt: skip

    @property
    def base_limits(self) -> MotionLimits:
        return BUNKER_LIMITS

    @property
    def response(self) -> Mapping[str, float]:
        return BUNKER_RESPONSE

    def _vehicle_model(self, home: Home, limits: MotionLimits) -> SkidSteerVehicle:
        return SkidSteerVehicle(home[0], home[1], home[2], limits)

    @property
    def track_pwm(self) -> tuple[int, int]:
        """SERVO1 (left track) and SERVO3 (right track) in microseconds."""
        left, right = self.vehicle.track_throttles
        return throttle_pwm(left), throttle_pwm(right)

    @property
    def battery_v(self) -> float:
        """The battery's voltage now, as SYS_STATUS reports it (for the base's 0x211)."""
        return self.battery.voltage_v

    def _servo_outputs(self) -> Sequence[int]:
        outputs = [0] * 16
        outputs[0], outputs[2] = self.track_pwm
        return outputs
