"""Vehicle kinds: their ArduPilot firmware, mode numbers and the mode that makes them safe."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

from executive.world.dialect import mavlink, mavutil

VehicleKind = Literal["rover", "boat", "sub", "vtol"]


def _ardupilot_modes(
    mav_type: int, *, dropped: frozenset[str] = frozenset(), renamed: Mapping[str, str] | None = None, added: Mapping[str, int] | None = None
) -> MappingProxyType[str, int]:
    """pymavlink's table of an ArduPilot vehicle's custom modes, where the firmware's source differs corrected.

    pymavlink's built-in tables (what ``mavutil.mode_mapping_byname`` returns), not a ``~/.pymavlink/custom_mode_map.json``
    that function would take in: a file in someone's home directory does not change the number HOLD is asked by.
    """
    table = {(renamed or {}).get(name, name): number for number, name in mavutil.AP_MAV_TYPE_MODE_MAP_DEFAULT[mav_type].items()}
    return MappingProxyType({name: number for name, number in table.items() if name not in dropped} | dict(added or {}))


#: ArduRover (rover and boat frames) custom modes: pymavlink's, but LEARNING (2), gone from the firmware (Rover/mode.h Mode::Number).
ROVER_MODES = _ardupilot_modes(mavlink.MAV_TYPE_GROUND_ROVER, dropped=frozenset({"LEARNING"}))

#: ArduSub custom modes: pymavlink's, and the two it lacks (ArduSub/mode.h Mode::Number: MOTOR_DETECT 20, SURFTRAK 21).
SUB_MODES = _ardupilot_modes(mavlink.MAV_TYPE_SUBMARINE, added={"MOTOR_DETECT": 20, "SURFTRAK": 21})

#: ArduPlane (QuadPlane) custom modes: pymavlink's, mode 25 by the firmware's name (ArduPlane/mode.h LOITER_ALT_QLAND).
PLANE_MODES = _ardupilot_modes(mavlink.MAV_TYPE_VTOL_QUADROTOR, renamed={"LOITERALTQLAND": "LOITER_ALT_QLAND"})


@dataclass(frozen=True)
class VehicleProfile:
    """What the executive needs to know about one kind of vehicle."""

    kind: VehicleKind
    mav_type: int
    modes: MappingProxyType[str, int]
    safe_mode: str  # where Ctrl-C, a crash or the end of a mission leaves it
    guided_mode: str
    manual_mode: str
    surface: bool  # moves on a surface: vertical position values are meaningless
    #: Modes in which a person drives (sticks steer and set the throttle): no failsafe of the executive changes them.
    pilot_modes: frozenset[str] = frozenset()

    @property
    def aircraft(self) -> bool:
        """It flies (its HEARTBEAT type is a fixed wing or a VTOL): it reports a landed state (EXTENDED_SYS_STATE)."""
        return self.mav_type in _AIRCRAFT


#: ArduRover's pilot-driven modes (Rover/mode.h: MANUAL, ACRO, STEERING take the sticks' steering and throttle).
_ROVER_PILOT = frozenset({"MANUAL", "ACRO", "STEERING"})
#: ArduSub's modes in which the pilot steers (ALT_HOLD keeps the depth only).
_SUB_PILOT = frozenset({"MANUAL", "STABILIZE", "ACRO", "ALT_HOLD"})
#: ArduPlane's pilot-flown modes, wing-borne and on the lift motors.
_PLANE_PILOT = frozenset({"MANUAL", "STABILIZE", "TRAINING", "ACRO", "FBWA", "FBWB", "CRUISE", "QSTABILIZE", "QHOVER", "QACRO"})

PROFILES: MappingProxyType[str, VehicleProfile] = MappingProxyType({
    "rover": VehicleProfile("rover", mavlink.MAV_TYPE_GROUND_ROVER, ROVER_MODES, "HOLD", "GUIDED", "MANUAL", True, _ROVER_PILOT),
    "boat": VehicleProfile("boat", mavlink.MAV_TYPE_SURFACE_BOAT, ROVER_MODES, "LOITER", "GUIDED", "MANUAL", True, _ROVER_PILOT),
    "sub": VehicleProfile("sub", mavlink.MAV_TYPE_SUBMARINE, SUB_MODES, "POSHOLD", "GUIDED", "MANUAL", False, _SUB_PILOT),
    "vtol": VehicleProfile("vtol", mavlink.MAV_TYPE_VTOL_QUADROTOR, PLANE_MODES, "QLOITER", "GUIDED", "QSTABILIZE", False, _PLANE_PILOT),
})  # fmt: skip

_AIRCRAFT = frozenset({
    mavlink.MAV_TYPE_FIXED_WING, mavlink.MAV_TYPE_VTOL_QUADROTOR, mavlink.MAV_TYPE_VTOL_TILTROTOR, mavlink.MAV_TYPE_VTOL_RESERVED2,
})  # fmt: skip

_BY_MAV_TYPE = {
    mavlink.MAV_TYPE_GROUND_ROVER: "rover",
    mavlink.MAV_TYPE_SURFACE_BOAT: "boat",
    mavlink.MAV_TYPE_SUBMARINE: "sub",
    mavlink.MAV_TYPE_FIXED_WING: "vtol",
    mavlink.MAV_TYPE_VTOL_QUADROTOR: "vtol",
    mavlink.MAV_TYPE_VTOL_TILTROTOR: "vtol",
    mavlink.MAV_TYPE_VTOL_RESERVED2: "vtol",  # VTOL_FIXEDROTOR in today's MAVLink: PX4's standard VTOL (its HEARTBEAT's type 22)
}


#: Autopilot firmware -> the vehicle kinds it drives here. PX4 has VTOL and rover airframes; it has no ArduSub (a sub) and
#: no boat of ours (its rover modules drive wheels).
AutopilotName = Literal["ardupilot", "px4"]
AUTOPILOT_VEHICLES: MappingProxyType[str, frozenset[str]] = MappingProxyType(
    {"ardupilot": frozenset({"rover", "boat", "sub", "vtol"}), "px4": frozenset({"vtol", "rover"})}
)


def profile_for_mav_type(mav_type: int) -> VehicleProfile | None:
    """The profile matching a HEARTBEAT ``type``, if it is one of ours."""
    kind = _BY_MAV_TYPE.get(mav_type)
    return PROFILES[kind] if kind else None
