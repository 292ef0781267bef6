"""The drive bridge: the autopilot's skid-steer outputs, sent to the AgileX base as motion commands.

ArduRover's skid-steer frame drives the left track from SERVO1 and the right from SERVO3
(/vehicle/servo_outputs, SERVO_OUTPUT_RAW). Each output maps onto [-1, 1]: 900..2100 µs around
1500 µs, clamped. Then, as the thesis's ``rcout_to_cmd_vel`` node does:

- linear  = (left + right) / 2 x ``linear_m_s``  (m/s at full throttle on both tracks; default 1.0)
- angular = (right - left)     x ``angular_rad_s`` (rad/s per unit of track difference; default 1.0,
  so a pivot turn with the tracks at -1/+1 asks for 2 rad/s; positive = counter-clockwise)

Every 1/``rate_hz`` s (50 Hz) of the injected clock :meth:`DriveBridge.service` sends a 0x421
control-mode select (CAN command mode; the base drops out of it after 500 ms without one, so it
goes before every command, as AgileX's ugv_sdk does) and then the 0x111 motion command. The
command is ZERO motion while the executive is not in control (:attr:`DriveBridge.in_control`,
set by the runtime), the autopilot is disarmed, or the servo outputs are missing or older than
``servo_timeout_s``.

/vehicle/servo_outputs carries no time of its own: the MAVLink reader puts a new tuple on the
blackboard for every SERVO_OUTPUT_RAW, so a new object there is a new report.
"""

from __future__ import annotations

import logging
import math
import threading
from dataclasses import dataclass

import can

from executive.io.can.agilex import INT16_MAX, ControlModeSelect, MotionCommand
from executive.io.can.state import DriveStatus
from executive.world import blackboard
from executive.world.clock import Clock

log = logging.getLogger(__name__)

PWM_NEUTRAL_US = 1500
PWM_HALF_RANGE_US = 600  # 900..2100 µs = -1..1
PWM_VALID_MIN_US, PWM_VALID_MAX_US = 500, 2500  # beyond this (0 = output unused) the output says nothing

ZERO = MotionCommand(0, 0)


def track_throttle(pwm: int | None) -> float | None:
    """A servo output in [-1, 1]; None when there is no usable output."""
    if pwm is None or not PWM_VALID_MIN_US <= pwm <= PWM_VALID_MAX_US:
        return None
    return max(-1.0, min(1.0, (pwm - PWM_NEUTRAL_US) / PWM_HALF_RANGE_US))


@dataclass(frozen=True)
class DriveConfig:
    """How the autopilot's outputs become motion commands."""

    linear_m_s: float = 1.0  # speed factor: m/s with both tracks at full throttle
    angular_rad_s: float = 1.0  # speed factor: rad/s per unit of (right - left), which spans [-2, 2]
    rate_hz: float = 50.0
    servo_timeout_s: float = 0.5  # SERVO_OUTPUT_RAW older than this: zero motion
    left_servo: int = 1
    right_servo: int = 3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.linear_m_s) and 0.0 <= self.linear_m_s * 1000.0 <= INT16_MAX):
            raise ValueError(f"linear speed factor must be in [0, {INT16_MAX / 1000}] m/s, got {self.linear_m_s}")
        if not (math.isfinite(self.angular_rad_s) and 0.0 <= self.angular_rad_s * 2000.0 <= INT16_MAX):
            raise ValueError(f"angular speed factor must be in [0, {INT16_MAX / 2000}] rad/s, got {self.angular_rad_s}")
        if not (math.isfinite(self.rate_hz) and 0.0 < self.rate_hz <= 1000.0):
            raise ValueError(f"rate must be in (0, 1000] Hz, got {self.rate_hz}")
        if not (math.isfinite(self.servo_timeout_s) and self.servo_timeout_s > 0.0):
            raise ValueError(f"servo timeout must be > 0 s, got {self.servo_timeout_s}")
        if not (1 <= self.left_servo <= 16 and 1 <= self.right_servo <= 16):
            raise ValueError(f"servo numbers must be in 1..16, got {self.left_servo} and {self.right_servo}")


