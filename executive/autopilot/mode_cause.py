"""Whose mode change is it: the autopilot's own transitions, judged by their cause, per firmware.

An autopilot changes mode by itself in a few documented states: PX4 loiters once a take-off or a
mission is done, goes back to the user's mode once disarmed, and its failsafe picks a mode; ArduSub
holds its depth once SURFACE reaches the surface, and at its mission's end without a position; ArduPilot's failsafes announce themselves. A mode
change is the autopilot's only when the firmware's cause for it shows in what the executive sees
(the landed state, the armed flag, the mission's state, the heartbeat's system status, the
autopilot's STATUSTEXT, the RC); anything else is a person's. Each rule cites the firmware source
that makes the transition. The mode the executive asked for itself is judged before (it is ours).
"""

from __future__ import annotations

from dataclasses import dataclass

from executive.world.dialect import mavlink
from executive.world.vehicles import AutopilotName

#: PX4 modes with mode_req_prevent_arming (src/modules/commander/ModeUtil/mode_requirements.cpp): never the mode it goes
#: back to once disarmed (UserModeIntention::change keeps only the others as _nav_state_after_disarming).
PX4_PREVENT_ARMING_MODES = frozenset({"AUTO.RTL", "AUTO.LAND", "AUTO.PRECLAND", "AUTO.FOLLOW_TARGET", "DESCEND", "TERMINATION"})
#: ArduSub's SURFACE is done above SURFACE_DEPTH (-10 cm, ArduSub/Parameters.cpp); GLOBAL_POSITION_INT's relative altitude
#: is minus the depth. A little margin for the report's rounding and the waves.
SUB_AT_SURFACE_M = -0.5
#: PX4's multicopter take-off (a VTOL's too: it takes off as one, vehicle_type ROTARY_WING) is reached once its global
#: position estimate is above the take-off item's altitude (above sea level, as NAV_TAKEOFF sent it) less NAV_MC_ALT_RAD,
#: 0.8 m by default (navigator/navigator_params.c; Navigator::get_altitude_acceptance_radius in navigator_main.cpp: the
#: take-off setpoint has no radius of its own; MissionBlock::is_mission_item_reached_or_completed in mission_block.cpp: no
#: yaw to wait for, set_takeoff_item leaves it NaN); navigator/takeoff.cpp then says it finished, with no message sent.
#: The vehicle's own NAV_MC_ALT_RAD is read (PARAM_REQUEST_READ, ``ModeChange.takeoff_alt_rad_m``); its default until it answers.
PX4_TAKEOFF_ALT_RAD_M = 0.8
PX4_TAKEOFF_ALT_RAD_PARAM = "NAV_MC_ALT_RAD"
#: A position report older than this cannot tell where the climb was when PX4 ended it (GLOBAL_POSITION_INT comes at 5 Hz).
PX4_POSITION_JUDGES_S = 1.0


@dataclass(frozen=True, slots=True)
class AutopilotCause:
    """Why the autopilot changed the mode itself: ``why`` for the log, ``failsafe`` when its failsafe did (ours answer it)."""

    why: str
    failsafe: bool = False
    #: The autopilot's own protection took the vehicle (its fence): the mission pauses hands off; a person resumes it.
    pauses: bool = False


@dataclass(frozen=True, slots=True)
class ModeChange:
    """A change of the heartbeat's mode and what the executive could see when it came."""

    previous: str
    mode: str
    armed: bool
    disarmed_just_now: bool  # armed at the previous heartbeat, or disarmed within the explaining window
    landed_state: str | None  # EXTENDED_SYS_STATE: ON_GROUND, IN_AIR, TAKEOFF, LANDING; None: not reported
    mission_complete: bool  # MISSION_CURRENT mission_state COMPLETE (5)
    system_status: int | None  # HEARTBEAT system_status (MAV_STATE) of the heartbeat that shows the change
    failsafe_text: str | None  # the autopilot's failsafe notice just before ("EKF failsafe"), or its RC failsafe
    alt_rel_m: float | None  # GLOBAL_POSITION_INT relative altitude (minus the depth under water)
    takeoff_alt_msl_m: float | None = None  # the altitude above sea level our latest take-off climbs to, as sent (None: unknown)
    #: GLOBAL_POSITION_INT's altitude above sea level, its climb rate (m/s, up) and age (s) when the change is judged
    alt_msl_m: float | None = None
    climb_m_s: float = 0.0
    position_age_s: float = 0.0
    fence_breached: bool = False  # FENCE_STATUS said the autopilot's own fence is breached, just before or with the change
    #: The autopilot's mission ended: MISSION_ITEM_REACHED of the last item MISSION_CURRENT counts, or MISSION_CURRENT COMPLETE
    #: (ArduPilot sends the first at once, in the loop that ends the mission; the second only at its next stream)
    mission_end_reached: bool = False
    position_ok: bool | None = None  # the EKF's last word (EKF_STATUS_REPORT): a horizontal position; None: not reported
    takeoff_alt_rad_m: float | None = None  # the take-off's altitude acceptance the vehicle holds (PX4 NAV_MC_ALT_RAD); None: unread


