"""Pieces every mission tree is made of: pre-flight, guarded work under the mission's failsafes, pause."""

from __future__ import annotations

from collections.abc import Sequence

import py_trees

from executive.behaviours import (
    AllWaypointsWithin,
    Arm,
    Armed,
    AutopilotAtLeg,
    BatteryAbove,
    DepthsOnAutopilot,
    EkfOk,
    EnergyEnough,
    EnergyFits,
    Failsafe,
    FollowAutoLeg,
    GoTo,
    GpsNotGlitching,
    Guard,
    HeadingSane,
    HorizonOnAutopilot,
    LinkAlive,
    ModeSwitchClear,
    ParameterIs,
    PositionKnown,
    RcChannelHigh,
    RcNotLost,
    RcNotTakingOver,
    ReadingsIn,
    SetMode,
    UnlessPaused,
    WaitUntil,
    inside_geofence,
)
from executive.behaviours.failsafe import condition_of
from executive.behaviours.returning import NoReturnUnderWay
from executive.behaviours.zone_guards import outside_keep_out
from executive.behaviours.zones import ZonesOnAutopilot, puts_zones_on_autopilot
from executive.mission.declaration import vehicle_profile
from executive.mission.failsafes import FailsafePolicy
from executive.mission.model import Mission
from executive.mission.return_path import ReturnPlanner
from executive.mission.rules import failsafe_policy, height_tolerance, rc_switch_channels, seabed_clearance

ARM_RETRY_S = 2.0
#: A sub's last waypoint in AUTO is reached within this of its depth (GUIDED's ChangeDepth tolerance).
SUB_DEPTH_TOLERANCE_M = 0.5
#: Where a VTOL flying as a plane is held: it cannot hover, and QLOITER (the vtol's safe mode) would make it
#: stop on its lift motors from cruise speed; LOITER circles where it is, as ArduPlane's own short failsafe does.
FIXED_WING_HOLD_MODE = "LOITER"


def safe_mode(mission: Mission) -> str:
    """Where this vehicle is held: HOLD for a rover, LOITER for a boat..."""
    return vehicle_profile(mission.vehicle).safe_mode


def fixed_wing_hold_mode(mission: Mission) -> str | None:
    """The hold for fixed-wing flight: LOITER for a vtol, None (the safe mode) for the others."""
    return FIXED_WING_HOLD_MODE if mission.vehicle == "vtol" else None


def wait_for_ekf(mission: Mission) -> py_trees.behaviour.Behaviour:
    """RUNNING until the EKF has a usable position (SUCCESS), FAILURE after ``limits.ekf_wait_s``."""
    return WaitUntil(EkfOk(), mission.limits.ekf_wait_s)


def within_reach(mission: Mission, name: str = "Within reach", check_name: str | None = None) -> py_trees.behaviour.Behaviour:
    """The EKF's position, then every waypoint within ``limits.max_goal_distance_m`` of it (else FAILURE naming the waypoint).

    Put before anything that moves the vehicle or changes its mode: a mission out of reach is
    rejected with nothing sent.
    """
    limits = mission.limits
    return py_trees.composites.Sequence(
        name,
        memory=True,
        children=[
            wait_for_ekf(mission),
            WaitUntil(PositionKnown(), limits.ekf_wait_s),
            AllWaypointsWithin(mission.waypoints, limits.max_goal_distance_m, name=check_name),
        ],
    )


def mode_switch_clear(mission: Mission) -> list[py_trees.behaviour.Behaviour]:
    """The check that the autopilot's own mode switch is on none of the mission's RC switches (none with RC from CAN)."""
    switches = rc_switch_channels(mission)
    return [ModeSwitchClear(switches)] if switches else []


def readings_in(mission: Mission) -> list[py_trees.behaviour.Behaviour]:
    """The wait for what the pre-flight checks and the battery guard need (the mode-switch parameter, a battery report), if anything."""
    switches, limits = rc_switch_channels(mission), mission.limits
    if not switches and limits.battery_min_pct is None and limits.battery_min_v is None:
        return []
    return [ReadingsIn(switches, limits.battery_min_pct, limits.battery_min_v)]


def energy_fits(mission: Mission) -> list[py_trees.behaviour.Behaviour]:
    """The whole route and the way home must fit the battery above the reserve, else refused unarmed (every mission, but
    ``energy: {check: off}``; a battery that cannot tell the energy of a mission without ``energy:``: warned, run unjudged)."""
    return [EnergyFits()] if mission.energy_rule() is not None else []


