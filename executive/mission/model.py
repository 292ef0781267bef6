"""The mission file format (version 1), as strict pydantic models.

Strict means: no silent coercion (``"5"`` is not a number, ``yes`` is not a float), no unknown
fields, every value in range. Rules that relate several fields (a waypoint speed inside the
mission's speed limits, say) are in :func:`executive.mission.rules.cross_field_errors` so that each gets its own
location in the file.

The ``failsafe:`` section's defaults and reactions are tables of their own: :mod:`executive.mission.failsafes`.
"""

from __future__ import annotations

import re
from functools import cache
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, WithJsonSchema, create_model, model_validator

from executive import registry
from executive.mission.declaration import BUILT_IN_KINDS, declared, kind_spec, plugin_kinds
from executive.mission.failsafes import FailsafeReaction, FailsafeRecovery
from executive.world.geofence import Geofence
from executive.world.vehicles import AutopilotName

VehicleKind = Literal["rover", "boat", "sub", "vtol"]
ControlMode = Literal["depth", "altitude"]

_STRICT = ConfigDict(strict=True, extra="forbid", frozen=True, allow_inf_nan=False)

#: ``tree:``: a name (built in, or a plugin's), or ``module.path:function`` (``module.path`` alone: its ``build``).
TREE_NAME = r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*(:[A-Za-z_][A-Za-z0-9_]*)?$"
_TREE_NAME_RE = re.compile(TREE_NAME)


def _tree_value(value: object) -> object:
    """``tree:`` is a tree's name or a tree composed in the file (a mapping, checked by :mod:`executive.tree.composition`)."""
    if isinstance(value, str) and not _TREE_NAME_RE.match(value):
        raise ValueError("not a tree name (a name, module.path or module.path:function) nor a composed tree (a mapping)")
    if not isinstance(value, str | dict):
        raise ValueError("expected a tree name, or a tree composed in the file (a mapping with node: or use:)")
    return value


def _vehicle_kind(value: object) -> object:
    """A vehicle kind: built in, or a plugin's tree's own (:attr:`TreeDeclaration.vehicle_kinds`); said as a Literal's error."""
    if isinstance(value, str) and (value in BUILT_IN_KINDS or kind_spec(value) is not None):
        return value
    kinds = [*BUILT_IN_KINDS, *plugin_kinds()]
    raise ValueError(f"Input should be {', '.join(map(repr, kinds[:-1]))} or {kinds[-1]!r}")  # as pydantic says it of a Literal


#: ``vehicle:``: a kind of ours (the schema's enum) or one a plugin's tree brings.
VehicleName = Annotated[str, BeforeValidator(_vehicle_kind), WithJsonSchema({"enum": list(BUILT_IN_KINDS), "type": "string"})]
#: The mission's options sections, each read by the tree that declares it (:attr:`TreeDeclaration.section`).
OPTION_SECTIONS = ("sampling", "vtol", "rc_route")
#: ``tree:``'s JSON schema; ``executive.tree.schema`` puts the node catalogue's in place of the composed tree's.
TREE_SCHEMA = {
    "anyOf": [
        {"type": "string", "pattern": TREE_NAME, "description": "a tree by name: built in, a plugin's, or module:function"},
        {"type": "object", "description": "a tree composed in the file: node: or use:, with parameters (executive behaviours)"},
    ],
    "default": registry.DEFAULT_TREE,
    "description": "the tree the mission runs",
}
#: ``tree:``: a name, or a mapping composing the node catalogue (:mod:`executive.tree.composition`).
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
    altitude_m: Range = Field(
        default_factory=lambda: Range(min=2.0, max=100.0),
        description="allowed altitudes above the seabed (sub): no leg, in any control mode, takes the sub closer to the seabed than min, "
        "as its sonar reads it",
    )
    seabed_floor: Literal["hold", "fail"] = Field(
        "hold",
        description="sub: a depth deeper than the water holds (the seabed, by the sonar, less altitude_m.min): hold: held at that floor, "
        "the leg judged reached there (a warning with the figures); fail: the leg fails",
    )
    water_depth_m: float | None = Field(
        None, gt=0.0, le=11_000.0, description="sub: the water depth over the route where known (a chart): validate refuses a depth it cannot hold"
    )
    alt_m: Range = Field(
        default_factory=lambda: Range(min=10.0, max=120.0),
        description="vtol: allowed heights above home of waypoints and take-off: by default 10 m (clear of people and trees) to "
        "120 m (the common ceiling for small drones: EU open category, FAA part 107's 400 ft)",
    )
    alt_tolerance_m: float = Field(
        10.0,
        gt=0.0,
        le=500.0,
        description="vtol: a waypoint counts as reached only within this of its height as well as acceptance_radius_m "
        "(10 m: PX4's NAV_FW_ALT_RAD, a wing-borne waypoint's altitude acceptance)",
    )
    link_timeout_s: float = Field(3.0, gt=0.0, le=60.0, description="heartbeat age after which the link counts as lost")
    recovery_timeout_s: float = Field(120.0, gt=0.0, le=86400.0, description="how long a failed guard may take to recover before the mission aborts")
    ekf_wait_s: float = Field(120.0, gt=0.0, le=3600.0, description="how long pre-flight waits for the EKF to become ready")
    battery_min_pct: float | None = Field(
        20.0, ge=0.0, le=100.0, description="remaining battery below this, percent, fails the battery guard (null: not checked)"
    )
    battery_min_v: float | None = Field(None, gt=0.0, le=1000.0, description="battery voltage below this fails the battery guard (null: not checked)")
    auto_horizon_legs: int = Field(
        3, ge=1, le=20, description="drive: auto: waypoints the autopilot holds beyond the current leg's (it stops at the last one it holds)"
    )


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
    """failsafe: one entry per condition (see the table of defaults in executive/mission/failsafes.py)."""

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
    energy: FailsafeRule | None = Field(None, description="the rest of the route and the way home no longer fit the battery (energy:)")
    keep_out: FailsafeRule | None = Field(
        None, description="the vehicle inside a keep-out zone, or heading into one closer than it can stop (geofence.keep_out)"
    )


