"""The AgileX protocol v2 frames the executive reads and writes (Bunker, and Scout/Tracer/Hunter alike).

Standard 11-bit ids at 500 kbit/s; multi-byte fields are big-endian ("MOTOROLA format").

=====  ===  =============================================================================================
id     dir  bytes
=====  ===  =============================================================================================
0x111  out  motion command: [0-1] int16 linear mm/s, [2-3] int16 angular 0.001 rad/s, [4-7] 0 (lateral,
            steering: not used by a skid-steer base)
0x211  in   system state: [0] vehicle state (0 normal, 1 e-stop, 2 exception), [1] control mode (0 RC,
            1 CAN command, 2 UART), [2-3] uint16 battery 0.1 V, [4-5] uint16 fault code (bits below),
            [6] reserved, [7] rolling counter
0x221  in   motion state: [0-1] int16 linear mm/s, [2-3] int16 angular 0.001 rad/s, [4-7] lateral and
            steering (not used by a skid-steer base)
0x241  in   RC state: [0] switches, 2 bits each (SWA bits 0-1: 2 up 3 down; SWB bits 2-3 and SWC bits 4-5:
            2 up 1 middle 3 down; SWD bits 6-7: 2 up 3 down), [1-4] int8 sticks right L/R, right U/D,
            left L/R, left U/D in [-100, 100], [5] int8 knob VRA in [-100, 100], [6] reserved, [7] rolling
            counter
0x311  in   odometry: [0-3] int32 left track mm, [4-7] int32 right track mm
0x421  out  control mode select: [0] 0x01 = CAN command mode (0x00 = standby/RC), [1-7] 0
=====  ===  =============================================================================================

Fault code bits (0x211): 0x0001 battery under-voltage fault, 0x0002 battery under-voltage warning,
0x0004 RC signal loss, 0x0008..0x0040 motor 1..4 communication, 0x0100 motor driver, 0x0200
high-level communication. ugv_sdk 1.x (the version the Bunker thesis modified) read byte 4 alone as
the fault code, which puts RC signal loss at 0x0400 of the 16-bit value: both bits mean RC signal loss.

:func:`decode` never raises: a frame it cannot read is ``None`` (unknown id, wrong length, remote or
extended frame) or comes back with ``valid`` False (values out of the protocol's range); callers
count both with :class:`FrameStats`.
"""

from __future__ import annotations

import logging
import struct
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, ClassVar, Self

import can

from executive.world.state import SwitchPosition

log = logging.getLogger(__name__)

MOTION_COMMAND_ID = 0x111
SYSTEM_STATE_ID = 0x211
MOTION_STATE_ID = 0x221
RC_STATE_ID = 0x241
ODOMETRY_ID = 0x311
CONTROL_MODE_SELECT_ID = 0x421

CONTROL_MODE_RC = 0x00
CONTROL_MODE_CAN = 0x01
CONTROL_MODE_UART = 0x02

STICK_MIN, STICK_MAX = -100, 100
INT16_MIN, INT16_MAX = -32768, 32767

VEHICLE_STATES = {0x00: "NORMAL", 0x01: "ESTOP", 0x02: "EXCEPTION"}
CONTROL_MODES = {CONTROL_MODE_RC: "RC", CONTROL_MODE_CAN: "CAN", CONTROL_MODE_UART: "UART"}

#: 0x211 fault code bit -> name.
FAULT_BITS: dict[int, str] = {
    0x0001: "BATTERY_LOW_FAULT",
    0x0002: "BATTERY_LOW_WARNING",
    0x0004: "RC_SIGNAL_LOSS",
    0x0008: "MOTOR1_COMM",
    0x0010: "MOTOR2_COMM",
    0x0020: "MOTOR3_COMM",
    0x0040: "MOTOR4_COMM",
    0x0080: "STEER_ENCODER",
    0x0100: "MOTOR_DRIVER",
    0x0200: "HIGH_LEVEL_COMM",
    0x0400: "RC_SIGNAL_LOSS",  # ugv_sdk 1.x layout: byte 4 = 0x04
}
RC_SIGNAL_LOSS_BITS = 0x0004 | 0x0400

