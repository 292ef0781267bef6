"""Vehicle kinds: their ArduPilot firmware, mode numbers and the mode that makes them safe."""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

from executive.world.dialect import mavlink

VehicleKind = Literal["rover", "boat", "sub", "vtol"]

#: ArduRover (rover and boat frames) custom modes.
ROVER_MODES = MappingProxyType({
    "MANUAL": 0, "ACRO": 1, "STEERING": 3, "HOLD": 4, "LOITER": 5, "FOLLOW": 6, "SIMPLE": 7,
    "DOCK": 8, "CIRCLE": 9, "AUTO": 10, "RTL": 11, "SMART_RTL": 12, "GUIDED": 15, "INITIALISING": 16,
})  # fmt: skip

#: ArduSub custom modes.
SUB_MODES = MappingProxyType({
    "STABILIZE": 0, "ACRO": 1, "ALT_HOLD": 2, "AUTO": 3, "GUIDED": 4, "CIRCLE": 7, "SURFACE": 9,
    "POSHOLD": 16, "MANUAL": 19, "MOTOR_DETECT": 20, "SURFTRAK": 21,
})  # fmt: skip

#: ArduPlane (QuadPlane) custom modes.
PLANE_MODES = MappingProxyType({
    "MANUAL": 0, "CIRCLE": 1, "STABILIZE": 2, "TRAINING": 3, "ACRO": 4, "FBWA": 5, "FBWB": 6,
    "CRUISE": 7, "AUTOTUNE": 8, "AUTO": 10, "RTL": 11, "LOITER": 12, "TAKEOFF": 13, "AVOID_ADSB": 14,
    "GUIDED": 15, "INITIALISING": 16, "QSTABILIZE": 17, "QHOVER": 18, "QLOITER": 19, "QLAND": 20,
    "QRTL": 21, "QAUTOTUNE": 22, "QACRO": 23, "THERMAL": 24, "LOITER_ALT_QLAND": 25,
})  # fmt: skip


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
