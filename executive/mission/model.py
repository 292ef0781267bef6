"""The mission file format (version 1), as strict pydantic models.

Strict means: no silent coercion (``"5"`` is not a number, ``yes`` is not a float), no unknown
fields, every value in range. Rules that relate several fields (a waypoint speed inside the
mission's speed limits, say) are in :func:`cross_field_errors` so that each gets its own
location in the file.

The ``failsafe:`` section says, per condition, what the executive does when it becomes true during
the guarded part of a mission: a *reaction* commanded in the same tick, then a *recovery* (resume
the same leg once the condition clears, within ``timeout_s``, default ``limits.recovery_timeout_s``;
or abort the mission at once, the vehicle left in the reaction's mode). An entry, or a field of
one, left out takes the default of the vehicle kind, or of the tree where a seed system has its
own rule (:func:`failsafe_policy`). Defaults (reaction, recovery):

================  ==============  ==============  =================  ============================
condition         rover           boat            sub                vtol
================  ==============  ==============  =================  ============================
link_loss         hold, resume    loiter, resume  surface, resume    hold, resume
rc_takeover       wait, resume    wait, resume    wait, resume       wait, resume
disarmed          wait, resume    wait, resume    wait, resume       wait, resume
rc_loss           hold, resume    loiter, resume  hold, resume       hold, resume
ekf_loss          hold, resume    hold, resume    hold, resume       hold, resume
gps_glitch        hold, resume    hold, resume    hold, resume       hold, resume
heading_insane    hold, resume    hold, resume    hold, resume       hold, resume
battery_low       rtl, abort      rtl, abort      surface, abort     rtl, abort
geofence_breach   hold, abort     rtl, abort      surface, abort     rtl, abort
================  ==============  ==============  =================  ============================

rc_takeover and disarmed are a person's acts (or the autopilot's own failsafe's): a person always wins, so
their reaction is ``wait`` (hands off) and nothing else; any other is refused at load
(:data:`PERSON_CONDITIONS`). Their recovery is the mission's to choose.

Seed rules, the defaults of their trees: ``goto_sample`` (the ASV) ekf_loss disarm, resume (MANUAL,
disarmed until the EKF recovers, then re-armed) and rc_takeover wait, abort (the RC leaving auto
ends the go-to); ``auv_survey`` link_loss hold, resume (the survey holds in POSHOLD).

Reactions (:data:`REACTION_MODES`): ``hold`` rover/boat HOLD, sub POSHOLD, vtol QLOITER; ``loiter``
rover/boat LOITER, sub POSHOLD, vtol QLOITER; ``rtl`` rover/boat RTL, vtol QRTL (no sub); ``surface``
sub SURFACE only; ``disarm`` the manual mode, then disarm, re-armed on resume (no vtol); ``wait``
nothing: hands off. A vtol flying as a plane holds, loiters in LOITER and returns in RTL.
heading_insane is judged on rovers and boats only (the heading filter checks the compass against
the course over ground, which a sub or a vtol does not follow); geofence_breach only with a
``geofence:`` section; rc_loss once an RC transmitter has been seen (or, ugv_rc_route, stale RC).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Annotated, Any, Literal, get_args

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, WithJsonSchema, model_validator

from executive.geo import distance
from executive.geofence import Geofence, open_ring, polygon_problems
from executive.mission.errors import Path
from executive.vehicles import AUTOPILOT_VEHICLES, PROFILES, AutopilotName

VehicleKind = Literal["rover", "boat", "sub", "vtol"]
ControlMode = Literal["depth", "altitude"]

_STRICT = ConfigDict(strict=True, extra="forbid", frozen=True, allow_inf_nan=False)

#: ``tree:``: a name (built in, or a plugin's), or ``module.path:function`` (``module.path`` alone: its ``build``).
TREE_NAME = r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*(:[A-Za-z_][A-Za-z0-9_]*)?$"
_TREE_NAME_RE = re.compile(TREE_NAME)


def _tree_value(value: object) -> object:
    """``tree:`` is a tree's name or a tree composed in the file (a mapping, checked by :mod:`executive.composition`)."""
    if isinstance(value, str) and not _TREE_NAME_RE.match(value):
        raise ValueError("not a tree name (a name, module.path or module.path:function) nor a composed tree (a mapping)")
    if not isinstance(value, str | dict):
        raise ValueError("expected a tree name, or a tree composed in the file (a mapping with node: or use:)")
    return value


#: ``tree:``'s JSON schema; ``executive.mission.schema`` puts the node catalogue's in place of the composed tree's.
TREE_SCHEMA = {
    "anyOf": [
        {"type": "string", "pattern": TREE_NAME, "description": "a tree by name: built in, a plugin's, or module:function"},
        {"type": "object", "description": "a tree composed in the file: node: or use:, with parameters (executive behaviours)"},
    ],
    "default": "waypoints",
    "description": "the tree the mission runs",
}
#: ``tree:``: a name, or a mapping composing the node catalogue (:mod:`executive.composition`).
TreeSpec = Annotated[str | dict[str, Any], BeforeValidator(_tree_value), WithJsonSchema(TREE_SCHEMA)]


