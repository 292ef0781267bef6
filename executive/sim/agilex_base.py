"""The AgileX Bunker's own controller on a CAN bus (protocol v2), for the simulated tracked UGV.

On the real vehicle the base, not the autopilot, drives the tracks: the executive's drive bridge
turns the autopilot's skid-steer outputs into 0x111 motion commands. :class:`SimulatedBase` closes
that loop in the simulator, serviced from the :class:`~executive.sim.server.SimServer` loop:

- sends 0x241 RC (50 Hz), 0x211 system state (10 Hz), 0x221 motion state and 0x311 odometry (50 Hz);
- the RC frame is the simulated transmitter: the autopilot's RC channels, one channel per switch as
  :class:`~executive.mission.model.SwitchChannels` says (defaults: SWA 5, SWB 6, SWC 7, SWD 8,
  knob VRA 9), sticks from channels 1-4 (mode 2: right L/R 1, right U/D 2, left U/D 3, left L/R 4,
  1000..2000 µs = -100..100); its rolling counter counts each frame;
- during an ``rc_loss`` fault it keeps repeating the last RC frame, counter frozen, and in CAN
  mode reports no fault (the thesis's field finding); in RC mode 0x211 carries RC signal loss;
- CAN command mode lasts while a 0x421 select (0x01) has come within 500 ms; then the tracks
  follow the last 0x111 command (the base's own speed controller), or stop when none has come
  within 500 ms. In RC mode the autopilot's outputs drive the tracks, as without a base.

Not emulated: e-stop and exception states, motor faults, the low-battery bits, UART mode, driving
by the transmitter's sticks in RC mode, the base's lights and its other frames (0x251..0x2A1).
"""

from __future__ import annotations

import logging
from collections import Counter

import can

from executive.io.can.agilex import (
    CONTROL_MODE_CAN,
    CONTROL_MODE_RC,
    INT16_MAX,
    INT16_MIN,
    ControlModeSelect,
    MotionCommand,
    MotionState,
    Odometry,
    RcState,
    SystemState,
    decode,
)
from executive.mission.model import SwitchChannels
from executive.sensing.rc import knob_value, switch_position
from executive.sim.ardupilot.bunker import BunkerSim
from executive.sim.faults import BatterySag, FaultInjector, RcLoss
from executive.sim.firmware import FirmwareSim
from executive.world.clock import Clock
from executive.world.state import SwitchPosition

log = logging.getLogger(__name__)

RC_PERIOD_S = 0.02
SYSTEM_PERIOD_S = 0.1
MOTION_PERIOD_S = 0.02  # 0x221 and 0x311
MODE_TIMEOUT_S = 0.5  # CAN command mode lapses this long after the last 0x421
COMMAND_TIMEOUT_S = 0.5  # no 0x111 for this long: the base stops
RC_LOSS_FAULT = 0x0004
MAX_DRAIN = 1000  # frames handled per service: a flood cannot starve the base's own frames
_EPSILON_S = 1e-6


class _Cadence:
    """A fixed-rate schedule that never bursts: after a stall of more than a period it restarts."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self._next: float | None = None

    def due(self, now: float) -> bool:
        """True (and the next slot booked) when a frame is due at ``now``."""
        booked = self._next
        if booked is not None and now < booked - _EPSILON_S:
            return False
        self._next = now + self.period_s if booked is None or now - booked >= self.period_s else booked + self.period_s
        return True


def _clamp(value: int, low: int, high: int) -> int:
    return max(low, min(high, value))


def _stick(pwm: int) -> int:
    """An RC channel as an AgileX stick value in [-100, 100]; 0 (no channel) is centred."""
    return 0 if not pwm else _clamp(round((pwm - 1500) / 5), -100, 100)


def _switch(pwm: int, two_way: bool) -> SwitchPosition:
    position = switch_position(pwm) or SwitchPosition.UP  # 0: no channel; the transmitter's switch is somewhere
    return SwitchPosition.UP if two_way and position is SwitchPosition.MIDDLE else position


def _int32(value: int) -> int:
    """Wrapped as the base's 32-bit odometry counter wraps."""
    return (value + 2**31) % 2**32 - 2**31


