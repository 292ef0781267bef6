"""The generic guarded route: pre-flight, then every waypoint under guards, then hold.

::

    Mission: while PAUSED, hold the vehicle (the leg is kept); otherwise run:
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to)
    ├── Guarded route or hold (reactive selector)
    │   ├── Guarded route: link alive? EKF ok? armed? RC not taking over? (+ the failsafe guards: GPS, heading, battery, RC loss,
    │   │   geofence) -> for each leg: in GUIDED (asked again if it left it), go to (through each waypoint but the last, toward the next)
    │   └── Wait for guards: the failing guard's failsafe (the mission's failsafe: policy): its reaction at once, then resume or abort
    └── Hold at the end (the vehicle's safe mode)
"""

from __future__ import annotations

import py_trees

from executive.behaviours import ForEachLeg, GoTo, SetMode
from executive.mission.model import Mission
from executive.trees.parts import guarded, mission_root, preflight, safe_mode, standard_guards
from executive.vehicles import PROFILES


def leg(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One leg: GUIDED, then drive to the waypoint (through it, toward the next, unless it is the last).

    GUIDED is checked every tick, not only when the leg starts: ArduPilot drops a position target
    silently outside GUIDED, so a vehicle that left it in a mode of our own asking (a failsafe's
    LOITER delivered late by a lagging link) would sit out the leg's timeout while the setpoints
    went nowhere. It is asked for again, and the leg goes on from where the vehicle is. A mode a
    person set is an intervention: the mission pauses before the tree ticks (executive.intervention).
    """
    limits = mission.limits
    go = GoTo(limits.acceptance_radius_m, limits.leg_timeout_s, look_ahead=True)
    guided = SetMode(PROFILES[mission.vehicle].guided_mode, confirm_by_ack=True)  # moving a tick after the ack, not at the next heartbeat
    return py_trees.composites.Sequence("Leg", memory=False, children=[guided, go])


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: waypoints`` mission."""
    route = guarded(ForEachLeg(leg(mission)), standard_guards(mission), mission)
    return mission_root(mission, preflight(mission), route, SetMode(safe_mode(mission), name="Hold at the end"))