_UP, _MIDDLE, _DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN
_TWO_WAY = {2: _UP, 3: _DOWN}
_THREE_WAY = {2: _UP, 1: _MIDDLE, 3: _DOWN}
_CODES = {_UP: 2, _MIDDLE: 1, _DOWN: 3}

_RC = struct.Struct(">B5bxB")
_SYSTEM = struct.Struct(">BBHHxB")
_SPEEDS = struct.Struct(">hh4x")  # 0x221 and 0x111
_ODOMETRY = struct.Struct(">ii")


def _message(arbitration_id: int, data: bytes) -> can.Message:
    return can.Message(arbitration_id=arbitration_id, data=data, is_extended_id=False)


def _fields_text(names: dict[int, str], value: int) -> str:
    return names.get(value, f"UNKNOWN({value})")


@dataclass(frozen=True, slots=True)
class RcState:
    """0x241: the RC transmitter as the base receives it. A switch with a code it cannot have is None."""

    ID: ClassVar[int] = RC_STATE_ID
    KIND: ClassVar[str] = "rc"

    swa: SwitchPosition | None
    swb: SwitchPosition | None
    swc: SwitchPosition | None
    swd: SwitchPosition | None
    right_lr: int
    right_ud: int
    left_lr: int
    left_ud: int
    knob: int  # VRA
    counter: int

    @property
    def valid(self) -> bool:
        switches_known = None not in (self.swa, self.swb, self.swc, self.swd)
        return switches_known and all(STICK_MIN <= v <= STICK_MAX for v in (self.right_lr, self.right_ud, self.left_lr, self.left_ud, self.knob))

    @classmethod
    def from_data(cls, data: bytes) -> RcState | None:
        if len(data) != 8:
            return None
        sws, right_lr, right_ud, left_lr, left_ud, knob, counter = _RC.unpack(data)
        return cls(
            _TWO_WAY.get(sws & 3),
            _THREE_WAY.get(sws >> 2 & 3),
            _THREE_WAY.get(sws >> 4 & 3),
            _TWO_WAY.get(sws >> 6 & 3),
            right_lr,
            right_ud,
            left_lr,
            left_ud,
            knob,
            counter,
        )

    def encode(self) -> can.Message:
        """The frame (for simulators and tests); ValueError for a switch position the switch does not have."""
        for name, position, two_way in (("SWA", self.swa, True), ("SWB", self.swb, False), ("SWC", self.swc, False), ("SWD", self.swd, True)):
            if position is None or (two_way and position is _MIDDLE):
                raise ValueError(f"{name} cannot be {position}")
        sws = _CODES[self.swa] | _CODES[self.swb] << 2 | _CODES[self.swc] << 4 | _CODES[self.swd] << 6  # type: ignore[index]
        return _message(self.ID, _RC.pack(sws, self.right_lr, self.right_ud, self.left_lr, self.left_ud, self.knob, self.counter))

    def describe(self) -> str:
        def pos(p: SwitchPosition | None) -> str:
            return p.value if p is not None else "?"

        return (
            f"RC SWA={pos(self.swa)} SWB={pos(self.swb)} SWC={pos(self.swc)} SWD={pos(self.swd)} "
            f"right=({self.right_lr},{self.right_ud}) left=({self.left_lr},{self.left_ud}) VRA={self.knob} counter={self.counter}"
        )

    def fields(self) -> dict[str, Any]:
        switches = {n: (p.value if p is not None else None) for n, p in (("swa", self.swa), ("swb", self.swb), ("swc", self.swc), ("swd", self.swd))}
        sticks = {"right_lr": self.right_lr, "right_ud": self.right_ud, "left_lr": self.left_lr, "left_ud": self.left_ud}
        return switches | sticks | {"knob": self.knob, "counter": self.counter}