def tree_name(mission: Mission) -> str | None:
    """The name of the mission's tree; None for a tree composed in the file."""
    return mission.tree if isinstance(mission.tree, str) else None


#: A vtol flies its legs as a plane and circles each point at WP_LOITER_RAD (60 m): a leg counts as reached from farther out.
VTOL_MIN_ACCEPTANCE_RADIUS_M = 70.0
#: ArduPlane (Q_GUIDED_MODE=1) flies a GUIDED target on its lift motors only within WP_LOITER_RAD of the aircraft: 60 m less a margin.
VTOL_HOVER_RADIUS_M = 50.0

Latitude = Annotated[float, Field(ge=-90.0, le=90.0, description="WGS84 latitude, degrees")]
Longitude = Annotated[float, Field(ge=-180.0, le=180.0, description="WGS84 longitude, degrees")]


class Range(BaseModel):
    """An inclusive ``[min, max]`` interval."""

    model_config = _STRICT
    min: float
    max: float

    @model_validator(mode="after")
    def _ordered(self) -> Range:
        if self.min > self.max:
            raise ValueError(f"min ({self.min}) is greater than max ({self.max})")
        return self

    def __contains__(self, value: float) -> bool:
        return self.min <= value <= self.max


#: Limits a vehicle kind has by default, where its seed system says other than :class:`Limits`: the AUV (Zeno)
#: takes speeds of 0.1-1 m/s and refuses a mission with a waypoint over 1 km from it.
VEHICLE_LIMITS: dict[str, dict[str, object]] = {
    "sub": {"speed_m_s": {"min": 0.1, "max": 1.0}, "max_goal_distance_m": 1000.0},
}


class Limits(BaseModel):
    """Numbers the guards and actions enforce (a sub's defaults: :data:`VEHICLE_LIMITS`)."""

    model_config = _STRICT
    acceptance_radius_m: float = Field(2.0, gt=0.0, le=1000.0, description="a waypoint counts as reached within this distance")
    leg_timeout_s: float = Field(120.0, gt=0.0, le=86400.0, description="a leg taking longer than this is abandoned")
    max_goal_distance_m: float = Field(
        5000.0,
        gt=0.0,
        le=100_000.0,
        description="a waypoint farther than this from the vehicle is refused, at upload and at start (sub: 1000 by default)",
    )
    speed_m_s: Range = Field(default_factory=lambda: Range(min=0.1, max=5.0), description="allowed waypoint speeds (sub: 0.1-1 by default)")
    depth_m: Range = Field(default_factory=lambda: Range(min=0.0, max=100.0), description="allowed depths (sub)")
    altitude_m: Range = Field(default_factory=lambda: Range(min=2.0, max=100.0), description="allowed altitudes above seabed/ground")
    link_timeout_s: float = Field(3.0, gt=0.0, le=60.0, description="heartbeat age after which the link counts as lost")
    recovery_timeout_s: float = Field(120.0, gt=0.0, le=86400.0, description="how long a failed guard may take to recover before the mission aborts")
    ekf_wait_s: float = Field(120.0, gt=0.0, le=3600.0, description="how long pre-flight waits for the EKF to become ready")
    battery_min_pct: float | None = Field(
        20.0, ge=0.0, le=100.0, description="remaining battery below this, percent, fails the battery guard (null: not checked)"
    )
    battery_min_v: float | None = Field(None, gt=0.0, le=1000.0, description="battery voltage below this fails the battery guard (null: not checked)")


class SwitchChannels(BaseModel):
    """Which RC channel carries each switch of an AgileX-style transmitter (SWA..SWD, knob VRA), for ``source: mavlink``."""

    model_config = _STRICT
    swa: int = Field(5, ge=1, le=18, description="two-position switch A (route edit trigger when down)")
    swb: int = Field(6, ge=1, le=18, description="three-position switch B")
    swc: int = Field(7, ge=1, le=18, description="three-position switch C (up MANUAL, middle AUTO, down aux mode)")
    swd: int = Field(8, ge=1, le=18, description="two-position switch D (down arm, up disarm)")
    knob: int = Field(9, ge=1, le=18, description="knob VRA, mapped to [-100, 100]")