class EnergyConfig(BaseModel):
    """energy: will the rest of the route and the way home fit the battery, above a reserve (executive.sensing.energy)."""

    model_config = _STRICT
    check: bool = Field(
        True, description="off: no energy rule for this mission (it runs on every mission whose vehicle reports its battery, energy: or not)"
    )
    capacity_wh: float | None = Field(
        None, gt=0.0, le=1_000_000.0, description="the pack's energy, Wh (else the autopilot's capacity in mAh times nominal_v)"
    )
    nominal_v: float | None = Field(
        None, gt=0.0, le=1000.0, description="the pack's nominal voltage, to turn the autopilot's mAh into Wh (PX4: BAT1_N_CELLS x 3.7 V)"
    )
    usable_pct: float = Field(100.0, gt=0.0, le=100.0, description="the share of the capacity that can be drawn at all")
    reserve_pct: float = Field(20.0, ge=0.0, lt=100.0, description="the share of the capacity kept when the vehicle is home")
    wh_per_km: float | None = Field(None, gt=0.0, le=100_000.0, description="seed of the consumption per km moved (else the kind's default)")
    wh_per_min: float | None = Field(None, ge=0.0, le=100_000.0, description="seed of the consumption per minute held (else the kind's default)")
    return_by: Literal["straight", "route"] = Field("straight", description="the way home: the straight line, or the route back")


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


class Circle(BaseModel):
    """A circle on the ground: its centre and radius."""

    model_config = _STRICT
    lat: Latitude
    lon: Longitude
    radius_m: float = Field(gt=0.0, le=1_000_000.0)


class Zone(BaseModel):
    """An area of the world, a polygon or a circle, with an optional name the checks' messages use."""

    # for editors: a shape (cross_field_errors also refuses two)
    model_config = ConfigDict(**_STRICT, json_schema_extra={"anyOf": [{"required": ["polygon"]}, {"required": ["circle"]}]})
    name: str | None = Field(None, min_length=1, max_length=64)
    polygon: Annotated[list[Vertex], Field(min_length=3, max_length=500)] | None = Field(
        None, description="corners in order (either direction; a last corner repeating the first is allowed); must not cross itself"
    )
    circle: Circle | None = Field(None, description="a circle instead of a polygon")


class RallyPoint(BaseModel):
    """A safe place to return to instead of home (QGroundControl's rally points)."""

    model_config = _STRICT
    lat: Latitude
    lon: Longitude
    alt_m: float = Field(0.0, ge=-1000.0, le=10_000.0, description="altitude above home (air vehicles)")
    name: str | None = Field(None, min_length=1, max_length=64)


class GeofenceConfig(BaseModel):
    """Where the vehicle may be: inside a polygon or any inclusion zone, within a distance of home, never in a keep-out zone."""

    model_config = _STRICT
    polygon: Annotated[list[Vertex], Field(min_length=3, max_length=500)] | None = Field(
        None, description="the fence's corners in order (either direction; a last corner repeating the first is allowed); must not cross itself"
    )
    max_distance_from_home_m: float | None = Field(
        None, gt=0.0, le=1_000_000.0, description="how far from home the vehicle may be (the autopilot's home, else the mission's home)"
    )
    inclusion: list[Zone] = Field(
        default_factory=list,
        max_length=100,
        description="more areas the route may use: every leg stays inside polygon or these (validate, start, upload, route edits)",
    )
    keep_out: list[Zone] = Field(
        default_factory=list, max_length=1000, description="areas no waypoint and no leg may enter, acceptance_radius_m as a margin (islands, piers)"
    )
    autopilot: Literal["upload", "enforce", "off"] = Field(
        "upload",
        description="the zones and rally_points on the autopilot at pre-flight (its fence and rally items, read back): upload sends them "
        "and leaves the autopilot's own fence settings as they are; enforce also switches its fence on (ArduPilot FENCE_ENABLE, "
        "FENCE_TYPE, FENCE_ACTION Hold; PX4 GF_ACTION Hold), left on after the mission; off sends nothing",
    )

    def fence(self) -> Geofence:
        """The :class:`Geofence` value the guard checks (the polygon must be valid: see cross_field_errors)."""
        polygons = tuple(tuple((v.lat, v.lon) for v in z.polygon) for z in self.inclusion if z.polygon is not None)
        circles = tuple((z.circle.lat, z.circle.lon, z.circle.radius_m) for z in self.inclusion if z.circle is not None)
        return Geofence(tuple((v.lat, v.lon) for v in self.polygon or ()), self.max_distance_from_home_m, polygons, circles)


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