@dataclass(frozen=True, slots=True)
class SystemState:
    """0x211: vehicle state, control mode, battery voltage and fault code of the base."""

    ID: ClassVar[int] = SYSTEM_STATE_ID
    KIND: ClassVar[str] = "system"

    vehicle_state: int
    control_mode: int
    battery_dv: int  # 0.1 V
    fault_code: int
    counter: int

    @property
    def valid(self) -> bool:
        return self.vehicle_state in VEHICLE_STATES and self.control_mode in CONTROL_MODES

    @property
    def battery_v(self) -> float:
        return self.battery_dv / 10.0

    @property
    def faults(self) -> tuple[str, ...]:
        """Names of the fault bits set, in bit order (unknown bits as BIT<n>), each once."""
        names = [FAULT_BITS.get(1 << bit, f"BIT{bit}") for bit in range(16) if self.fault_code >> bit & 1]
        return tuple(dict.fromkeys(names))

    @property
    def rc_signal_lost(self) -> bool:
        return bool(self.fault_code & RC_SIGNAL_LOSS_BITS)

    @classmethod
    def from_data(cls, data: bytes) -> SystemState | None:
        if len(data) != 8:
            return None
        return cls(*_SYSTEM.unpack(data))

    def encode(self) -> can.Message:
        return _message(self.ID, _SYSTEM.pack(self.vehicle_state, self.control_mode, self.battery_dv, self.fault_code, self.counter))

    def describe(self) -> str:
        faults = ",".join(self.faults) or "none"
        return (
            f"SYSTEM state={_fields_text(VEHICLE_STATES, self.vehicle_state)} mode={_fields_text(CONTROL_MODES, self.control_mode)} "
            f"battery={self.battery_v:.1f}V faults={faults} (0x{self.fault_code:04X}) counter={self.counter}"
        )

    def fields(self) -> dict[str, Any]:
        return {
            "vehicle_state": _fields_text(VEHICLE_STATES, self.vehicle_state),
            "control_mode": _fields_text(CONTROL_MODES, self.control_mode),
            "battery_v": self.battery_v,
            "fault_code": self.fault_code,
            "faults": list(self.faults),
            "counter": self.counter,
        }


@dataclass(frozen=True, slots=True)
class _Speeds:
    """A linear (mm/s) and angular (0.001 rad/s) speed pair, int16 big-endian: what 0x221 reports and 0x111 commands."""

    ID: ClassVar[int]
    KIND: ClassVar[str]
    LABEL: ClassVar[str]

    linear_mm_s: int
    angular_mrad_s: int

    valid: ClassVar[bool] = True  # every int16 pair is a speed

    @property
    def linear_m_s(self) -> float:
        return self.linear_mm_s / 1000.0

    @property
    def angular_rad_s(self) -> float:
        return self.angular_mrad_s / 1000.0

    @classmethod
    def from_data(cls, data: bytes) -> Self | None:
        return cls(*_SPEEDS.unpack(data)) if len(data) == 8 else None

    def encode(self) -> can.Message:
        return _message(self.ID, _SPEEDS.pack(self.linear_mm_s, self.angular_mrad_s))

    def describe(self) -> str:
        return f"{self.LABEL} linear={self.linear_m_s:+.3f}m/s angular={self.angular_rad_s:+.3f}rad/s"

    def fields(self) -> dict[str, Any]:
        return {"linear_m_s": self.linear_m_s, "angular_rad_s": self.angular_rad_s}


@dataclass(frozen=True, slots=True)
class MotionState(_Speeds):
    """0x221: the speed the base measures."""

    ID: ClassVar[int] = MOTION_STATE_ID
    KIND: ClassVar[str] = "motion"
    LABEL: ClassVar[str] = "MOTION"


@dataclass(frozen=True, slots=True)
class Odometry:
    """0x311: distance each track has run since the base started, mm."""

    ID: ClassVar[int] = ODOMETRY_ID
    KIND: ClassVar[str] = "odometry"

    left_mm: int
    right_mm: int

    valid: ClassVar[bool] = True

    @classmethod
    def from_data(cls, data: bytes) -> Odometry | None:
        return cls(*_ODOMETRY.unpack(data)) if len(data) == 8 else None

    def encode(self) -> can.Message:
        return _message(self.ID, _ODOMETRY.pack(self.left_mm, self.right_mm))

    def describe(self) -> str:
        return f"ODOMETRY left={self.left_mm / 1000:.3f}m right={self.right_mm / 1000:.3f}m"

    def fields(self) -> dict[str, Any]:
        return {"left_m": self.left_mm / 1000.0, "right_m": self.right_mm / 1000.0}