class RcConfig(BaseModel):
    """Where the RC receiver is read and what its switches mean."""

    model_config = _STRICT
    source: Literal["mavlink", "can"] = Field("mavlink", description="RC from the autopilot's RC_CHANNELS or from the CAN bus (AgileX 0x241)")
    takeover_channel: int = Field(6, ge=1, le=18, description="RC channel whose high position means manual take-over (mavlink)")
    takeover_above_us: int = Field(1700, ge=800, le=2200, description="PWM above which the take-over channel is high")
    arm_channel: int | None = Field(
        None, ge=1, le=18, description="RC channel whose high position arms the vehicle in pre-flight (mavlink; goto_sample: 5, the ASV seed's)"
    )
    fresh_timeout_s: float = Field(1.0, gt=0.0, le=60.0, description="an RC report older than this (or a frozen CAN counter) is stale")
    switch_channels: SwitchChannels = Field(default_factory=SwitchChannels)


class InstrumentConfig(BaseModel):
    """The instrument that takes the samples: its ``type`` (a back end), and that back end's own fields.

    Built in: ``simulated`` (the built-in simulator only) and ``serial`` (``port``, ``baud``,
    ``columns``, ``units``: a line-protocol CTD or sonde); plugins add types (the
    ``executive.instruments`` entry-point group). Each back end checks its fields.
    """

    model_config = ConfigDict(strict=True, extra="allow", frozen=True, allow_inf_nan=False)
    type: str = Field(min_length=1, max_length=64, description="simulated, serial, or a plugin's type")


class SamplingOptions(BaseModel):
    """goto_sample: what happens at a sample point."""

    model_config = _STRICT
    duration_s: float = Field(10.0, gt=0.0, le=3600.0, description="how long the sampler reads at a sample point")
    rate_hz: float = Field(1.0, gt=0.0, le=100.0, description="sensor reads per second")
    sensors: list[str] = Field(default_factory=lambda: ["temperature", "conductivity", "ph", "dissolved_oxygen"], min_length=1, max_length=32)
    hold_mode: str = Field("LOITER", description="the mode the vehicle holds the sample point in")
    instrument: InstrumentConfig | None = Field(
        None, description="what takes the samples (default: the simulated instrument, with the built-in simulator only)"
    )
    require: Literal["all", "any"] = Field(
        "all",
        description="all: a sample is complete only with a reading of every sensor named; one missing any is recorded as partial and "
        "its sample point is not done. any: a reading of any one of them completes it (the missing ones are recorded)",
    )


class EnuPoint(BaseModel):
    """A point of the local frame in ROS's ENU axes: metres east, north and up from home (the local origin)."""

    model_config = _STRICT
    east_m: float = Field(ge=-10_000.0, le=10_000.0)
    north_m: float = Field(ge=-10_000.0, le=10_000.0)
    up_m: float = Field(ge=5.0, le=500.0, description="height above home")


class VtolOptions(BaseModel):
    """vtol_transit: take-off, transitions and landing."""

    model_config = _STRICT
    takeoff_alt_m: float = Field(30.0, ge=5.0, le=500.0, description="climb as a multicopter to this height above home")
    land: Literal["home", "last"] = Field("home", description="land back at home or at the last waypoint")
    transition_timeout_s: float = Field(30.0, gt=0.0, le=300.0, description="a transition not confirmed by EXTENDED_SYS_STATE by then fails")
    hover_enu: EnuPoint | None = Field(
        None,
        description=f"a local point flown as a multicopter after take-off, before the transition: within {VTOL_HOVER_RADIUS_M:g} m of home, "
        "and the aircraft needs Q_GUIDED_MODE=1 (simulator.q_guided_mode for the built-in one)",
    )


class RcRouteOptions(BaseModel):
    """ugv_rc_route: how long the operator has, and what switch C down selects."""

    model_config = _STRICT
    aux_mode: str | None = Field(None, description="mode for switch C down (None: ignored)")
    operator_timeout_s: float = Field(3600.0, gt=0.0, le=86400.0, description="give up if the operator has not started the route by then")


FailsafeCondition = Literal[
    "link_loss", "rc_takeover", "disarmed", "rc_loss", "ekf_loss", "gps_glitch", "heading_insane", "battery_low", "geofence_breach"
]
FailsafeReaction = Literal["hold", "loiter", "rtl", "surface", "disarm", "wait"]
FailsafeRecovery = Literal["resume", "abort"]
FAILSAFE_CONDITIONS: tuple[str, ...] = get_args(FailsafeCondition)