def preflight(mission: Mission) -> py_trees.behaviour.Behaviour:
    """A usable EKF, the readings its checks need (bounded), the autopilot's mode switch clear of the mission's; then arm or wait for it.

    Arming: auto_arm arms; else the RC arm switch high arms, or the operator arms.
    """
    limits, rc = mission.limits, mission.rc
    if mission.auto_arm:
        arming: py_trees.behaviour.Behaviour = WaitUntil(Arm(), limits.ekf_wait_s, name="Arm", retry_s=ARM_RETRY_S)
    elif rc.arm_channel is not None:  # the seed's ASV: channel 5 high = armed
        arm = WaitUntil(Arm(), limits.recovery_timeout_s, name="Arm", retry_s=ARM_RETRY_S)
        switch = py_trees.composites.Sequence(
            f"RC channel {rc.arm_channel} high: arm", memory=False, children=[RcChannelHigh(rc.arm_channel, rc.takeover_above_us), arm]
        )
        either = py_trees.composites.Selector("Armed, or arm on the RC switch", memory=False, children=[Armed(), switch])
        name = f"Wait for the operator to arm (or RC channel {rc.arm_channel} high)"
        arming = WaitUntil(either, limits.recovery_timeout_s, name=name, hint=how_to_arm(mission))
    else:
        arming = WaitUntil(Armed(), limits.recovery_timeout_s, name="Wait for the operator to arm", hint=how_to_arm(mission))
    checks = [
        wait_for_ekf(mission), *readings_in(mission), *mode_switch_clear(mission), *mission_end_checks(mission), *energy_fits(mission),
        *zones_on_autopilot(mission),
    ]  # fmt: skip
    return py_trees.composites.Sequence("Pre-flight", memory=True, children=[*checks, arming])


#: drive: auto: what stops the vehicle at the end of the horizon it holds. ArduRover's ModeAuto::exit_mission
#: (Rover/mode_auto.cpp): MIS_DONE_BEHAVE 0 stops in AUTO, 1 loiters in AUTO; 2 (ACRO) and 3 (MANUAL) change mode and
#: drive on as the sticks say (Rover/Parameters.cpp: "0:Hold in Auto Mode,1:Loiter in Auto Mode,2:Acro Mode,3:Manual Mode").
MISSION_END_STOPS = ("MIS_DONE_BEHAVE", (0.0, 1.0), "drive: auto needs the vehicle stopped at the end of the horizon it holds (0 Hold, 1 Loiter)")


def mission_end_checks(mission: Mission) -> list[py_trees.behaviour.Behaviour]:
    """drive: auto: the check that the autopilot stops the vehicle at the end of its mission (else the mission is refused).

    ArduSub has no parameter for it: Sub::exit_mission (ArduSub/commands_logic.cpp) always holds, in AUTO at the
    stopping point, position and depth (ModeAuto::auto_loiter_start), or, without a position, in ALT_HOLD (depth only).
    """
    if mission.drive != "auto" or mission.vehicle == "sub":
        return []
    name, allowed, why = MISSION_END_STOPS
    return [ParameterIs(name, allowed, why)]


def zones_on_autopilot(mission: Mission) -> list[py_trees.behaviour.Behaviour]:
    """The zones and rally points sent to the autopilot and read back (``geofence.autopilot``, default upload), if the mission has any."""
    if not puts_zones_on_autopilot(mission):
        return []
    return [ZonesOnAutopilot(mission.geofence, mission.rally_points)]


def how_to_arm(mission: Mission) -> str:
    """What a person does to arm this mission's vehicle, said when the pre-flight starts waiting for it and when it gives up."""
    switch = f", RC channel {mission.rc.arm_channel} high" if mission.rc.arm_channel is not None else ""
    return f"to arm it: `executive ctl arm`{switch} or a ground station; or `auto_arm: true` in the mission to have it armed in pre-flight"


def standard_guards(mission: Mission) -> list[Guard]:
    """Link alive, EKF ok, armed, RC not taking over: what every leg is guarded by."""
    return [LinkAlive(), EkfOk(), Armed(), RcNotTakingOver(mission.rc.takeover_channel, mission.rc.takeover_above_us)]


def failsafe_guards(mission: Mission, guards: Sequence[Guard]) -> list[Guard]:
    """``guards``, then guards for the failsafe conditions they leave out: GPS glitch, heading (surface vehicles), battery, RC loss, geofence.

    The heading filter judges the compass against the course over ground, which tells the heading
    only for a vehicle that goes where it points: a sub moves sideways, a vtol hovers or crabs.
    An Armed guard is added when a reaction disarms: the vehicle must be armed again before the work resumes.
    """
    limits, covered = mission.limits, {condition_of(g) for g in guards}
    battery_checked = limits.battery_min_pct is not None or limits.battery_min_v is not None
    candidates: list[tuple[str, Guard | None]] = [
        ("gps_glitch", GpsNotGlitching()),
        ("heading_insane", HeadingSane() if vehicle_profile(mission.vehicle).surface else None),
        ("battery_low", BatteryAbove(limits.battery_min_pct, limits.battery_min_v) if battery_checked else None),
        ("rc_loss", RcNotLost(mission.rc.source)),
        ("geofence_breach", inside_geofence(mission)),
        ("energy", EnergyEnough(required=mission.energy is not None) if mission.energy_rule() is not None else None),
        ("keep_out", outside_keep_out(mission)),
    ]
    extra = [guard for condition, guard in candidates if condition not in covered and guard is not None]
    policy = failsafe_policy(mission)
    checked_conditions = covered | {condition_of(g) for g in extra}
    if "disarmed" not in covered and any(policy[c].reaction == "disarm" for c in checked_conditions if c in policy):
        extra.append(Armed())
    return [*guards, *extra]