def waypoint_label(index: int, name: str | None = None) -> str:
    """A waypoint as a person counts it, from 1, with its name: ``waypoint 7 'far'`` for ``waypoints[6]``."""
    return f"waypoint {index + 1}" + (f" {name!r}" if name else "")


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
    )
    version: Literal[1] = Field(description="mission file format version")
    name: str = Field(min_length=1, max_length=128)
    vehicle: VehicleName
    autopilot: AutopilotName | None = Field(
        None, description="the autopilot firmware (default: the one the HEARTBEAT names); px4 starts a simulated PX4 without --mavlink"
    )
    tree: TreeSpec = Field(
        registry.DEFAULT_TREE,
        description="the tree: a built-in one (a module of trees/), a plugin's (entry point group executive.trees), "
        "module:function of a module on the Python path (module alone: its build), or a tree composed in the file (a mapping)",
    )
    description: str | None = Field(None, max_length=4096)
    drive: Literal["guided", "auto"] = Field(
        "guided",
        description="guided: the executive sends each leg's target (GUIDED); auto: the autopilot drives its own mission in AUTO, "
        "holding only limits.auto_horizon_legs waypoints beyond the current leg, under the executive's supervision",
    )
    auto_arm: bool = Field(False, description="arm the vehicle in pre-flight (else wait for the operator to arm it)")
    home: Home | None = None
    geofence: GeofenceConfig | None = Field(None, description="where the vehicle may be")
    rally_points: list[RallyPoint] = Field(default_factory=list, max_length=100, description="safe places to return to besides home")
    limits: Limits = Field(default_factory=Limits)
    rc: RcConfig = Field(default_factory=RcConfig)
    failsafe: FailsafeConfig = Field(default_factory=FailsafeConfig, description="what each failing condition makes the executive do")
    sampling: SamplingOptions | None = Field(None, description="goto_sample options")
    vtol: VtolOptions | None = Field(None, description="vtol_transit options")
    rc_route: RcRouteOptions | None = Field(None, description="ugv_rc_route options")
    simulator: SimulatorOptions | None = Field(None, description="the built-in simulated vehicle for `executive run` without --mavlink")
    energy: EnergyConfig | None = Field(
        None, description="the battery's energy and reserve: the route and the way home must fit (said or not; check: off to opt out)"
    )
    waypoints: list[Waypoint] = Field(max_length=100_000, description="the route; only ugv_rc_route may start empty (the operator records it)")

    def energy_rule(self) -> EnergyConfig | None:
        """The energy rule's settings: the ``energy:`` block, else its defaults (every mission has the rule); None with ``check: off``."""
        if self.energy is None:
            return EnergyConfig()
        return self.energy if self.energy.check else None

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
        """The ``rc:`` settings the tree declares (:attr:`TreeDeclaration.rc_defaults`) where the file says nothing else."""
        if not isinstance(data, dict) or not isinstance(data.get("tree"), str):
            return data
        rc = data.get("rc", {})
        if not isinstance(rc, dict) or rc.get("source", "mavlink") != "mavlink":
            return data
        defaults = declared(data["tree"]).rc_defaults
        return {**data, "rc": {**defaults, **rc}} if any(key not in rc for key in defaults) else data


def _plugin_sections(trees: list[str]) -> dict[str, tuple[str, type[BaseModel]]]:
    """The options sections of their own the named trees declare: section -> (tree, its model); a mission's own field is not one."""
    found: dict[str, tuple[str, type[BaseModel]]] = {}
    for name in trees:
        declaration = declared(name)
        if declaration.section is not None and declaration.options is not None and declaration.section not in Mission.model_fields:
            found.setdefault(declaration.section, (name, declaration.options))
    return found


@cache
def _with_sections(base: type[Mission], sections: tuple[tuple[str, str, type[BaseModel]], ...]) -> type[Mission]:
    fields: dict[str, Any] = {
        section: (options | None, Field(None, description=f"{tree} options (a plugin's)")) for section, tree, options in sections
    }
    extended: type[Mission] = create_model("Mission", __base__=base, __module__=__name__, __doc__=base.__doc__, **fields)
    return extended


def mission_model(data: object = None, base: type[Mission] = Mission) -> type[Mission]:
    """The model a mission file is validated as: ``base``, with the options section its plugin tree declares as its own.

    None: with every installed plugin tree's section (the JSON schema's).
    """
    if data is None:
        trees = registry.names(registry.TREES)
    elif isinstance(data, dict) and isinstance(data.get("tree"), str):
        trees = [data["tree"]]
    else:
        return base
    sections = _plugin_sections(trees)
    return _with_sections(base, tuple((s, tree, model) for s, (tree, model) in sorted(sections.items()))) if sections else base
