"""The generic guarded route: pre-flight, then every waypoint under guards, then hold.

::

    Mission: while PAUSED, hold the vehicle (the leg is kept); otherwise run:
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to)
    ├── Guarded route or hold (reactive selector)
    │   ├── Guarded route: link alive? EKF ok? armed? RC not taking over? (+ the failsafe guards: GPS, heading, battery, RC loss,
    │   │   geofence) -> for each leg: in GUIDED (asked again if it left it), go to (through each waypoint but the last, toward the next);
    │   │   drive: auto: the horizon on the autopilot, its mission at the leg, AUTO, the leg followed
    │   └── Wait for guards: the failing guard's failsafe (the mission's failsafe: policy): its reaction at once, then resume or abort
    └── Hold at the end (the vehicle's safe mode)
"""

from __future__ import annotations

import py_trees

from executive.behaviours import ForEachLeg, SetMode
from executive.mission.declaration import TreeDeclaration
from executive.mission.model import Mission
from executive.trees.parts import failsafe_guarded, leg, mission_root, preflight, safe_mode, standard_guards

#: Any vehicle kind; drive: auto on ArduRover's rover and boat.
DECLARATION = TreeDeclaration(
    doc="the generic guarded route: pre-flight, then every waypoint under guards, then hold",
    vehicles=frozenset({"rover", "boat", "sub", "vtol"}),
    auto_drive={"rover": "ArduRover", "boat": "ArduRover"},
    timed_legs=True,
)


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: waypoints`` mission."""
    route = failsafe_guarded(ForEachLeg(leg(mission)), standard_guards(mission), mission)
    return mission_root(mission, preflight(mission), route, SetMode(safe_mode(mission), name="Hold at the end"))
