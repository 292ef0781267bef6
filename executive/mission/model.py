"""The mission file format (version 1), as strict pydantic models.

Strict means: no silent coercion (``"5"`` is not a number, ``yes`` is not a float), no unknown
fields, every value in range. Rules that relate several fields (a waypoint speed inside the
mission's speed limits, say) are in :func:`cross_field_errors` so that each gets its own
location in the file.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from executive.geofence import Geofence, open_ring, polygon_problems
from executive.mission.errors import Path
from executive.vehicles import PROFILES

VehicleKind = Literal["rover", "boat", "sub", "vtol"]
ControlMode = Literal["depth", "altitude"]

_STRICT = ConfigDict(strict=True, extra="forbid", frozen=True, allow_inf_nan=False)

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


class Limits(BaseModel):
    """Numbers the guards and actions enforce."""

    model_config = _STRICT
    acceptance_radius_m: float = Field(2.0, gt=0.0, le=1000.0, description="a waypoint counts as reached within this distance")
    leg_timeout_s: float = Field(120.0, gt=0.0, le=86400.0, description="a leg taking longer than this is abandoned")
    max_goal_distance_m: float = Field(5000.0, gt=0.0, le=100_000.0, description="targets farther than this from the vehicle are refused")
    speed_m_s: Range = Field(default_factory=lambda: Range(min=0.1, max=5.0), description="allowed waypoint speeds")
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
    fresh_timeout_s: float = Field(1.0, gt=0.0, le=60.0, description="an RC report older than this (or a frozen CAN counter) is stale")
    switch_channels: SwitchChannels = Field(default_factory=SwitchChannels)


class SamplingOptions(BaseModel):
    """goto_sample: what happens at a sample point."""

    model_config = _STRICT
    duration_s: float = Field(10.0, gt=0.0, le=3600.0, description="how long the sampler reads at a sample point")
    rate_hz: float = Field(1.0, gt=0.0, le=100.0, description="sensor reads per second")
    sensors: list[str] = Field(default_factory=lambda: ["temperature", "conductivity", "ph", "dissolved_oxygen"], min_length=1, max_length=32)
    hold_mode: str = Field("LOITER", description="the mode the vehicle holds the sample point in")


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
    q_guided_mode: int = Field(
        0, ge=0, le=1, description="vtol: ArduPlane's Q_GUIDED_MODE (1: GUIDED targets end in a hover; near ones are flown as a multicopter)"
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
    tree: str = Field("waypoints", pattern=r"^[a-z][a-z0-9_]*$", description="module of trees/ that builds the tree")
    description: str | None = Field(None, max_length=4096)
    auto_arm: bool = Field(False, description="arm the vehicle in pre-flight (else wait for the operator to arm it)")
    home: Home | None = None
    geofence: GeofenceConfig | None = Field(None, description="where the vehicle may be")
    limits: Limits = Field(default_factory=Limits)
    rc: RcConfig = Field(default_factory=RcConfig)
    sampling: SamplingOptions | None = Field(None, description="goto_sample options")
    vtol: VtolOptions | None = Field(None, description="vtol_transit options")
    rc_route: RcRouteOptions | None = Field(None, description="ugv_rc_route options")
    simulator: SimulatorOptions | None = Field(None, description="the built-in simulated vehicle for `executive run` without --mavlink")
    waypoints: list[Waypoint] = Field(max_length=100_000, description="the route; only ugv_rc_route may start empty (the operator records it)")


#: Tree -> the vehicle kinds it can drive and the options section it reads.
TREE_RULES: dict[str, tuple[frozenset[str], str | None]] = {
    "waypoints": (frozenset({"rover", "boat", "sub", "vtol"}), None),
    "goto_sample": (frozenset({"rover", "boat"}), "sampling"),
    "auv_survey": (frozenset({"sub"}), None),
    "vtol_transit": (frozenset({"vtol"}), "vtol"),
    "ugv_rc_route": (frozenset({"rover"}), "rc_route"),
}


def cross_field_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Rules between fields; each error is the path of the offending value and why."""
    errors: list[tuple[Path, str]] = []
    limits = mission.limits
    kinds, section = TREE_RULES.get(mission.tree, (frozenset({mission.vehicle}), None))
    if mission.vehicle not in kinds:
        errors.append((("tree",), f"tree {mission.tree} drives {', '.join(sorted(kinds))}, not a {mission.vehicle}"))
    for other in ("sampling", "vtol", "rc_route"):
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
    if mission.tree != "goto_sample":
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
    if mission.vehicle == "vtol":
        errors += _vtol_errors(mission)
    if mission.simulator is not None and mission.simulator.q_guided_mode and (mission.simulator.model or mission.vehicle) != "vtol":
        errors.append((("simulator", "q_guided_mode"), "only the simulated vtol (ArduPlane) has Q_GUIDED_MODE"))
    if mission.geofence is not None:
        errors += _geofence_errors(mission)
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
