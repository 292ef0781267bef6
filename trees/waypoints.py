"""The generic guarded route: pre-flight, then every waypoint under guards, then hold.

::

    Mission: while PAUSED, hold the vehicle (the leg is kept); otherwise run:
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to)
    ├── Route or hold (reactive selector)
    │   ├── Guarded route: link alive? EKF ok? armed? RC not taking over? -> for each leg: set GUIDED, go to
    │   └── Wait for guards: hold (unless a person has the vehicle) until they recover, within a limit
    └── Hold at the end (the vehicle's safe mode)
"""

from __future__ import annotations

import py_trees

from executive.behaviours import (
    Arm,
    Armed,
    EkfOk,
    ForEachLeg,
    GoTo,
    LinkAlive,
    RcNotTakingOver,
    SetMode,
    UnlessPaused,
    WaitForGuards,
    WaitUntil,
)
from executive.mission.model import Mission
from executive.vehicles import PROFILES

ARM_RETRY_S = 2.0


def preflight(mission: Mission) -> py_trees.behaviour.Behaviour:
    """Wait for a usable EKF, then arm (auto_arm) or wait for the operator to arm."""
    limits = mission.limits
    arming = (
        WaitUntil(Arm(), limits.ekf_wait_s, name="Arm", retry_s=ARM_RETRY_S)
        if mission.auto_arm
        else WaitUntil(Armed(), limits.recovery_timeout_s, name="Wait for the operator to arm")
    )
    return py_trees.composites.Sequence("Pre-flight", memory=True, children=[WaitUntil(EkfOk(), limits.ekf_wait_s), arming])


def guarded_route(mission: Mission) -> py_trees.behaviour.Behaviour:
    """Every leg under the guards; when one fails, hold and wait for it to recover."""
    limits, profile = mission.limits, PROFILES[mission.vehicle]
    guards = [LinkAlive(), EkfOk(), Armed(), RcNotTakingOver(mission.rc.takeover_channel, mission.rc.takeover_above_us)]
    leg = py_trees.composites.Sequence(
        "Leg", memory=True, children=[SetMode(profile.guided_mode), GoTo(limits.acceptance_radius_m, limits.leg_timeout_s)]
    )
    route = py_trees.composites.Sequence("Guarded route", memory=False, children=[*guards, ForEachLeg(leg)])
    wait = WaitForGuards(guards, limits.recovery_timeout_s, hold_mode=profile.safe_mode)
    return py_trees.composites.Selector("Route or hold", memory=False, children=[route, wait])


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: waypoints`` mission."""
    safe_mode = PROFILES[mission.vehicle].safe_mode
    hold = SetMode(safe_mode, name="Hold at the end")
    body = py_trees.composites.Sequence("Run", memory=True, children=[preflight(mission), guarded_route(mission), hold])
    return UnlessPaused(body, hold_mode=safe_mode, name="Mission")