class SimulatedBase:
    """The Bunker's controller on ``bus``: call :meth:`service` often (under the server's lock, after the autopilot's update).

    ``faults`` (the server's injector) tells it when the transmitter is lost and the battery sags.
    The caller owns ``bus`` (and shuts it down).
    """

    def __init__(
        self,
        bus: can.BusABC,
        clock: Clock,
        autopilot: FirmwareSim,
        *,
        faults: FaultInjector | None = None,
        switch_channels: SwitchChannels | None = None,
    ) -> None:
        if not isinstance(autopilot, BunkerSim):
            raise ValueError(f"a simulated AgileX base needs the bunker (tracked, skid-steered), not {type(autopilot).__name__}")
        self._bus = bus
        self._clock = clock
        self.autopilot: BunkerSim = autopilot
        self.faults = faults
        self.switch_channels = switch_channels or SwitchChannels()
        self._rc_due, self._system_due, self._motion_due = _Cadence(RC_PERIOD_S), _Cadence(SYSTEM_PERIOD_S), _Cadence(MOTION_PERIOD_S)
        self._rc_counter = 0  # the next 0x241 frame's
        self._system_counter = 0
        self._last_rc: RcState | None = None
        self._mode_select_time: float | None = None
        #: The last 0x111 received, and when.
        self.command: MotionCommand | None = None
        self.command_time: float | None = None
        self.received: Counter[int] = Counter()  # frames read, per id
        self.sent: Counter[int] = Counter()
        self.send_errors = 0

    # -- state -------------------------------------------------------------------------------------

    @property
    def control_mode(self) -> int:
        """CONTROL_MODE_CAN while 0x421 selects have kept coming, else CONTROL_MODE_RC."""
        t = self._mode_select_time
        return CONTROL_MODE_CAN if t is not None and self._clock.now() - t <= MODE_TIMEOUT_S + _EPSILON_S else CONTROL_MODE_RC

    @property
    def rc_lost(self) -> bool:
        """The receiver has lost the transmitter (an ``rc_loss`` fault in force)."""
        return self.faults is not None and any(isinstance(f, RcLoss) for f in self.faults.active())

    @property
    def drive_command(self) -> tuple[float, float] | None:
        """(linear m/s, angular rad/s) the base drives the tracks at now; None in RC mode (the autopilot's outputs drive them)."""
        if self.control_mode != CONTROL_MODE_CAN:
            return None
        if self.command is None or self.command_time is None or self._clock.now() - self.command_time > COMMAND_TIMEOUT_S + _EPSILON_S:
            return 0.0, 0.0
        return self.command.linear_m_s, self.command.angular_rad_s

    def rc_state(self) -> RcState:
        """The transmitter as the receiver sees it now (with the next counter value)."""
        ch = self.autopilot.rc_channels
        c = self.switch_channels

        def pwm(channel: int) -> int:
            return ch[channel - 1] if len(ch) >= channel else 0

        return RcState(
            swa=_switch(pwm(c.swa), two_way=True),
            swb=_switch(pwm(c.swb), two_way=False),
            swc=_switch(pwm(c.swc), two_way=False),
            swd=_switch(pwm(c.swd), two_way=True),
            right_lr=_stick(pwm(1)),
            right_ud=_stick(pwm(2)),
            left_lr=_stick(pwm(4)),
            left_ud=_stick(pwm(3)),
            knob=knob_value(pwm(c.knob)) or 0,
            counter=self._rc_counter,
        )

    # -- the loop ----------------------------------------------------------------------------------

    def service(self) -> None:
        """Read what the executive sent, set the tracks' command, send the frames now due. Never blocks."""
        now = self._clock.now()
        self._receive(now)
        self.autopilot.vehicle.base_command = self.drive_command
        if self._rc_due.due(now):
            self._send_rc()
        if self._system_due.due(now):
            self._send(SystemState(0, self.control_mode, self._battery_dv(), self._fault_code(), self._system_counter).encode())
            self._system_counter = (self._system_counter + 1) % 256
        if self._motion_due.due(now):
            vehicle = self.autopilot.vehicle
            linear = _clamp(round(vehicle.speed_m_s * 1000.0), INT16_MIN, INT16_MAX)
            angular = _clamp(round(-vehicle.yaw_rate_rad_s * 1000.0), INT16_MIN, INT16_MAX)  # the protocol's is counter-clockwise
            self._send(MotionState(linear, angular).encode())
            left, right = vehicle.odometry_m
            self._send(Odometry(_int32(round(left * 1000.0)), _int32(round(right * 1000.0))).encode())

    def _receive(self, now: float) -> None:
        for _ in range(MAX_DRAIN):
            try:
                msg = self._bus.recv(0.0)
            except Exception as exc:  # a bus going down: try again next service
                log.warning("simulated base: CAN read failed: %s", exc)
                return
            if msg is None:
                return
            frame = decode(msg)
            if frame is None or not frame.valid:
                continue
            self.received[msg.arbitration_id] += 1
            if isinstance(frame, ControlModeSelect):
                self._mode_select_time = now if frame.mode == CONTROL_MODE_CAN else None
            elif isinstance(frame, MotionCommand):
                self.command, self.command_time = frame, now

    def _send_rc(self) -> None:
        if self._last_rc is None or not self.rc_lost:
            self._last_rc = self.rc_state()
            self._rc_counter = (self._rc_counter + 1) % 256
        self._send(self._last_rc.encode())  # RC lost: the same frame again, counter and all

    def _battery_dv(self) -> int:
        volts = self.autopilot.battery_v
        if self.faults is not None:
            volts -= sum(f.drop_v for f in self.faults.active() if isinstance(f, BatterySag))
        return _clamp(round(volts * 10.0), 0, 0xFFFF)

    def _fault_code(self) -> int:
        # in CAN command mode the real base does not report an RC signal loss at all
        return RC_LOSS_FAULT if self.rc_lost and self.control_mode == CONTROL_MODE_RC else 0

    def _send(self, msg: can.Message) -> None:
        try:
            self._bus.send(msg)
        except Exception as exc:  # a full queue or a bus-off: the next frame is 20 ms away
            self.send_errors += 1
            if self.send_errors == 1 or self.send_errors % 100 == 0:
                log.warning("simulated base: CAN send failed (%d so far): %s", self.send_errors, exc)
            return
        self.sent[msg.arbitration_id] += 1