#: reaction -> vehicle kind -> the mode it commands (a vtol flying as a plane: the second); a kind left out has no such reaction.
REACTION_MODES: dict[str, dict[str, tuple[str, str]]] = {
    "hold": {"rover": ("HOLD", "HOLD"), "boat": ("HOLD", "HOLD"), "sub": ("POSHOLD", "POSHOLD"), "vtol": ("QLOITER", "LOITER")},
    "loiter": {"rover": ("LOITER", "LOITER"), "boat": ("LOITER", "LOITER"), "sub": ("POSHOLD", "POSHOLD"), "vtol": ("QLOITER", "LOITER")},
    "rtl": {"rover": ("RTL", "RTL"), "boat": ("RTL", "RTL"), "vtol": ("QRTL", "RTL")},
    "surface": {"sub": ("SURFACE", "SURFACE")},
    "disarm": {"rover": ("MANUAL", "MANUAL"), "boat": ("MANUAL", "MANUAL"), "sub": ("MANUAL", "MANUAL")},
}
_NO_REACTION = {"rtl": "a sub has no RTL: use surface", "surface": "only a sub can surface", "disarm": "disarming a vtol would drop it"}
#: Conditions that are a person's act: a person always wins, so their only reaction is ``wait`` (hands off); why, for the loader's error.
PERSON_CONDITIONS: dict[str, str] = {
    "rc_takeover": "a person who takes over always wins: the executive keeps its hands off (reaction wait), "
    "it never commands against the take-over switch",
    "disarmed": "a vehicle disarmed mid-mission was disarmed by a person (or by the autopilot's own failsafe), who always wins: "
    "the executive keeps its hands off (reaction wait)",
}

_R, _W, _A = "resume", "wait", "abort"
_COMMON = {"rc_takeover": (_W, _R), "disarmed": (_W, _R), "ekf_loss": ("hold", _R), "gps_glitch": ("hold", _R), "heading_insane": ("hold", _R)}
#: The default failsafe policy of each vehicle kind: condition -> (reaction, recovery). The table in the module docstring.
VEHICLE_FAILSAFES: dict[str, dict[str, tuple[str, str]]] = {
    "rover": _COMMON | {"link_loss": ("hold", _R), "rc_loss": ("hold", _R), "battery_low": ("rtl", _A), "geofence_breach": ("hold", _A)},
    "boat": _COMMON | {"link_loss": ("loiter", _R), "rc_loss": ("loiter", _R), "battery_low": ("rtl", _A), "geofence_breach": ("rtl", _A)},
    "sub": _COMMON | {"link_loss": ("surface", _R), "rc_loss": ("hold", _R), "battery_low": ("surface", _A), "geofence_breach": ("surface", _A)},
    "vtol": _COMMON | {"link_loss": ("hold", _R), "rc_loss": ("hold", _R), "battery_low": ("rtl", _A), "geofence_breach": ("rtl", _A)},
}
#: Seed systems' rules that differ from their vehicle's defaults: the defaults of their trees.
TREE_FAILSAFES: dict[str, dict[str, tuple[str, str]]] = {
    "goto_sample": {"ekf_loss": ("disarm", _R), "rc_takeover": (_W, _A)},
    "auv_survey": {"link_loss": ("hold", _R)},
    # The operator drives the tracked UGV (MANUAL) or ArduRover does (AUTO), and skidding tracks take the course off the
    # heading in every turn: a bad compass is flagged and journalled, the vehicle left as it is (a mission may say hold).
    "ugv_rc_route": {"heading_insane": (_W, _R)},
}


class FailsafeRule(BaseModel):
    """What the executive does when one condition becomes true; a field left out takes the default."""

    model_config = _STRICT
    reaction: FailsafeReaction | None = Field(
        None, description="commanded in the tick the condition becomes true: hold, loiter, rtl, surface, disarm (manual mode), wait (hands off)"
    )
    recovery: FailsafeRecovery | None = Field(
        None, description="resume: the same leg once the condition clears; abort: the mission ends at once, the vehicle left in the reaction's mode"
    )
    timeout_s: float | None = Field(
        None, gt=0.0, le=86400.0, description="resume: how long the condition may last before the mission aborts (default limits.recovery_timeout_s)"
    )


class FailsafeConfig(BaseModel):
    """failsafe: one entry per condition (see the table of defaults in executive/mission/model.py)."""

    model_config = _STRICT
    link_loss: FailsafeRule | None = Field(None, description="no HEARTBEAT from the autopilot within limits.link_timeout_s")
    rc_takeover: FailsafeRule | None = Field(None, description="a person takes over: the RC take-over switch high (or out of AUTO)")
    disarmed: FailsafeRule | None = Field(None, description="the vehicle disarmed mid-mission (a pilot, or the autopilot's own failsafe)")
    rc_loss: FailsafeRule | None = Field(None, description="the RC transmitter seen during the mission is gone, or its reports are stale")
    ekf_loss: FailsafeRule | None = Field(None, description="the EKF has no position estimate or its variances are over the threshold")
    gps_glitch: FailsafeRule | None = Field(None, description="the EKF flags GPS_GLITCHING")
    heading_insane: FailsafeRule | None = Field(None, description="the heading filter does not trust the compass (/heading/ok false)")
    battery_low: FailsafeRule | None = Field(None, description="the battery below limits.battery_min_pct or limits.battery_min_v")
    geofence_breach: FailsafeRule | None = Field(None, description="the vehicle outside the mission's geofence (only with a geofence: section)")


