"""The AUV survey (the Zeno AUV's mission manager): accept the route, dive and run it leg by leg under guards, surface, hold.

::

    Mission: while PAUSED, hold in POSHOLD (the leg is kept); otherwise run:
    ├── Accept the mission (once): wait for the EKF and a position, then every waypoint within 1 km of it?
    │   (a waypoint farther away refuses the whole mission, before anything is sent to the vehicle)
    │   and the downward rangefinder's range (RNGFND1_MIN/MAX) covers every altitude leg's height?
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to)
    ├── Guarded survey or hold (reactive selector)
    │   ├── Guarded survey: link alive? EKF ok? armed? RC not taking over? speed, depth and (altitude legs) altitude within limits?
    │   │   -> for each leg: set GUIDED, change speed, reach the depth or the altitude above the seabed, go to the waypoint at it
    │   │   (drive: auto: the horizon on ArduSub, its depths under the seabed floor; its mission at the leg, AUTO, the leg followed)
    │   └── Wait for guards: the failing guard's failsafe (by default hold in POSHOLD; a limit: hold) until it recovers, within a limit
    ├── Surface: ArduSub's SURFACE mode (it hands over to ALT_HOLD by itself at the surface)
    └── Hold at the surface: POSHOLD

The end: an AUV comes up at the end of a survey to be seen, to get GPS and radio back and to be
picked up; POSHOLD then keeps it on the last waypoint (ALT_HOLD, where SURFACE leaves it, holds
only the depth and would let it drift). It stays armed: the crew disarms it at the pick-up.
Surfacing is not guarded: holding would stop the one manoeuvre that makes a sub safe.

A leg follows the waypoint's control mode: ``depth`` dives (or rises) to ``depth_m`` where the
vehicle is, then goes to the waypoint at that depth; ``altitude`` does the same at ``altitude_m``
above the seabed, flown as depth targets from the measured depth and the downward sonar, re-sent as
the seabed changes (ArduSub drops terrain-frame targets: executive/world/seabed.py); with the seabed
beyond the sonar's reach the sub first dives, without overshooting, until the sonar reads it. A depth leg without
``depth_m`` runs at the surface (depth 0, as the Zeno vehicle is run). The 1 km rule is checked
once, at the start: pausing and resuming a mission does not accept it again.
"""

from __future__ import annotations

import py_trees
from py_trees.common import OneShotPolicy

from executive.behaviours import (
    AltitudeWithin,
    ChangeAltitude,
    ChangeDepth,
    ChangeSpeed,
    DepthWithin,
    ForEachLeg,
    GoTo,
    Guard,
    RangefinderReaches,
    SetMode,
    SpeedWithin,
    Surface,
)
from executive.mission.declaration import TreeDeclaration, vehicle_profile
from executive.mission.model import Mission
from executive.trees.parts import auto_leg, failsafe_guarded, mission_root, preflight, safe_mode, standard_guards, within_reach


def acceptance(mission: Mission) -> py_trees.behaviour.Behaviour:
    """Once: the EKF's position, then every waypoint within ``max_goal_distance_m`` of it, and the rangefinder's range covering
    every altitude leg (else the mission fails, naming the waypoint, and the parameter and the value it needs)."""
    check = py_trees.composites.Sequence(
        "Accept the mission", memory=True, children=[within_reach(mission, "Waypoints within reach"), RangefinderReaches(mission.waypoints)]
    )
    return py_trees.decorators.OneShot("Once", check, OneShotPolicy.ON_SUCCESSFUL_COMPLETION)


def survey_guards(mission: Mission) -> list[Guard]:
    """The standard guards, and the mission's speed, depth and (on altitude legs) altitude limits."""
    limits = mission.limits
    return [
        *standard_guards(mission),
        SpeedWithin(limits.speed_m_s),
        DepthWithin(limits.depth_m),
        AltitudeWithin(limits.altitude_m, altitude_legs_only=True),
    ]


def leg(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One leg: GUIDED, the leg's speed, its depth or altitude where the vehicle is, then the waypoint at that depth or altitude.

    ``drive: auto``: the leg in ArduSub's AUTO (:func:`executive.trees.parts.auto_leg`): straight to the waypoint at its
    depth (no altitude legs), at the autopilot's WPNAV_SPEED, not the waypoint's speed."""
    if mission.drive == "auto":
        return auto_leg(mission)
    limits = mission.limits
    return py_trees.composites.Sequence(
        "Leg",
        memory=True,
        children=[
            SetMode(vehicle_profile(mission.vehicle).guided_mode),
            ChangeSpeed(),
            ChangeDepth(timeout_s=limits.leg_timeout_s, clearance_m=limits.altitude_m.min, too_deep=limits.seabed_floor),
            ChangeAltitude(timeout_s=limits.leg_timeout_s),
            GoTo(limits.acceptance_radius_m, limits.leg_timeout_s, seabed_clearance_m=limits.altitude_m.min),
        ],
    )


#: A sub; drive: auto on ArduSub (its waypoints at their depths); a lost link holds the survey in POSHOLD.
DECLARATION = TreeDeclaration(
    doc="the AUV survey: accept the route, dive and run it leg by leg under guards, surface, hold",
    vehicles=frozenset({"sub"}),
    auto_drive={"sub": "ArduSub"},
    failsafes={"link_loss": ("hold", "resume")},
    timed_legs=True,
)


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: auv_survey`` mission."""
    survey = failsafe_guarded(ForEachLeg(leg(mission)), survey_guards(mission), mission, name="Guarded survey")
    return mission_root(mission, acceptance(mission), preflight(mission), survey, Surface(), SetMode(safe_mode(mission), name="Hold at the surface"))
