"""Pieces every mission tree is made of: pre-flight, guarded work that holds when a guard fails, pause."""

from __future__ import annotations

from collections.abc import Sequence

import py_trees

from executive.behaviours import (
    Arm,
    Armed,
    EkfOk,
    Guard,
    LinkAlive,
    RcNotTakingOver,
    UnlessPaused,
    WaitForGuards,
    WaitUntil,
)
from executive.mission.model import Mission
from executive.vehicles import PROFILES

ARM_RETRY_S = 2.0
#: Where a VTOL flying as a plane is held: it cannot hover, and QLOITER (the vtol's safe mode) would make it
#: stop on its lift motors from cruise speed; LOITER circles where it is, as ArduPlane's own short failsafe does.
FIXED_WING_HOLD_MODE = "LOITER"


def safe_mode(mission: Mission) -> str:
    """Where this vehicle is held: HOLD for a rover, LOITER for a boat..."""
    return PROFILES[mission.vehicle].safe_mode


def fixed_wing_hold_mode(mission: Mission) -> str | None:
    """The hold for fixed-wing flight: LOITER for a vtol, None (the safe mode) for the others."""
    return FIXED_WING_HOLD_MODE if mission.vehicle == "vtol" else None


def wait_for_ekf(mission: Mission) -> py_trees.behaviour.Behaviour:
    """RUNNING until the EKF has a usable position (SUCCESS), FAILURE after ``limits.ekf_wait_s``."""
    return WaitUntil(EkfOk(), mission.limits.ekf_wait_s)


def preflight(mission: Mission) -> py_trees.behaviour.Behaviour:
    """Wait for a usable EKF, then arm (auto_arm) or wait for the operator to arm."""
    limits = mission.limits
    arming = (
        WaitUntil(Arm(), limits.ekf_wait_s, name="Arm", retry_s=ARM_RETRY_S)
        if mission.auto_arm
        else WaitUntil(Armed(), limits.recovery_timeout_s, name="Wait for the operator to arm")
    )
    return py_trees.composites.Sequence("Pre-flight", memory=True, children=[wait_for_ekf(mission), arming])


def standard_guards(mission: Mission) -> list[Guard]:
    """Link alive, EKF ok, armed, RC not taking over: what every leg is guarded by."""
    return [LinkAlive(), EkfOk(), Armed(), RcNotTakingOver(mission.rc.takeover_channel, mission.rc.takeover_above_us)]


def guarded(
    work: py_trees.behaviour.Behaviour, guards: Sequence[Guard], mission: Mission, name: str = "Guarded route"
) -> py_trees.behaviour.Behaviour:
    """``work`` under ``guards``, re-checked every tick; when one fails, hold and wait for it to recover (within a limit).

    Progress is kept in the mission state, so the work resumes where it was when the guard recovers.
    """
    route = py_trees.composites.Sequence(name, memory=False, children=[*guards, work])
    wait = WaitForGuards(guards, mission.limits.recovery_timeout_s, hold_mode=safe_mode(mission), fixed_wing_hold_mode=fixed_wing_hold_mode(mission))
    return py_trees.composites.Selector(f"{name} or hold", memory=False, children=[route, wait])


def mission_root(mission: Mission, *steps: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """The steps in order, held in the safe mode (a vtol flying as a plane: LOITER) while the mission is PAUSED."""
    body = py_trees.composites.Sequence("Run", memory=True, children=list(steps))
    return UnlessPaused(body, hold_mode=safe_mode(mission), name="Mission", fixed_wing_hold_mode=fixed_wing_hold_mode(mission))