@dataclass(frozen=True)
class FailsafePolicy:
    """One condition's policy, every field decided."""

    condition: str
    reaction: str
    recovery: str
    timeout_s: float


class Home(BaseModel):
    """Where the vehicle is expected to start (the simulated vehicle starts here)."""

    model_config = _STRICT
    lat: Latitude
    lon: Longitude
    heading_deg: float = Field(0.0, ge=0.0, lt=360.0)


class Vertex(BaseModel):
    """A corner of the geofence polygon."""

    model_config = _STRICT
    lat: Latitude
    lon: Longitude


class GeofenceConfig(BaseModel):
    """Where the vehicle may be: inside a polygon, within a distance of home, or both."""

    model_config = _STRICT
    polygon: Annotated[list[Vertex], Field(min_length=3, max_length=500)] | None = Field(
        None, description="the fence's corners in order (either direction; a last corner repeating the first is allowed); must not cross itself"
    )
    max_distance_from_home_m: float | None = Field(
        None, gt=0.0, le=1_000_000.0, description="how far from home the vehicle may be (the autopilot's home, else the mission's home)"
    )

    def fence(self) -> Geofence:
        """The :class:`Geofence` value the guard checks (the polygon must be valid: see cross_field_errors)."""
        return Geofence(tuple((v.lat, v.lon) for v in self.polygon or ()), self.max_distance_from_home_m)


class Waypoint(BaseModel):
    """One point of the route."""

    model_config = _STRICT
    lat: Latitude
    lon: Longitude
    alt_m: float = Field(0.0, ge=-1000.0, le=10_000.0, description="altitude above home (air vehicles)")
    name: str | None = Field(None, max_length=64)
    speed_m_s: float | None = Field(None, gt=0.0, description="speed on the leg to this point")
    depth_m: float | None = Field(None, ge=0.0, description="target depth (sub, control_mode depth)")
    altitude_m: float | None = Field(None, gt=0.0, description="height above the seabed (sub, control_mode altitude)")
    control_mode: ControlMode | None = Field(None, description="sub: hold a depth or an altitude above the seabed")
    sample: bool = Field(False, description="goto_sample: hold here and run the sampler")


class SimulatorOptions(BaseModel):
    """How ``executive run`` sets up its built-in simulated vehicle (ignored with --mavlink)."""

    model_config = _STRICT
    model: Literal["rover", "boat", "bunker", "sub", "vtol"] | None = Field(None, description="simulated vehicle (default: the vehicle kind)")
    events: str | None = Field(None, min_length=1, description="event file (faults, operator inputs) for the simulator, relative to the mission")
    ekf_ready_after_s: float = Field(40.0, ge=0.0, le=600.0, description="how long the simulated EKF takes to use GPS after boot")
    params: dict[str, float] = Field(
        default_factory=dict, description="firmware parameters set differently from their defaults (MODE_CH: 0 frees channel 8)"
    )
    q_guided_mode: int = Field(
        0, ge=0, le=1, description="vtol: ArduPlane's Q_GUIDED_MODE (1: GUIDED targets end in a hover; near ones are flown as a multicopter)"
    )
    seabed_depth_m: float = Field(30.0, gt=1.0, le=1000.0, description="sub: water depth under the start point (ArduSub's SITL: 50 m)")
    rangefinder_max_m: float = Field(
        30.0, gt=1.0, le=700.0, description="sub: the downward rangefinder's maximum, RNGFND1_MAX (ArduSub's default sonar: 30 m)"
    )