def failsafe(guards: Sequence[Guard], mission: Mission, name: str = "Wait for guards", work: py_trees.behaviour.Behaviour | None = None) -> Failsafe:
    """The mission's failsafe for ``guards``, standing behind ``work`` (None: a guard alone).

    A guard of no failsafe condition (a limit) holds and resumes within ``limits.recovery_timeout_s``.
    """
    fallback = FailsafePolicy("limit", "hold", "resume", mission.limits.recovery_timeout_s)
    returns = ReturnPlanner(mission)
    return Failsafe(
        guards, failsafe_policy(mission), mission.vehicle, fallback, name=name,
        returns=returns if returns.needed else None, reach_m=mission.limits.acceptance_radius_m,
        leg_timeout_s=mission.limits.leg_timeout_s, work=work,
    )  # fmt: skip


def failsafe_guarded(
    work: py_trees.behaviour.Behaviour, guards: Sequence[Guard], mission: Mission, name: str = "Guarded route"
) -> py_trees.behaviour.Behaviour:
    """``work`` under ``guards`` (and :func:`failsafe_guards`), re-checked every tick; when one fails, its failsafe (the mission's policy).

    The failsafe commands the reaction in the tick the guard fails, then waits for the guard to
    recover (within its time limit) or aborts the mission. Progress is kept in the mission state,
    so the work resumes where it was when the guard recovers.
    """
    guards = failsafe_guards(mission, guards)
    react = failsafe(guards, mission, work=work)
    gate = [NoReturnUnderWay(react)] if react.returns is not None else []  # a return that ends the mission is not resumed from
    route = py_trees.composites.Sequence(name, memory=False, children=[*gate, *guards, work])
    return py_trees.composites.Selector(f"{name} or hold", memory=False, children=[route, react])


def guided_leg(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One leg: GUIDED, then drive to the waypoint (through it, toward the next, unless it is the last).

    GUIDED is checked every tick, not only when the leg starts: ArduPilot drops a position target
    silently outside GUIDED, so a vehicle that left it in a mode of our own asking (a failsafe's
    LOITER delivered late by a lagging link) would sit out the leg's timeout while the setpoints
    went nowhere. It is asked for again, and the leg goes on from where the vehicle is. A mode a
    person set is an intervention: the mission pauses before the tree ticks (executive.operator.intervention).
    """
    limits = mission.limits
    go = GoTo(
        limits.acceptance_radius_m,
        limits.leg_timeout_s,
        look_ahead=True,
        seabed_clearance_m=seabed_clearance(mission),
        height_tolerance_m=height_tolerance(mission),
    )
    guided = SetMode(vehicle_profile(mission.vehicle).guided_mode, confirm_by_ack=True)  # moving a tick after the ack, not at the next heartbeat
    return py_trees.composites.Sequence("Leg", memory=False, children=[guided, go])


def auto_leg(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One leg in AUTO (drive: auto): the horizon on the autopilot, its mission at this leg, AUTO, then the leg as AUTO drives it.

    AUTO is checked every tick as GUIDED is in :func:`guided_leg`: asked again if a mode of our own
    asking left it; a mode a person set pauses the mission (executive.operator.intervention).
    """
    limits = mission.limits
    sub = mission.vehicle == "sub"  # its depths under the seabed floor, its last waypoint reached at its depth too
    horizon_legs = limits.auto_horizon_legs
    horizon = DepthsOnAutopilot(horizon_legs, limits.altitude_m.min, limits.seabed_floor) if sub else HorizonOnAutopilot(horizon_legs)
    steps = [
        horizon,
        AutopilotAtLeg(),
        SetMode("AUTO", confirm_by_ack=True),  # the port names it per firmware (mode_name)
        FollowAutoLeg(limits.acceptance_radius_m, limits.leg_timeout_s, depth_tolerance_m=SUB_DEPTH_TOLERANCE_M if sub else None),
    ]
    return py_trees.composites.Sequence("Leg in AUTO", memory=False, children=steps)


def leg(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One leg as the mission's ``drive:`` says: :func:`auto_leg` or :func:`guided_leg`."""
    return auto_leg(mission) if mission.drive == "auto" else guided_leg(mission)


def checked(guard: Guard, mission: Mission, name: str | None = None) -> py_trees.behaviour.Behaviour:
    """One guard on its own, with its failsafe: SUCCESS while it holds; else the reaction, then RUNNING until it recovers, or FAILURE."""
    return py_trees.composites.Selector(
        name or f"{guard.name} or failsafe", memory=False, children=[guard, failsafe([guard], mission, name="Failsafe")]
    )


def mission_root(mission: Mission, *steps: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """The steps in order, held in the safe mode (a vtol flying as a plane: LOITER) while the mission is PAUSED."""
    body = py_trees.composites.Sequence("Run", memory=True, children=list(steps))
    return UnlessPaused(body, hold_mode=safe_mode(mission), name="Mission", fixed_wing_hold_mode=fixed_wing_hold_mode(mission))
