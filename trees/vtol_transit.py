"""VTOL transit (seed system 3): take off as a multicopter, fly the route as a plane, come back a multicopter and land.

::

    Mission: while PAUSED, hold in QLOITER (flying as a plane: LOITER); otherwise run:
    ├── Firmware check (once, with a hover point): Q_GUIDED_MODE is 1? (else refused, naming it and why)
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to)
    ├── Guarded flight or hold (reactive selector)
    │   ├── Guarded flight: link alive? EKF ok? armed? RC not taking over? -> Flight:
    │   │   ├── Take off (once): set GUIDED, NAV_TAKEOFF to vtol.takeoff_alt_m (EXTENDED_SYS_STATE IN_AIR, and the height;
    │   │   │                    already in the air after a hold: DO_REPOSITION over where it is)
    │   │   ├── Hover point (once, with vtol.hover_enu): ENU -> NED -> lat/lon from home, DO_REPOSITION, flown as a multicopter
    │   │   ├── Wing-borne (once): transition to FW (EXTENDED_SYS_STATE FW) -> for each leg: go to (DO_REPOSITION)
    │   │   │                      -> vtol.land home: back to home (the local origin, DO_REPOSITION)
    │   │   └── Transition to MC: QLOITER (EXTENDED_SYS_STATE MC)
    │   └── Wait for guards: the failing guard's failsafe (by default QLOITER, as a plane LOITER; low battery QRTL/RTL and abort)
    └── Land: vtol.land home: QRTL (over home on the lift motors, then down); last: QLAND where it is; done when disarmed on the ground

How ArduPlane (a QuadPlane) is flown here, and why:

- GUIDED targets go as MAV_CMD_DO_REPOSITION: ArduPlane takes only the altitude from a position
  setpoint, global or local (SET_POSITION_TARGET_LOCAL_NED: MAV_FRAME_LOCAL_OFFSET_NED in GUIDED,
  its z alone). The hover point, given in ROS's ENU like the seed's local setpoints, is taken to
  NED and then to a latitude and longitude with home as the local origin.
- A plane circles a GUIDED point at WP_LOITER_RAD (60 m): a wing-borne leg counts as reached
  within the mission's acceptance radius (at least 70 m for a vtol, checked when the mission is
  loaded). Only with Q_GUIDED_MODE=1 does ArduPlane fly a GUIDED point on its lift motors, and only
  within WP_LOITER_RAD of the aircraft: the hover point needs both (its 50 m rule is checked too).
- DO_VTOL_TRANSITION works in AUTO only (QuadPlane::handle_do_vtol_transition: "VTOL transition
  only in AUTO"): to FW the aircraft is repositioned 600 m ahead (GUIDED flies wing-borne; with
  Q_GUIDED_MODE 1 the last ~140 m of a GUIDED target are a VTOL approach, so a nearer point never
  shows FW), to MC it is put in QLOITER; each transition counts only once EXTENDED_SYS_STATE says
  so, and fails after vtol.transition_timeout_s. With Q_GUIDED_MODE 1 each wing-borne leg ends in
  that approach (it is reached within the acceptance radius, on the lift motors).
- A plane cannot stop on a point: braking on the lift motors from cruise speed takes ~80 m. QRTL
  is ArduPlane's way back over home on the lift motors; it ends in the same descent as QLAND.
- The landing is not guarded: disarming is how it ends, and QRTL/QLAND are what ArduPlane's own
  failsafes do anyway; an executive hold would only stop it in the air.
- Each phase done is not flown again when a guard recovers or the mission resumes (a hold in
  QLOITER stops a wing-borne leg: the transition to FW comes again, then the same leg). A climb
  stopped by a guard goes on with DO_REPOSITION straight above the aircraft at the take-off height
  (ArduPlane refuses NAV_TAKEOFF in the air).
"""

from __future__ import annotations

import py_trees
from py_trees.common import OneShotPolicy

from executive.behaviours import ForEachLeg, GoTo, GoToLocal, Land, ParameterIs, SetMode, TakeOff, VtolTransition
from executive.mission.declaration import TreeDeclaration, vehicle_profile
from executive.mission.model import Mission, VtolOptions
from executive.trees.parts import failsafe_guarded, mission_root, preflight, standard_guards
from executive.world import frames