def autopilot_cause(firmware: AutopilotName, vehicle: str, change: ModeChange) -> AutopilotCause | None:
    """Why the autopilot made ``change`` itself (its firmware's documented transition in that state), or None: a person's."""
    if change.failsafe_text is not None:
        # ArduPilot announces its failsafes by STATUSTEXT (Rover/ekf_check.cpp "EKF failsafe" -> HOLD; Rover/failsafe.cpp RC
        # loss -> FS_ACTION, and every RC channel 0 once it acted); PX4 its delayed ones ("Failsafe activated: entering Hold
        # for N seconds", commander/failsafe/framework.cpp notifyUser)
        return AutopilotCause(change.failsafe_text, failsafe=True)
    if firmware == "px4":
        return _px4_cause(change)
    return _ardupilot_cause(vehicle, change)


def facts_may_lag(firmware: AutopilotName, vehicle: str, change: ModeChange) -> bool:
    """Whether ``change``, unexplained, may yet be explained by facts that the autopilot streams after its heartbeat: then they are
    waited for. ArduSub's mission end in ALT_HOLD shows in MISSION_CURRENT (1 Hz) and EKF_STATUS_REPORT (2 Hz), and a link back
    after a cut brings the heartbeat first, with the facts before the cut still on the blackboard."""
    return firmware == "ardupilot" and vehicle == "sub" and change.previous == "AUTO" and change.mode == "ALT_HOLD" and change.armed


def _px4_cause(c: ModeChange) -> AutopilotCause | None:
    if c.disarmed_just_now and not c.armed and c.mode not in PX4_PREVENT_ARMING_MODES:
        return AutopilotCause("disarmed: back to the last mode asked for, PX4 Commander::disarm, UserModeIntention::onDisarm")
    if not c.armed:
        return None
    if c.system_status == mavlink.MAV_STATE_CRITICAL:
        # mavlink/streams/HEARTBEAT.hpp: armed with vehicle_status.failsafe set; a person's mode change ends the failsafe first
        return AutopilotCause("PX4's failsafe: HEARTBEAT system_status CRITICAL, commander/failsafe/failsafe.cpp", failsafe=True)
    if c.previous == "AUTO.TAKEOFF" and c.mode in ("AUTO.LOITER", "AUTO.MISSION") and _takeoff_reached(c):
        # navigator/takeoff.cpp reports the take-off finished at its altitude; the commander then loiters (or flies the mission,
        # COM_TAKEOFF_ACT 1). EXTENDED_SYS_STATE's TAKEOFF cannot tell: it turns IN_AIR with any other setpoint, a person's Hold too;
        # no STATUSTEXT, MISSION_ITEM_REACHED or MISSION_CURRENT says it (none on the real SIH, tests/data/px4/README.md)
        return AutopilotCause("the take-off is done, PX4 Commander::checkForMissionUpdate, navigator/takeoff.cpp")
    if c.previous == "AUTO.MISSION" and c.mode == "AUTO.LOITER" and c.mission_complete and c.landed_state != "ON_GROUND":
        return AutopilotCause("the mission is finished, PX4 Commander::checkForMissionUpdate")
    return None


def _takeoff_reached(c: ModeChange) -> bool:
    """PX4's own test, on its own estimate: GLOBAL_POSITION_INT's ``alt`` is the navigator's global position altitude
    (mavlink/streams/GLOBAL_POSITION_INT.hpp), the latest report climbed on for its age at most. Its relative altitude is not:
    it counts from home, whose altitude PX4 corrects in the first seconds of flight (commander/HomePosition.cpp, by ~1 m steps
    on the SIH), and the take-off's altitude was sent above sea level from the home known before."""
    if c.landed_state == "ON_GROUND" or c.alt_msl_m is None or c.takeoff_alt_msl_m is None or c.position_age_s > PX4_POSITION_JUDGES_S:
        return False
    climbed_since = max(0.0, c.climb_m_s) * max(0.0, c.position_age_s)  # the switch came at most now
    alt_rad_m = PX4_TAKEOFF_ALT_RAD_M if c.takeoff_alt_rad_m is None else c.takeoff_alt_rad_m
    return c.alt_msl_m + climbed_since >= c.takeoff_alt_msl_m - alt_rad_m


def _ardupilot_cause(vehicle: str, c: ModeChange) -> AutopilotCause | None:
    if c.fence_breached and c.armed:
        # Rover/fence.cpp fence_check: a new breach sets FENCE_ACTION's mode (reason FENCE_BREACHED); AC_Fence::record_breach sends
        # FENCE_STATUS at once, and no STATUSTEXT
        return AutopilotCause(f"its own fence breached (FENCE_STATUS), FENCE_ACTION -> {c.mode}, Rover/fence.cpp", pauses=True)
    if (
        vehicle == "sub"
        and c.previous == "AUTO"
        and c.mode == "ALT_HOLD"
        and c.armed
        and c.position_ok is False
        and (c.mission_end_reached or c.mission_complete)
    ):
        # ArduSub/commands_logic.cpp Sub::exit_mission: ModeAuto::auto_loiter_start fails without sub.position_ok(), then
        # set_mode(ALT_HOLD, ModeReason::MISSION_END), said by no STATUSTEXT; with a position it holds in AUTO instead
        return AutopilotCause("its mission ended without a position: ALT_HOLD, ArduSub Sub::exit_mission (commands_logic.cpp)")
    if vehicle == "sub" and c.previous == "SURFACE" and c.mode == "ALT_HOLD" and c.alt_rel_m is not None and c.alt_rel_m >= SUB_AT_SURFACE_M:
        return AutopilotCause("at the surface, ArduSub mode_surface.cpp SURFACE_COMPLETE")
    return None
