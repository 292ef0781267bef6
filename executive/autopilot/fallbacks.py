"""Which failsafe reaction follows one the autopilot will not take, per firmware and vehicle kind, from the firmware's source.

A reaction is a mode, named the way the trees name modes (``HOLD``; the PX4 back end maps it to
``AUTO.LOITER``), or :data:`DISARM`. Each has what it needs of the vehicle's present state that the
executive can see (a position estimate) and the reaction to ask for instead when it is refused
again and again, or cannot be entered at all in that state. A reaction with no next one is asked
again until the failsafe's time is up. The manual's failsafe table (docs/failsafes.md) is this table.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from types import MappingProxyType

from executive.mission.declaration import kind_spec
from executive.world.vehicles import profile_for_mav_type

#: Not a mode: disarm the vehicle (its motors stop).
DISARM = "DISARM"


@dataclass(frozen=True)
class Fallback:
    """One reaction: whether it needs a position estimate, the reaction after it (None: none), and the firmware's word for both."""

    needs_position: bool
    then: str | None
    why: str


_F = Fallback

# ArduRover (rover and boat frames).
# Rover/mode.h: Mode::requires_position() is true but for MANUAL, ACRO, STEERING and HOLD; Rover/mode.cpp Mode::enter refuses such a
# mode while armed unless ekf_position_ok() && !failsafe.ekf; Rover/mode_rtl.cpp ModeRTL::_enter also refuses without home.
# HOLD needs neither and FLTMODE_GCSBLOCK cannot block it (Rover/system.cpp gcs_mode_enabled's list). Last: a disarm, which stops the
# motors (Rover/AP_Arming_Rover.cpp disarm refuses only a rudder disarm while driving).
_ARDUROVER = MappingProxyType({
    "RTL": _F(True, "HOLD", "ArduRover RTL needs a position estimate and home (Rover/mode.cpp Mode::enter, Rover/mode_rtl.cpp)"),
    "LOITER": _F(True, "HOLD", "ArduRover LOITER needs a position estimate (Rover/mode.cpp Mode::enter)"),
    "HOLD": _F(False, DISARM, "ArduRover HOLD needs no position (Rover/mode.h); a disarm stops the motors (Rover/AP_Arming_Rover.cpp)"),
    DISARM: _F(False, None, "nothing after a disarm"),
})  # fmt: skip

# ArduSub. ArduSub/mode.h: POSHOLD (and GUIDED, AUTO, CIRCLE) requires_GPS; ArduSub/mode.cpp Sub::set_mode refuses it without
# Sub::position_ok() ("Mode change failed: %s requires position"; ArduSub/system.cpp: no position while its EKF failsafe is on).
# ALT_HOLD needs only the depth, SURFACE nothing. ArduSub/failsafe.cpp does the same steps itself: failsafe_terrain_act POSHOLD, else
# ALT_HOLD; failsafe_gcs_check ALT_HOLD or SURFACE refused -> disarm.
_ARDUSUB = MappingProxyType({
    "POSHOLD": _F(True, "ALT_HOLD", "ArduSub POSHOLD needs a position (ArduSub/mode.cpp Sub::set_mode); its own terrain failsafe "
                  "holds in ALT_HOLD instead (ArduSub/failsafe.cpp)"),
    "ALT_HOLD": _F(False, DISARM, "ArduSub's own GCS failsafe disarms when ALT_HOLD is refused (ArduSub/failsafe.cpp)"),
    "SURFACE": _F(False, DISARM, "ArduSub's own GCS failsafe disarms when SURFACE is refused (ArduSub/failsafe.cpp)"),
    DISARM: _F(False, None, "nothing after a disarm"),
})  # fmt: skip

# ArduPlane QuadPlane. No mode needs a position to be entered (ArduPlane/system.cpp Plane::set_mode, ArduPlane/mode.cpp Mode::enter);
# refusals come from a fence recovery, FLTMODE_GCSBLOCK or Q_ENABLE 0. Its own failsafes (ArduPlane/events.cpp failsafe_short_on_event,
# failsafe_long_on_event) put a hovering QuadPlane in QLAND and a plane flying in GUIDED or LOITER in CIRCLE, which needs no position
# (ArduPlane/mode_circle.cpp). Never a disarm: it would drop the vehicle.
_ARDUPLANE = MappingProxyType({
    "QLOITER": _F(False, "QLAND", "ArduPlane's own failsafe lands a hovering QuadPlane in QLAND (ArduPlane/events.cpp)"),
    "QRTL": _F(False, "QLAND", "ArduPlane's own failsafe lands a hovering QuadPlane in QLAND (ArduPlane/events.cpp)"),
    "QLAND": _F(False, None, "QLAND is ArduPlane's last hovering failsafe (ArduPlane/events.cpp)"),
    "LOITER": _F(False, "CIRCLE", "ArduPlane's own failsafe circles a plane in CIRCLE, no position needed (ArduPlane/events.cpp, "
                 "ArduPlane/mode_circle.cpp)"),
    "RTL": _F(False, "CIRCLE", "ArduPlane's own failsafe circles a plane in CIRCLE, no position needed (ArduPlane/events.cpp, "
              "ArduPlane/mode_circle.cpp)"),
    "CIRCLE": _F(False, None, "CIRCLE is ArduPlane's last fixed-wing failsafe (ArduPlane/events.cpp)"),
})  # fmt: skip

