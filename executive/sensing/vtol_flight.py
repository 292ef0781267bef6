"""Is a VTOL flying as a plane? Judged from what the vehicle reports, for the way it is sent home and the energy that takes.

A return asked of a VTOL in wing-borne flight, or on its way to it, must be the plane's:

- ArduPlane RTL (ArduPlane/mode_rtl.cpp ModeRTL::_enter, ModeRTL::update) flies home as a plane;
  with Q_RTL_MODE 1 (SWITCH_QRTL, switch_QRTL()) it switches to QRTL within RTL_RADIUS of home
  and lands there on the lift motors. QRTL entered while the lift motors run (ArduPlane/mode_qrtl.cpp
  ModeQRTL::_enter: spool state THROTTLE_UNLIMITED, "VTOL flight or assisting", as they do through a
  transition, SLT_Transition::update in ArduPlane/quadplane.cpp) flies the whole way home hovering,
  at Q_WP_SPEED: on a real QuadPlane SITL turned back 0.5 s after its transition, 106 s of hover,
  18.5 Wh for a 6.3 Wh plane estimate.
- PX4 AUTO.RTL flies home as a fixed-wing when the vehicle is one at the time and transitions to
  land (src/modules/navigator/rtl_direct.cpp, upstream a70a558393: RTL_STATE_TRANSITION_TO_MC
  just before the landing).

EXTENDED_SYS_STATE vtol_state says it (FW or TRANSITION_TO_FW: a plane; MC or TRANSITION_TO_MC: not),
but ArduPlane sends it only once asked for and at the rate asked, so it may lag or be missing: a
ground speed no hover reaches is taken as wing-borne whatever the last state said.
"""

from __future__ import annotations

#: Faster over the ground than this (m/s) a VTOL is wing-borne: twice Q_WP_SPEED's 5 m/s (ArduPlane/quadplane.cpp, the
#: fastest a QuadPlane hovers along), below the stall-safe AIRSPEED_MIN 13 m/s of SITL's quadplane.parm.
WING_BORNE_M_S = 10.0
PLANE_STATES = frozenset({"FW", "TRANSITION_TO_FW"})


def flies_as_plane(vtol_state: str | None, ground_speed_m_s: float | None) -> bool:
    """Whether a VTOL reported in ``vtol_state`` (EXTENDED_SYS_STATE, None: not reported) at ``ground_speed_m_s`` flies as a plane."""
    if vtol_state in PLANE_STATES:
        return True
    if vtol_state == "TRANSITION_TO_MC":  # braking to hover: asked for by the executive or the firmware, never fought
        return False
    return ground_speed_m_s is not None and ground_speed_m_s >= WING_BORNE_M_S