#: How close to the hover point (3-D) counts as there: a multicopter stops on a point.
HOVER_ACCEPTANCE_M = 2.0
#: How far ahead the transition to FW is aimed. With Q_GUIDED_MODE 1 ArduPlane flies the last ~140 m of a GUIDED
#: target as a VTOL approach (issue 14, SITL: "VTOL Position1 d=143.4" after a reposition 300 m ahead, FW never
#: reported); the transition must be done before that. SLT_Transition::update() (ArduPlane/quadplane.cpp) holds the
#: lift motors until the airspeed is above both AIRSPEED_MIN and Q_ASSIST_SPEED (18 m/s in quadplane.parm), then
#: blends them out over Q_TRANSITION_MS (5 s): at 2 m/s/s to a 25 m/s cruise that is ~81 m + ~112 m from a hover.
#: 600 m leaves ~190 m + 140 m with room to spare for a slower airframe or a head wind.
TRANSITION_AHEAD_M = 600.0


def once(name: str, *steps: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """``steps`` in order until they have all succeeded once; after that, SUCCESS without ticking them."""
    body = py_trees.composites.Sequence(name, memory=True, children=list(steps))
    return py_trees.decorators.OneShot(f"{name} (once)", body, OneShotPolicy.ON_SUCCESSFUL_COMPLETION)


def home_enu(options: VtolOptions) -> frames.Enu:
    """Home, the local origin, at the take-off height."""
    return frames.Enu(0.0, 0.0, options.takeoff_alt_m)


def flight(mission: Mission, options: VtolOptions) -> py_trees.behaviour.Behaviour:
    """Take-off, hover point, wing-borne route (and return home), back to multicopter."""
    limits = mission.limits
    steps: list[py_trees.behaviour.Behaviour] = [
        once(
            "Take off", SetMode(vehicle_profile(mission.vehicle).guided_mode), TakeOff(options.takeoff_alt_m, confirm_timeout_s=limits.leg_timeout_s)
        )
    ]
    if options.hover_enu is not None:
        point = frames.Enu(options.hover_enu.east_m, options.hover_enu.north_m, options.hover_enu.up_m)
        steps.append(once("Hover point", GoToLocal(point, HOVER_ACCEPTANCE_M, limits.leg_timeout_s, method="reposition")))
    leg = GoTo(limits.acceptance_radius_m, limits.leg_timeout_s, method="reposition", height_tolerance_m=limits.alt_tolerance_m)
    to_fw = VtolTransition("FW", options.transition_timeout_s, ahead_m=TRANSITION_AHEAD_M)
    wing_borne: list[py_trees.behaviour.Behaviour] = [to_fw, ForEachLeg(leg)]
    if options.land == "home":
        wing_borne.append(GoToLocal(home_enu(options), limits.acceptance_radius_m, limits.leg_timeout_s, name="Back to home", method="reposition"))
    steps += [once("Wing-borne", *wing_borne), VtolTransition("MC", options.transition_timeout_s)]
    return py_trees.composites.Sequence("Flight", memory=True, children=steps)


def land(mission: Mission, options: VtolOptions) -> py_trees.behaviour.Behaviour:
    """QRTL back over home (vtol.land home) or QLAND where the aircraft is (last); SUCCESS once disarmed on the ground."""
    if options.land == "home":
        return Land("QRTL", name="Land at home (QRTL)", confirm_timeout_s=mission.limits.leg_timeout_s)
    return Land("QLAND", name="Land here (QLAND)", confirm_timeout_s=mission.limits.leg_timeout_s)


def firmware_check(options: VtolOptions) -> py_trees.behaviour.Behaviour | None:
    """What the mission needs of ArduPlane's parameters, checked before anything moves: a hover point needs Q_GUIDED_MODE 1."""
    if options.hover_enu is None:
        return None
    why = (
        "the hover point (vtol.hover_enu) is flown on the lift motors only with Q_GUIDED_MODE 1; "
        "with 0 ArduPlane flies to it as a plane and circles it at WP_LOITER_RAD (QuadPlane::guided_mode_enabled)"
    )
    once_checked = ParameterIs("Q_GUIDED_MODE", (1.0,), why)
    return py_trees.decorators.OneShot("Firmware check (once)", once_checked, OneShotPolicy.ON_SUCCESSFUL_COMPLETION)


#: A vtol, its ``vtol:`` options (their defaults flown where the file has none); guided only. Its legs are flown at the
#: vtol's airspeed, not timed against limits.speed_m_s.
DECLARATION = TreeDeclaration(
    doc="VTOL transit: take off as a multicopter, fly the route as a plane, come back a multicopter and land",
    vehicles=frozenset({"vtol"}),
    auto_refused="its take-off, transitions and landing are the executive's",
    section="vtol",
)


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: vtol_transit`` mission."""
    options = mission.vtol or VtolOptions()
    work = failsafe_guarded(flight(mission, options), standard_guards(mission), mission, name="Guarded flight")
    check = firmware_check(options)
    return mission_root(mission, *([check] if check else []), preflight(mission), work, land(mission, options))
