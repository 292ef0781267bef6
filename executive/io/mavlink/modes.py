"""Flight-mode tables: names <-> the numbers each autopilot firmware uses.

ArduPilot numbers its modes per vehicle firmware (Rover, Sub, Plane). PX4 packs a main mode and a
sub mode into ``custom_mode`` (bits 16-23 and 24-31). Trees name modes the ArduPilot way; on PX4
the nearest equivalent is used (``GUIDED`` is ``OFFBOARD``, ``HOLD`` is ``AUTO.LOITER``...).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

from executive.world.dialect import mavlink, mavutil
from executive.world.vehicles import profile_for_mav_type


class ModeTable(Protocol):
    """How one firmware names and numbers its modes."""

    def encode(self, mode: str | int) -> tuple[float, float]:
        """DO_SET_MODE param2 and param3 for a mode name (wins) or number; KeyError if unknown."""
        ...

    def decode(self, custom_mode: int) -> str:
        """The name of a HEARTBEAT ``custom_mode``."""
        ...

    def canonical(self, mode: str) -> str:
        """The name this firmware reports for a mode the trees call ``mode``."""
        ...


class ArduPilotModes:
    """One ArduPilot firmware's mode numbers."""

    def __init__(self, table: Mapping[str, int]) -> None:
        self._by_name = dict(table)
        self._by_number = {v: k for k, v in table.items()}

    def encode(self, mode: str | int) -> tuple[float, float]:
        if isinstance(mode, str):
            return float(self._by_name[mode.upper()]), 0.0
        if mode not in self._by_number:
            raise KeyError(mode)
        return float(mode), 0.0

    def decode(self, custom_mode: int) -> str:
        return self._by_number.get(custom_mode, f"MODE({custom_mode})")

    def canonical(self, mode: str) -> str:
        return mode.upper()


def _px4(main: int, sub: int = 0) -> int:
    return (main << 16) | (sub << 24)


#: AUTO's precision landing, which pymavlink does not name (PX4 src/modules/commander/px4_custom_mode.h PX4_CUSTOM_SUB_MODE_AUTO_PRECLAND).
_AUTO_PRECLAND = 9


def _px4_number(name: str) -> int:
    """``POSCTL`` -> its main mode's ``custom_mode``; ``AUTO.LOITER`` -> AUTO's with its sub mode (pymavlink's PX4_CUSTOM_* numbers)."""
    main, _, sub = name.partition(".")
    if not sub:
        return _px4(getattr(mavutil, f"PX4_CUSTOM_MAIN_MODE_{main}"))
    return _px4(mavutil.PX4_CUSTOM_MAIN_MODE_AUTO, _AUTO_PRECLAND if sub == "PRECLAND" else getattr(mavutil, f"PX4_CUSTOM_SUB_MODE_AUTO_{sub}"))


#: PX4 modes, by the names QGroundControl shows (main mode, or main.sub for AUTO).
PX4_MODES: dict[str, int] = {
    name: _px4_number(name)
    for name in (
        "MANUAL", "ALTCTL", "POSCTL", "AUTO.READY", "AUTO.TAKEOFF", "AUTO.LOITER", "AUTO.MISSION", "AUTO.RTL", "AUTO.LAND",
        "AUTO.FOLLOW_TARGET", "AUTO.PRECLAND", "ACRO", "OFFBOARD", "STABILIZED", "RATTITUDE",
    )
}  # fmt: skip

#: ArduPilot mode names the trees use -> the PX4 mode that does the same job.
PX4_EQUIVALENTS: dict[str, str] = {
    "GUIDED": "OFFBOARD", "HOLD": "AUTO.LOITER", "LOITER": "AUTO.LOITER", "QLOITER": "AUTO.LOITER", "POSHOLD": "AUTO.LOITER",
    "AUTO": "AUTO.MISSION", "RTL": "AUTO.RTL", "QRTL": "AUTO.RTL", "QLAND": "AUTO.LAND", "LAND": "AUTO.LAND",
    "TAKEOFF": "AUTO.TAKEOFF", "QHOVER": "POSCTL", "QSTABILIZE": "STABILIZED", "ALT_HOLD": "ALTCTL",
}  # fmt: skip


class Px4Modes:
    """PX4's main/sub modes."""

    def __init__(self) -> None:
        self._by_number = {v: k for k, v in PX4_MODES.items()}

    def encode(self, mode: str | int) -> tuple[float, float]:
        number = PX4_MODES[self.canonical(mode)] if isinstance(mode, str) else mode
        if number not in self._by_number:
            raise KeyError(mode)
        return float((number >> 16) & 0xFF), float((number >> 24) & 0xFF)

    def decode(self, custom_mode: int) -> str:
        return self._by_number.get(custom_mode, f"MODE({custom_mode >> 16 & 0xFF}.{custom_mode >> 24 & 0xFF})")

    def canonical(self, mode: str) -> str:
        mode = mode.upper()
        return PX4_EQUIVALENTS.get(mode, mode)


def mode_table(autopilot: int, mav_type: int) -> ModeTable:
    """The mode table for an autopilot seen in a HEARTBEAT (``autopilot``, ``type``).

    An ArduPilot vehicle of a kind we have no table for gets an empty one: its modes show as
    ``MODE(n)`` and cannot be requested by name.
    """
    if autopilot == mavlink.MAV_AUTOPILOT_PX4:
        return Px4Modes()
    profile = profile_for_mav_type(mav_type)
    return ArduPilotModes(profile.modes if profile else {})