@dataclass(frozen=True, slots=True)
class MotionCommand(_Speeds):
    """0x111: the speed the base is told to drive at."""

    ID: ClassVar[int] = MOTION_COMMAND_ID
    KIND: ClassVar[str] = "command"
    LABEL: ClassVar[str] = "COMMAND"

    @classmethod
    def from_si(cls, linear_m_s: float, angular_rad_s: float) -> MotionCommand:
        """Rounded to the protocol's mm/s and 0.001 rad/s; ValueError beyond int16."""
        linear, angular = round(linear_m_s * 1000.0), round(angular_rad_s * 1000.0)
        if not (INT16_MIN <= linear <= INT16_MAX and INT16_MIN <= angular <= INT16_MAX):
            raise ValueError(f"motion command out of range: {linear_m_s} m/s, {angular_rad_s} rad/s")
        return cls(linear, angular)


@dataclass(frozen=True, slots=True)
class ControlModeSelect:
    """0x421: which interface commands the base (0x01 = CAN command mode); the base wants it repeated (500 ms timeout)."""

    ID: ClassVar[int] = CONTROL_MODE_SELECT_ID
    KIND: ClassVar[str] = "mode_select"

    mode: int = CONTROL_MODE_CAN

    @property
    def valid(self) -> bool:
        return self.mode in CONTROL_MODES

    @classmethod
    def from_data(cls, data: bytes) -> ControlModeSelect | None:
        return cls(data[0]) if 1 <= len(data) <= 8 else None  # the manuals say 1 byte, ugv_sdk sends 8

    def encode(self) -> can.Message:
        return _message(self.ID, bytes([self.mode, 0, 0, 0, 0, 0, 0, 0]))

    def describe(self) -> str:
        return f"MODE_SELECT mode={_fields_text(CONTROL_MODES, self.mode)}"

    def fields(self) -> dict[str, Any]:
        return {"mode": _fields_text(CONTROL_MODES, self.mode)}


Frame = RcState | SystemState | MotionState | Odometry | MotionCommand | ControlModeSelect

_BY_ID: dict[int, Any] = {cls.ID: cls for cls in (RcState, SystemState, MotionState, Odometry, MotionCommand, ControlModeSelect)}
KNOWN_IDS: frozenset[int] = frozenset(_BY_ID)


#: Decoder failures already logged, by frame id and exception: each kind is said once, then only counted as bad frames.
_FAILURES_SAID: set[tuple[object, type[BaseException]]] = set()


def decode(msg: can.Message) -> Frame | None:
    """The AgileX frame ``msg`` carries; None for anything else. Never raises; a decoder that does is logged once per kind."""
    try:
        if msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
            return None
        cls = _BY_ID.get(msg.arbitration_id)
        return None if cls is None else cls.from_data(bytes(msg.data))
    except Exception as exc:  # a boundary: nothing a bus delivers may crash the executive, and a decoder bug is not a bad frame
        frame_id = getattr(msg, "arbitration_id", None)
        if (frame_id, type(exc)) not in _FAILURES_SAID:
            _FAILURES_SAID.add((frame_id, type(exc)))
            where = f"0x{frame_id:03X}" if isinstance(frame_id, int) else repr(frame_id)
            log.error("CAN frame %s: the AgileX decoder raised %s (counted as a bad frame; said once)", where, type(exc).__name__, exc_info=exc)
        return None


def is_agilex(msg: can.Message) -> bool:
    """An 11-bit data frame with an id this module knows (whether or not its content is usable)."""
    try:
        return not (msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame) and msg.arbitration_id in KNOWN_IDS
    except Exception:
        return False


@dataclass
class FrameStats:
    """Frames seen, per id; AgileX frames that could not be used (bad); frames of other ids (other)."""

    frames: int = 0
    bad: int = 0
    other: int = 0
    per_id: Counter[int] = field(default_factory=Counter)

    def record(self, msg: can.Message, frame: Frame | None) -> bool:
        """Count one frame and its decoding; True when the frame is usable."""
        self.frames += 1
        self.per_id[msg.arbitration_id] += 1
        if frame is not None:
            if frame.valid:
                return True
            self.bad += 1
        elif is_agilex(msg):
            self.bad += 1
        else:
            self.other += 1
        return False