class Mission(BaseModel):
    """A mission file."""

    model_config = ConfigDict(
        strict=True,
        extra="forbid",
        frozen=True,
        allow_inf_nan=False,
        # for editors: an empty route only for ugv_rc_route, whose operator records it (cross_field_errors says so too)
        json_schema_extra={
            "anyOf": [
                {"type": "object", "required": ["tree"], "properties": {"tree": {"const": "ugv_rc_route"}}},
                {"type": "object", "properties": {"waypoints": {"minItems": 1}}},
            ]
        },
    )
    version: Literal[1] = Field(description="mission file format version")
    name: str = Field(min_length=1, max_length=128)
    vehicle: VehicleKind
    autopilot: AutopilotName | None = Field(
        None, description="the autopilot firmware (default: the one the HEARTBEAT names); px4 starts a simulated PX4 without --mavlink"
    )
    tree: TreeSpec = Field(
        "waypoints",
        description="the tree: a built-in one (a module of trees/), a plugin's (entry point group executive.trees), "
        "module:function of a module on the Python path (module alone: its build), or a tree composed in the file (a mapping)",
    )
    description: str | None = Field(None, max_length=4096)
    auto_arm: bool = Field(False, description="arm the vehicle in pre-flight (else wait for the operator to arm it)")
    home: Home | None = None
    geofence: GeofenceConfig | None = Field(None, description="where the vehicle may be")
    limits: Limits = Field(default_factory=Limits)
    rc: RcConfig = Field(default_factory=RcConfig)
    failsafe: FailsafeConfig = Field(default_factory=FailsafeConfig, description="what each failing condition makes the executive do")
    sampling: SamplingOptions | None = Field(None, description="goto_sample options")
    vtol: VtolOptions | None = Field(None, description="vtol_transit options")
    rc_route: RcRouteOptions | None = Field(None, description="ugv_rc_route options")
    simulator: SimulatorOptions | None = Field(None, description="the built-in simulated vehicle for `executive run` without --mavlink")
    waypoints: list[Waypoint] = Field(max_length=100_000, description="the route; only ugv_rc_route may start empty (the operator records it)")

    @model_validator(mode="before")
    @classmethod
    def _vehicle_limits(cls, data: object) -> object:
        """The vehicle kind's default limits (:data:`VEHICLE_LIMITS`) where the file gives none."""
        if not isinstance(data, dict) or not isinstance(data.get("vehicle"), str) or data["vehicle"] not in VEHICLE_LIMITS:
            return data
        limits = data.get("limits", {})
        if not isinstance(limits, dict):
            return data  # the error is reported as it is
        return {**data, "limits": VEHICLE_LIMITS[data["vehicle"]] | limits}

    @model_validator(mode="before")
    @classmethod
    def _tree_rc(cls, data: object) -> object:
        """The ASV seed's RC: channel 5 high arms the vehicle (goto_sample, where the file says nothing else)."""
        if not isinstance(data, dict) or data.get("tree") != "goto_sample":
            return data
        rc = data.get("rc", {})
        if not isinstance(rc, dict) or "arm_channel" in rc or rc.get("source", "mavlink") != "mavlink":
            return data
        return {**data, "rc": {**rc, "arm_channel": 5}}


_PARAM_NAME = re.compile(r"[A-Z][A-Z0-9_]{0,15}")

#: Tree -> the vehicle kinds it can drive and the options section it reads.
TREE_RULES: dict[str, tuple[frozenset[str], str | None]] = {
    "waypoints": (frozenset({"rover", "boat", "sub", "vtol"}), None),
    "goto_sample": (frozenset({"rover", "boat"}), "sampling"),
    "auv_survey": (frozenset({"sub"}), None),
    "vtol_transit": (frozenset({"vtol"}), "vtol"),
    "ugv_rc_route": (frozenset({"rover"}), "rc_route"),
}


def rc_switch_channels(mission: Mission) -> dict[int, str]:
    """The RC channels whose positions this mission reads from the autopilot (``rc.source: mavlink``), each with what it is.

    Empty with RC from CAN: then the autopilot's own RC channels are not the mission's switches.
    """
    rc = mission.rc
    if rc.source != "mavlink":
        return {}
    if mission.tree == "ugv_rc_route":  # switch C is the person's: the take-over channel is not read
        c = rc.switch_channels
        found = {c.knob: "knob VRA", c.swd: "switch D", c.swc: "switch C", c.swb: "switch B", c.swa: "switch A"}
    else:
        found = {rc.takeover_channel: "the take-over switch"}
    if rc.arm_channel is not None:
        found.setdefault(rc.arm_channel, "the arm switch")
    return dict(sorted(found.items()))


#: Trees that need what only ArduPilot does, and why.
ARDUPILOT_ONLY_TREES: dict[str, str] = {
    "ugv_rc_route": "its operator drives it with ArduRover's modes and switches (arming only in MANUAL, switch C to AUTO)",
}


def autopilot_errors(mission: Mission, autopilot: str) -> list[str]:
    """Why ``autopilot`` cannot fly ``mission`` (empty when it can)."""
    errors = []
    kinds = AUTOPILOT_VEHICLES[autopilot]
    if mission.vehicle not in kinds:
        errors.append(f"{autopilot} drives {', '.join(sorted(kinds))} here, not a {mission.vehicle}")
    name = tree_name(mission)
    if autopilot != "ardupilot" and name in ARDUPILOT_ONLY_TREES:
        errors.append(f"tree {name} needs ArduPilot: {ARDUPILOT_ONLY_TREES[name]}")
    return errors


