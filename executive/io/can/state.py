"""Immutable values the CAN reader and the drive bridge put on the blackboard (``/base/*``, ``/rc/sticks``).

Like :mod:`executive.world.state`: replaced whole, stamped with the executive clock time they were received at.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class RcSticks:
    """The AgileX transmitter's sticks (0x241), each in [-100, 100]."""

    right_lr: int
    right_ud: int
    left_lr: int
    left_ud: int
    time: float


@dataclass(frozen=True, slots=True)
class BaseSystem:
    """The base's system state (0x211)."""

    vehicle_state: str  # NORMAL, ESTOP, EXCEPTION
    control_mode: str  # RC, CAN, UART: who the base obeys
    battery_v: float
    fault_code: int
    faults: tuple[str, ...]  # names of the fault bits set, e.g. ("RC_SIGNAL_LOSS",)
    time: float


@dataclass(frozen=True, slots=True)
class BaseMotion:
    """The speed the base measures (0x221)."""

    linear_m_s: float
    angular_rad_s: float  # positive = counter-clockwise seen from above
    time: float


@dataclass(frozen=True, slots=True)
class BaseOdometry:
    """Distance each track has run since the base started (0x311), m."""

    left_m: float
    right_m: float
    time: float


@dataclass(frozen=True, slots=True)
class DriveStatus:
    """What the drive bridge sends the base (0x111) and, when it sends zero motion for a reason, why."""

    linear_m_s: float
    angular_rad_s: float
    reason: str  # empty while the autopilot's outputs are forwarded
    time: float  # when this command was first sent
