"""The glider survey: a sailplane flown by ArduPlane, launched on lift motors, then from waypoint to waypoint under guards, then loitering.

Its module declares, beside ``build``, what the executive checks a mission against: the vehicle kind it
brings (``glider``: ArduPlane's modes, LOITER its safe mode, and the simulated vehicle it rides: the built-in
simulated ArduPlane QuadPlane, whose lift motors launch it), the firmware it needs, its RC switches and its
failsafe defaults.
"""

from __future__ import annotations

import py_trees
from pydantic import BaseModel, ConfigDict, Field

from executive.behaviours import ForEachLeg, GoTo, SetMode, TakeOff
from executive.mission.declaration import TreeDeclaration, VehicleKindSpec
from executive.trees.parts import failsafe_guarded, mission_root, preflight, safe_mode, standard_guards
from executive.trees.vtol_transit import once
from executive.world.dialect import mavlink
from executive.world.vehicles import PLANE_MODES, VehicleProfile

_R, _A = "resume", "abort"
GLIDER = VehicleKindSpec(
    profile=VehicleProfile(
        "glider",  # type: ignore[arg-type]  # a kind of the plugin's own
        mavlink.MAV_TYPE_FIXED_WING,  # ArduPlane says it is a fixed wing
        PLANE_MODES,
        safe_mode="LOITER",
        guided_mode="GUIDED",
        manual_mode="MANUAL",
        surface=False,
        pilot_modes=frozenset({"MANUAL", "STABILIZE", "FBWA"}),
    ),
    autopilots=frozenset({"ardupilot"}),
    failsafes={"link_loss": ("loiter", _R), "rc_takeover": ("wait", _R), "disarmed": ("wait", _R), "rc_loss": ("loiter", _R)}
    | {"ekf_loss": ("hold", _R), "gps_glitch": ("hold", _R), "heading_insane": ("hold", _R)}
    | {"battery_low": ("rtl", _A), "geofence_breach": ("rtl", _A), "energy": ("rtl", _A), "keep_out": ("rtl", _A)},
    energy_seeds=(5.0, 16.0),  # the simulated QuadPlane's, as the built-in vtol's
    reactions={"hold": ("LOITER", "LOITER"), "loiter": ("LOITER", "LOITER"), "rtl": ("RTL", "RTL")},
    no_reaction={"surface": "a glider cannot surface", "disarm": "disarming a glider in flight would drop it"},
    simulator="vtol",  # the simulated ArduPlane (a QuadPlane): it launches on the lift motors, then flies the wing
)


class GliderOptions(BaseModel):
    """The mission's ``glider:`` section, the tree's own."""

    model_config = ConfigDict(strict=True, extra="forbid", frozen=True)
    launch_alt_m: float = Field(40.0, ge=20.0, le=120.0, description="how high the lift motors take it before it flies the wing")
    thermal_channel: int = Field(7, ge=5, le=16, description="the pilot's thermal switch (ArduPlane's FLTMODE_CH is 8)")


def switches(mission):
    """The take-over switch, and the pilot's thermal switch (``glider.thermal_channel``)."""
    return {mission.rc.takeover_channel: "the take-over switch", DECLARATION.options_of(mission).thermal_channel: "the thermal switch"}


DECLARATION = TreeDeclaration(
    doc="a sailplane's survey: launched on its lift motors, then each waypoint in GUIDED under guards, then loiter",
    vehicles=frozenset({"glider"}),
    needs=("ardupilot", "it soars in ArduPlane's THERMAL mode"),
    section="glider",
    options=GliderOptions,
    rc_switches=switches,
    failsafes={"link_loss": ("rtl", _A)},
    timed_legs=True,
    vehicle_kinds=(GLIDER,),
)


def build(mission):
    limits, options = mission.limits, DECLARATION.options_of(mission)
    launch = once("Launch", SetMode("GUIDED"), TakeOff(options.launch_alt_m, confirm_timeout_s=limits.leg_timeout_s))
    leg = GoTo(limits.acceptance_radius_m, limits.leg_timeout_s, method="reposition")  # ArduPlane flies GUIDED to a DO_REPOSITION
    route = failsafe_guarded(
        py_trees.composites.Sequence("Flight", memory=True, children=[launch, ForEachLeg(leg)]), standard_guards(mission), mission
    )
    return mission_root(mission, preflight(mission), route, SetMode(safe_mode(mission), name="Loiter at the end"))