def cross_field_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Rules between fields; each error is the path of the offending value and why."""
    errors: list[tuple[Path, str]] = []
    limits = mission.limits
    name = tree_name(mission)
    kinds, section = TREE_RULES.get(name or "", (frozenset({mission.vehicle}), None))
    if mission.vehicle not in kinds:
        errors.append((("tree",), f"tree {mission.tree} drives {', '.join(sorted(kinds))}, not a {mission.vehicle}"))
    for other in ("sampling", "vtol", "rc_route") if name is not None else ():  # a composed tree's nodes read what they need
        if other != section and getattr(mission, other) is not None:
            errors.append(((other,), f"only used by tree {next(t for t, (_, s) in TREE_RULES.items() if s == other)} (tree is {mission.tree})"))
    aux_mode = mission.rc_route.aux_mode if mission.rc_route is not None else None
    if aux_mode is not None and aux_mode.upper() not in PROFILES[mission.vehicle].modes:
        known = ", ".join(m for m in PROFILES[mission.vehicle].modes if m != "INITIALISING")
        errors.append((("rc_route", "aux_mode"), f"{aux_mode!r}: not a {mission.vehicle} mode (known: {known})"))
    if not mission.waypoints and mission.tree != "ugv_rc_route":
        errors.append((("waypoints",), "at least one waypoint is needed"))
    if mission.tree == "goto_sample" and not any(wp.sample for wp in mission.waypoints):
        errors.append((("waypoints",), "goto_sample needs at least one waypoint with sample: true"))
    if mission.tree != "goto_sample" and name is not None:  # a composed tree: its sample node (executive.composition)
        errors += [(("waypoints", i, "sample"), "only goto_sample takes samples") for i, wp in enumerate(mission.waypoints) if wp.sample]
    for i, wp in enumerate(mission.waypoints):
        here: Path = ("waypoints", i)
        if wp.speed_m_s is not None and wp.speed_m_s not in limits.speed_m_s:
            errors.append(((*here, "speed_m_s"), f"{wp.speed_m_s} m/s is outside limits.speed_m_s "
                           f"[{limits.speed_m_s.min}, {limits.speed_m_s.max}]"))  # fmt: skip
        sub_fields = ("depth_m", "altitude_m", "control_mode")
        if mission.vehicle != "sub":
            for field in sub_fields:
                if getattr(wp, field) is not None:
                    errors.append(((*here, field), f"only a sub has {field} (vehicle is {mission.vehicle})"))
            continue
        if wp.depth_m is not None and wp.depth_m not in limits.depth_m:
            errors.append(((*here, "depth_m"), f"{wp.depth_m} m is outside limits.depth_m "
                           f"[{limits.depth_m.min}, {limits.depth_m.max}]"))  # fmt: skip
        if wp.altitude_m is not None and wp.altitude_m not in limits.altitude_m:
            errors.append(((*here, "altitude_m"), f"{wp.altitude_m} m is outside limits.altitude_m "
                           f"[{limits.altitude_m.min}, {limits.altitude_m.max}]"))  # fmt: skip
        if wp.control_mode == "altitude" and wp.altitude_m is None:
            errors.append(((*here, "altitude_m"), "control_mode altitude needs altitude_m"))
        if wp.control_mode != "altitude" and wp.altitude_m is not None:
            errors.append(((*here, "altitude_m"), "altitude_m is only used with control_mode altitude"))
    if mission.home is not None:  # the distance rule, as the vehicle will judge it at start (executive.reach) if it starts at home
        limit = limits.max_goal_distance_m
        for i, wp in enumerate(mission.waypoints):
            if (d := distance(mission.home.lat, mission.home.lon, wp.lat, wp.lon)) > limit:
                why = f"{d:.0f} m from home, over limits.max_goal_distance_m ({limit:g} m): refused at start with the vehicle at home"
                errors.append((("waypoints", i), why))
    if mission.vehicle == "vtol":
        errors += _vtol_errors(mission)
    if mission.simulator is not None and mission.simulator.q_guided_mode and (mission.simulator.model or mission.vehicle) != "vtol":
        errors.append((("simulator", "q_guided_mode"), "only the simulated vtol (ArduPlane) has Q_GUIDED_MODE"))
    if mission.simulator is not None:
        errors += [
            (("simulator", "params", name), "not a parameter name (capitals, digits and _, at most 16)")
            for name in mission.simulator.params
            if not _PARAM_NAME.fullmatch(name)
        ]
    if mission.rc.arm_channel is not None and mission.rc.source != "mavlink":
        errors.append((("rc", "arm_channel"), "an arm switch is read from the autopilot's RC channels (rc.source: mavlink)"))
    if mission.autopilot is not None:
        errors += [(("autopilot",), why) for why in autopilot_errors(mission, mission.autopilot)]
    if mission.geofence is not None:
        errors += _geofence_errors(mission)
    if mission.sampling is not None and mission.sampling.instrument is not None:
        from executive.io.instruments import option_errors  # the back ends (and their plugins) import this module

        errors += option_errors(mission.sampling.instrument, ("sampling", "instrument"))
    errors += _failsafe_errors(mission)
    return errors


def failsafe_policy(mission: Mission) -> dict[str, FailsafePolicy]:
    """Every condition's failsafe for this mission: its ``failsafe:`` entry, else the tree's default, else the vehicle kind's."""
    defaults = VEHICLE_FAILSAFES[mission.vehicle] | TREE_FAILSAFES.get(tree_name(mission) or "", {})
    policy = {}
    for condition in FAILSAFE_CONDITIONS:
        rule: FailsafeRule = getattr(mission.failsafe, condition) or FailsafeRule()
        reaction, recovery = defaults[condition]
        timeout_s = rule.timeout_s if rule.timeout_s is not None else mission.limits.recovery_timeout_s
        policy[condition] = FailsafePolicy(condition, rule.reaction or reaction, rule.recovery or recovery, timeout_s)
    return policy