# PX4 (main, 2025). src/modules/commander/ModeUtil/mode_requirements.cpp: AUTO.LOITER and AUTO.RTL need a global and a local position
# (relaxed for a fixed-wing), AUTO.RTL a home too; AUTO.LAND only a local altitude and a relaxed local position; MANUAL needs
# manual control (RC). The commander refuses a mode whose requirements fail (Commander.cpp handle_command DO_SET_MODE). A ground
# vehicle may always be disarmed (Commander.cpp disarm: is_ground_vehicle); a flying one is refused "not landed".
_PX4_ROVER = MappingProxyType({
    "RTL": _F(True, "HOLD", "PX4 AUTO.RTL needs a global position and home (commander/ModeUtil/mode_requirements.cpp)"),
    "HOLD": _F(True, DISARM, "PX4 AUTO.LOITER needs a global position (mode_requirements.cpp); a rover may always be disarmed "
               "(commander/Commander.cpp)"),
    "LOITER": _F(True, DISARM, "PX4 AUTO.LOITER needs a global position (mode_requirements.cpp); a rover may always be disarmed "
                 "(commander/Commander.cpp)"),
    DISARM: _F(False, None, "nothing after a disarm"),
})  # fmt: skip
_PX4_VTOL = MappingProxyType({
    "QRTL": _F(True, "QLAND", "PX4 AUTO.RTL needs a global position (mode_requirements.cpp); AUTO.LAND a local one only"),
    "RTL": _F(True, "QLAND", "PX4 AUTO.RTL needs a global position (mode_requirements.cpp); AUTO.LAND a local one only"),
    "QLOITER": _F(True, "QLAND", "PX4 AUTO.LOITER needs a global position (mode_requirements.cpp); AUTO.LAND a local one only"),
    "LOITER": _F(True, "QLAND", "PX4 AUTO.LOITER needs a global position (mode_requirements.cpp); AUTO.LAND a local one only"),
    "QLAND": _F(False, None, "AUTO.LAND is the last: PX4's own failsafe descends without a position (mode_requirements.cpp)"),
})  # fmt: skip

#: (firmware, vehicle kind) -> reaction -> its fallback. A reaction missing here has no fallback and needs nothing the executive can judge.
FALLBACKS: MappingProxyType[tuple[str, str], MappingProxyType[str, Fallback]] = MappingProxyType({
    ("ardupilot", "rover"): _ARDUROVER,
    ("ardupilot", "boat"): _ARDUROVER,
    ("ardupilot", "sub"): _ARDUSUB,
    ("ardupilot", "vtol"): _ARDUPLANE,
    ("px4", "rover"): _PX4_ROVER,
    ("px4", "vtol"): _PX4_VTOL,
})  # fmt: skip

_NONE = Fallback(False, None, "")


def _as_built_in(vehicle: str) -> str:
    """The built-in kind whose firmware a plugin's kind reports by its HEARTBEAT type (a fixed wing: ArduPlane's, the vtol's)."""
    if (spec := kind_spec(vehicle)) is None:
        return vehicle
    built_in = profile_for_mav_type(spec.profile.mav_type)
    return built_in.kind if built_in is not None else vehicle


def fallback(autopilot: str, vehicle: str, reaction: str) -> Fallback:
    """What ``reaction`` needs and what follows it on this firmware and vehicle kind (a plugin's: as its firmware's vehicle type)."""
    return FALLBACKS.get((autopilot, _as_built_in(vehicle)), MappingProxyType({})).get(reaction, _NONE)


def chain(autopilot: str, vehicle: str, reaction: str) -> Iterator[str]:
    """``reaction``, then each reaction that follows it in turn."""
    seen: set[str] = set()
    step: str | None = reaction
    while step is not None and step not in seen:
        seen.add(step)
        yield step
        step = fallback(autopilot, vehicle, step).then
