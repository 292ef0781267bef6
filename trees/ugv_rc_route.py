"""The tracked UGV's RC route (seed system 2, AgileX Bunker on ArduRover): the operator records a route with the
transmitter's switches while driving, and the autopilot drives it in AUTO.

::

    Mission: while PAUSED, hold the vehicle (the route is kept); otherwise run:
    ├── Wait for the EKF (no waypoint can be recorded without a position)
    ├── RC route or hold (reactive selector)
    │   ├── RC route: link alive? RC fresh? -> every tick, all of (done when the route is):
    │   │   ├── Switch A: edit the route: down = one edit, by the knob VRA: [-100, -26] clear the route,
    │   │   │   [-25, 25] add a waypoint here at the end, [26, 100] remove the current waypoint
    │   │   ├── Keep the route on the autopilot: upload it after each change (home at item 0), read it back
    │   │   ├── Switch C: mode: up MANUAL, middle AUTO (once the route is on the autopilot), down rc_route.aux_mode
    │   │   ├── Switch D: arm: down arm (only in MANUAL), up disarm
    │   │   └── Drive the route in AUTO: wait for the operator (within rc_route.operator_timeout_s),
    │   │       follow MISSION_CURRENT / MISSION_ITEM_REACHED; done at the last waypoint
    │   └── Wait for guards: the failing guard's failsafe (by default hold) until it recovers, within a limit
    └── Hold at the end (HOLD)

The switches act when they move (edge-triggered): the position first seen is only noted, and the
executive never sets a mode again on its own, so a ground station or a failsafe that changed it
since is not fought. After a hold (RC stale, link lost), move switch C again to take the vehicle
back. The route lives in the mission state: a guard failure or a pause loses none of it, and the
run starts with the mission file's waypoints (often none). The autopilot, not the executive,
drives in AUTO, at its own WP_SPEED, and judges when a waypoint is reached (WP_RADIUS).
"""

from __future__ import annotations

import py_trees

from executive.behaviours import (
    ArmSwitch,
    DriveRouteInAuto,
    KeepRouteOnAutopilot,
    LinkAlive,
    ModeSwitch,
    RcFresh,
    RouteEditSwitch,
    SetMode,
)
from executive.mission.declaration import TreeDeclaration
from executive.mission.model import Mission, RcRouteOptions
from executive.trees.parts import failsafe_guarded, mission_root, mode_switch_clear, safe_mode, wait_for_ekf


def operator_and_route(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The switches, the route kept on the autopilot and its drive, ticked together; SUCCESS when the route is driven."""
    options = mission.rc_route or RcRouteOptions()
    return py_trees.composites.Parallel(
        "Operator and route",
        policy=py_trees.common.ParallelPolicy.SuccessOnOne(),
        children=[
            RouteEditSwitch(),  # first: an edit is uploaded, and AUTO waits for it, in the same tick
            KeepRouteOnAutopilot(),
            ModeSwitch(options.aux_mode),
            ArmSwitch(),
            DriveRouteInAuto(options.operator_timeout_s, leg_timeout_s=mission.limits.leg_timeout_s),
        ],
    )


def switch_channels(mission: Mission) -> dict[int, str]:
    """The transmitter's switches and knob this tree reads (switch C is the person's: the take-over channel is not read)."""
    c = mission.rc.switch_channels
    return {c.knob: "knob VRA", c.swd: "switch D", c.swc: "switch C", c.swb: "switch B", c.swa: "switch A"}


#: The tracked UGV on ArduRover: its operator records the route (it may start empty) and drives it with ArduRover's modes
#: and switches. The operator drives it (MANUAL) or ArduRover does (AUTO), and skidding tracks take the course off the
#: heading in every turn: a bad compass is flagged and journalled, the vehicle left as it is (a mission may say hold).
DECLARATION = TreeDeclaration(
    doc="the tracked UGV's RC route: the operator records a route with the transmitter's switches, the autopilot drives it in AUTO",
    vehicles=frozenset({"rover"}),
    needs=("ardupilot", "its operator drives it with ArduRover's modes and switches (arming only in MANUAL, switch C to AUTO)"),
    auto_refused="its operator puts the route in AUTO already",
    section="rc_route",
    rc_switches=switch_channels,
    failsafes={"heading_insane": ("wait", "resume")},
    refused_reactions={"disarm": "the operator arms and disarms with switch D"},
    empty_route=True,
)


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: ugv_rc_route`` mission."""
    route = failsafe_guarded(operator_and_route(mission), [LinkAlive(), RcFresh()], mission, name="RC route")
    return mission_root(mission, wait_for_ekf(mission), *mode_switch_clear(mission), route, SetMode(safe_mode(mission), name="Hold at the end"))