def _failsafe_errors(mission: Mission) -> list[tuple[Path, str]]:
    """A person's act is never reacted to; each reaction exists for the vehicle; a time limit only where the mission resumes."""
    errors: list[tuple[Path, str]] = []
    policy = failsafe_policy(mission)
    for condition in FAILSAFE_CONDITIONS:
        rule: FailsafeRule | None = getattr(mission.failsafe, condition)
        if rule is None:
            continue
        here: Path = ("failsafe", condition)
        reaction = policy[condition].reaction
        if reaction != "wait" and condition in PERSON_CONDITIONS:
            errors.append(((*here, "reaction"), f"{reaction}: {PERSON_CONDITIONS[condition]}"))
        elif reaction != "wait" and mission.vehicle not in REACTION_MODES[reaction]:
            errors.append(((*here, "reaction"), f"{reaction}: not for a {mission.vehicle} ({_NO_REACTION[reaction]})"))
        elif reaction == "disarm" and mission.tree == "ugv_rc_route":
            errors.append(((*here, "reaction"), "disarm: not in tree ugv_rc_route (the operator arms and disarms with switch D)"))
        if condition == "geofence_breach" and policy[condition].recovery == "resume" and reaction != "rtl":
            # a recovery that cannot happen from where the reaction leaves the vehicle: held outside, it stays outside
            errors.append(
                (
                    (*here, "recovery"),
                    f"resume after {reaction}: a vehicle held outside the fence never comes back in; use reaction rtl, or recovery abort",
                )
            )
        if rule.timeout_s is not None and policy[condition].recovery == "abort":
            errors.append(((*here, "timeout_s"), "recovery abort ends the mission at once: a time limit is only for resume"))
    return errors


def _vtol_errors(mission: Mission) -> list[tuple[Path, str]]:
    """A vtol's legs are flown as a plane; its hover point as a multicopter, near home."""
    errors: list[tuple[Path, str]] = []
    radius = mission.limits.acceptance_radius_m
    if radius < VTOL_MIN_ACCEPTANCE_RADIUS_M:
        default = "" if "acceptance_radius_m" in mission.limits.model_fields_set else " (the default)"
        errors.append((("limits", "acceptance_radius_m"), f"{radius:g} m{default} is too small for a vtol: it flies its legs as a plane, "
                       f"circling each point at WP_LOITER_RAD (60 m); use at least {VTOL_MIN_ACCEPTANCE_RADIUS_M:g} m"))  # fmt: skip
    hover = mission.vtol.hover_enu if mission.vtol is not None else None
    if hover is not None and math.hypot(hover.east_m, hover.north_m) > VTOL_HOVER_RADIUS_M:
        errors.append((("vtol", "hover_enu"), f"{math.hypot(hover.east_m, hover.north_m):.0f} m from home, over {VTOL_HOVER_RADIUS_M:g} m: "
                       "ArduPlane flies a farther GUIDED target as a plane, not on its lift motors"))  # fmt: skip
    return errors


def _geofence_errors(mission: Mission) -> list[tuple[Path, str]]:
    """The fence is usable, and the home and every waypoint of the mission are inside it."""
    config = mission.geofence
    assert config is not None
    if config.polygon is None and config.max_distance_from_home_m is None:
        return [(("geofence",), "a geofence needs a polygon, max_distance_from_home_m or both")]
    if config.polygon is not None:
        problems = polygon_problems(open_ring([(v.lat, v.lon) for v in config.polygon]))
        if problems:
            return [(("geofence", "polygon", i), why) for i, why in problems]
    fence = config.fence()
    home = (mission.home.lat, mission.home.lon) if mission.home else None
    if home is None:  # the distance rule waits for the autopilot's home, at run time
        fence = Geofence(fence.polygon)
    points: list[tuple[Path, float, float]] = [(("home",), *home)] if home else []
    points += [(("waypoints", i), wp.lat, wp.lon) for i, wp in enumerate(mission.waypoints)]
    errors: list[tuple[Path, str]] = []
    for path, lat, lon in points:
        why = fence.why_outside(lat, lon, home)
        if why:
            errors.append((path, f"outside the geofence: {why}"))
    return errors