def motion_from_tracks(left: float, right: float, config: DriveConfig) -> MotionCommand:
    """The motion command for track throttles ``left`` and ``right`` in [-1, 1]."""
    return MotionCommand.from_si((left + right) / 2.0 * config.linear_m_s, (right - left) * config.angular_rad_s)


class DriveBridge:
    """Sends the base a motion command at ``config.rate_hz``: the autopilot's outputs when they may drive it, else zero."""

    def __init__(self, bus: can.BusABC, clock: Clock, config: DriveConfig | None = None) -> None:
        self._bus = bus
        self._clock = clock
        self.config = config or DriveConfig()
        self.period_s = 1.0 / self.config.rate_hz
        #: Set by the runtime: True while the executive drives the vehicle (else the base is held still).
        self.in_control = False
        self._in = blackboard.reader("drive bridge in", ["/vehicle/servo_outputs", "/vehicle/armed"])
        self._out = blackboard.writer("drive bridge", ["/base/drive", "/base/send_errors"])
        self._next_due: float | None = None
        self._seen_outputs: object = None  # the blackboard's object: a new one is a new report
        self._outputs: tuple[int, ...] | None = None
        self._outputs_time: float | None = None
        self.sent = 0
        self.send_errors = 0

    @property
    def next_due(self) -> float:
        """Clock time the next command is due (now, before the first)."""
        return self._clock.now() if self._next_due is None else self._next_due

    def service(self) -> bool:
        """Send the next command if it is due (never blocks or sleeps); True when one was sent."""
        now = self._clock.now()
        self._note_outputs(now)
        if self._next_due is not None and now < self._next_due:
            return False
        # keep the cadence; after a stall (more than a period late) restart it instead of sending a burst
        self._next_due = now + self.period_s if self._next_due is None or now - self._next_due >= self.period_s else self._next_due + self.period_s
        command, reason = self.command(now)
        if self._send(ControlModeSelect().encode()) and self._send(command.encode()):
            self.sent += 1
        status: DriveStatus | None = self._out.get("/base/drive")
        if status is None or (status.linear_m_s, status.angular_rad_s, status.reason) != (command.linear_m_s, command.angular_rad_s, reason):
            self._out.set("/base/drive", DriveStatus(command.linear_m_s, command.angular_rad_s, reason, now))
        return True

    def command(self, now: float) -> tuple[MotionCommand, str]:
        """The motion command to send now, and why it is zero ("" when the autopilot drives)."""
        if not self.in_control:
            return ZERO, "executive not in control"
        if not self._in.get("/vehicle/armed"):
            return ZERO, "disarmed"
        if self._outputs is None or self._outputs_time is None:
            return ZERO, "no servo outputs yet"
        if now - self._outputs_time > self.config.servo_timeout_s:
            return ZERO, f"servo outputs older than {self.config.servo_timeout_s:g} s"
        left = track_throttle(self._output(self.config.left_servo))
        right = track_throttle(self._output(self.config.right_servo))
        if left is None or right is None:
            return ZERO, f"no usable servo {self.config.left_servo if left is None else self.config.right_servo} output"
        return motion_from_tracks(left, right, self.config), ""

    def run(self, stop: threading.Event) -> None:
        """Serve until ``stop`` is set: for a thread of its own, when the runtime's tick is slower than the bridge's rate."""
        while not stop.is_set():
            self.service()
            self._clock.sleep_until(self.next_due)

    def _output(self, servo: int) -> int | None:
        outputs = self._outputs or ()
        return outputs[servo - 1] if len(outputs) >= servo else None

    def _note_outputs(self, now: float) -> None:
        outputs = self._in.get("/vehicle/servo_outputs")
        if outputs and outputs is not self._seen_outputs:
            self._seen_outputs = outputs
            self._outputs, self._outputs_time = tuple(outputs), now

    def _send(self, msg: can.Message) -> bool:
        try:
            self._bus.send(msg)
            return True
        except Exception as exc:  # a full buffer or a bus-off raises CanOperationError / OSError: drop it, the next one is 20 ms away
            self.send_errors += 1
            if self.send_errors == 1 or self.send_errors % 100 == 0:
                log.warning("CAN send failed (%d so far): %s", self.send_errors, exc)
            self._out.set("/base/send_errors", self.send_errors)
            return False
