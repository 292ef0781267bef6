"""The rules between a mission's fields, each error located at the offending value; the failsafe policy a mission gets.

What a rule knows of a named tree is what the tree declares (:mod:`executive.mission.declaration`). A rule that
needs more than the file (its tree found, its instrument's options) is :mod:`executive.admission.checks`'s.
"""

from __future__ import annotations

import math
import re

from executive.mission.declaration import (
    FIRMWARE_NAMES,
    declared,
    drives,
    kind_failsafes,
    reaction_refused,
    trees_with,
    vehicle_profile,
)
from executive.mission.errors import Path
from executive.mission.failsafes import (
    FAILSAFE_CONDITIONS,
    PERSON_CONDITIONS,
    FailsafePolicy,
)
from executive.mission.model import (
    OPTION_SECTIONS,
    VTOL_HOVER_RADIUS_M,
    VTOL_MIN_ACCEPTANCE_RADIUS_M,
    FailsafeRule,
    Mission,
    Vertex,
    VtolOptions,
    tree_name,
)
from executive.mission.zones import chord_m, route_errors, zone_shape_errors
from executive.world.geo import distance
from executive.world.geofence import Geofence, open_ring, polygon_problems
from executive.world.vehicles import AUTOPILOT_VEHICLES

_PARAM_NAME = re.compile(r"[A-Z][A-Z0-9_]{0,15}")


def rc_switch_channels(mission: Mission) -> dict[int, str]:
    """The RC channels whose positions this mission reads from the autopilot (``rc.source: mavlink``), each with what it is.

    The tree's declared switches (:attr:`TreeDeclaration.rc_switches`), else the take-over switch; and the arm switch. Empty
    with RC from CAN: then the autopilot's own RC channels are not the mission's switches.
    """
    rc = mission.rc
    if rc.source != "mavlink":
        return {}
    switches = declared(tree_name(mission)).rc_switches
    found = dict(switches(mission)) if switches is not None else {rc.takeover_channel: "the take-over switch"}
    if rc.arm_channel is not None:
        found.setdefault(rc.arm_channel, "the arm switch")
    return dict(sorted(found.items()))


#: drive: auto refused, per autopilot and whether the vehicle is a vtol, until it can be flown so: why.
AUTO_DRIVE_AUTOPILOT_REFUSED: dict[tuple[str, bool], str] = {
    ("px4", False): "drive: auto on PX4 flies a vtol's waypoints so far (proven on PX4's SIH, which has no rover or boat)",
    # ArduPlane/commands_logic.cpp Plane::exit_mission_callback: set_mode(mode_rtl, ModeReason::MISSION_END)
    ("ardupilot", True): "drive: auto on a vtol needs PX4: ArduPlane ends its mission in RTL, flying home from the end of the horizon "
    "instead of holding there (Plane::exit_mission_callback)",
}


def drive_errors(mission: Mission) -> list[str]:
    """Why ``drive: auto`` cannot drive this mission's tree and vehicle (empty: it can, or the drive is guided)."""
    if mission.drive != "auto":
        return []
    name = tree_name(mission)
    if name is None:
        return ["a tree composed in the file is not driven in AUTO: use drive: guided"]
    declaration = declared(name)
    if declaration.auto_refused is not None:
        return [f"tree {name}: {declaration.auto_refused}; use drive: guided"]
    kinds = declaration.auto_drive
    if not kinds:
        return [f"tree {name} is not known to be driven in AUTO; use drive: guided"]
    if mission.vehicle not in kinds:
        kinds_here = f"{' or '.join(sorted(kinds))} ({' or '.join(sorted(set(kinds.values())))})"
        return [f"tree {name} is driven in AUTO on a {kinds_here} so far, not a {mission.vehicle}; use drive: guided"]
    return []


#: drive: auto on a sub: why an altitude leg cannot be a mission item. ArduSub's AUTO takes a height above the seabed
#: (the terrain frame) only from a good sonar reading at the leg's start, else its terrain failsafe
#: (ArduSub/mode_auto.cpp auto_wp_start: "Terrain data (rangefinder) not available", failsafe_terrain_on_event), and the
#: executive's depth from the sonar, re-sent as the seabed changes (executive.world.seabed), cannot be put in one item.
AUTO_ALTITUDE_LEG = (
    "drive: auto flies a sub's waypoints at their depths: ArduSub's AUTO holds a height above the seabed only with the sonar "
    "reading it when the leg starts (else its terrain failsafe); use control_mode depth, or drive: guided"
)


def _auto_depth_errors(mission: Mission) -> list[tuple[Path, str]]:
    """drive: auto on a sub: every leg a depth leg."""
    if mission.drive != "auto" or mission.vehicle != "sub":
        return []
    return [(("waypoints", i, "control_mode"), AUTO_ALTITUDE_LEG) for i, wp in enumerate(mission.waypoints) if wp.control_mode == "altitude"]


def autopilot_errors(mission: Mission, autopilot: str) -> list[str]:
    """Why ``autopilot`` cannot fly ``mission`` (empty when it can)."""
    errors = []
    kinds = AUTOPILOT_VEHICLES[autopilot]
    if not drives(autopilot, mission.vehicle):
        errors.append(f"{autopilot} drives {', '.join(sorted(kinds))} here, not a {mission.vehicle}")
    name, needs = tree_name(mission), declared(tree_name(mission)).needs
    if needs is not None and autopilot != needs[0]:
        errors.append(f"tree {name} needs {FIRMWARE_NAMES.get(needs[0], needs[0])}: {needs[1]}")
    if mission.drive == "auto" and (why := AUTO_DRIVE_AUTOPILOT_REFUSED.get((autopilot, mission.vehicle == "vtol"))):
        errors.append(why)
    return errors


def cross_field_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Rules between fields; each error is the path of the offending value and why."""
    errors: list[tuple[Path, str]] = []
    limits = mission.limits
    name = tree_name(mission)
    declaration = declared(name)
    kinds = declaration.vehicles
    if kinds is not None and mission.vehicle not in kinds:
        errors.append((("tree",), f"tree {mission.tree} drives {', '.join(sorted(kinds))}, not a {mission.vehicle}"))
    if declaration.options is not None and declaration.section in Mission.model_fields:  # its own section cannot be one of ours
        errors.append(
            (("tree",), f"tree {mission.tree} declares an options section of its own named {declaration.section}, a field of every mission")
        )
    for other in OPTION_SECTIONS if name is not None else ():  # a composed tree's nodes read what they need
        if other != declaration.section and getattr(mission, other) is not None:
            readers = " or ".join(trees_with(lambda d, other=other: d.section == other))
            errors.append(((other,), f"only used by tree {readers} (tree is {mission.tree})"))
    aux_mode = mission.rc_route.aux_mode if mission.rc_route is not None else None
    modes = vehicle_profile(mission.vehicle).modes
    if aux_mode is not None and aux_mode.upper() not in modes:
        known = ", ".join(m for m in modes if m != "INITIALISING")
        errors.append((("rc_route", "aux_mode"), f"{aux_mode!r}: not a {mission.vehicle} mode (known: {known})"))
    if not mission.waypoints and not declaration.empty_route:
        errors.append((("waypoints",), "at least one waypoint is needed"))
    if declaration.samples and not any(wp.sample for wp in mission.waypoints):
        errors.append((("waypoints",), f"{name} needs at least one waypoint with sample: true"))
    if not declaration.samples and name is not None and any(wp.sample for wp in mission.waypoints):  # composed: its sample node
        why = f"only {' or '.join(trees_with(lambda d: d.samples))} takes samples"
        errors += [(("waypoints", i, "sample"), why) for i, wp in enumerate(mission.waypoints) if wp.sample]
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
        if limits.water_depth_m is not None:
            errors += _water_depth_errors(mission, i)
        if wp.control_mode == "altitude" and wp.altitude_m is None:
            errors.append(((*here, "altitude_m"), "control_mode altitude needs altitude_m"))
        if wp.control_mode != "altitude" and wp.altitude_m is not None:
            errors.append(((*here, "altitude_m"), "altitude_m is only used with control_mode altitude"))
    if mission.home is not None:  # the distance rule, as the vehicle will judge it at start (executive.admission.reach) if it starts at home
        limit = limits.max_goal_distance_m
        wps = mission.waypoints
        far = chord_m([mission.home.lat] * len(wps), [mission.home.lon] * len(wps), [w.lat for w in wps], [w.lon for w in wps])
        for i, wp in enumerate(wps):
            if far[i] > limit - 2.0 and (d := distance(mission.home.lat, mission.home.lon, wp.lat, wp.lon)) > limit:  # chord: a metre short
                why = f"{d:.0f} m from home, over limits.max_goal_distance_m ({limit:g} m): refused at start with the vehicle at home"
                errors.append((("waypoints", i), why))
    errors += _leg_time_errors(mission)
    errors += [(("drive",), why) for why in drive_errors(mission)] + _auto_depth_errors(mission)
    if mission.vehicle == "vtol":
        errors += _vtol_errors(mission) + _height_errors(mission)
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
    errors += _failsafe_errors(mission)
    return errors


def failsafe_policy(mission: Mission) -> dict[str, FailsafePolicy]:
    """Every condition's failsafe for this mission: its ``failsafe:`` entry, else the tree's default, else the vehicle kind's."""
    defaults = kind_failsafes(mission.vehicle) | dict(declared(tree_name(mission)).failsafes)
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
        elif reaction != "wait" and (why := reaction_refused(mission.vehicle, reaction)) is not None:
            errors.append(((*here, "reaction"), f"{reaction}: not for a {mission.vehicle} ({why})"))
        elif reaction in (refused := declared(tree_name(mission)).refused_reactions):
            errors.append(((*here, "reaction"), f"{reaction}: not in tree {mission.tree} ({refused[reaction]})"))
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


def _water_depth_errors(mission: Mission, i: int) -> list[tuple[Path, str]]:
    """Waypoint ``i`` of a sub within the water ``limits.water_depth_m`` states: no deeper than ``limits.altitude_m.min`` above
    the seabed (the floor the sub is held at in flight, executive.world.seabed), no higher above the seabed than the water is deep."""
    limits, wp = mission.limits, mission.waypoints[i]
    water, clearance = limits.water_depth_m, limits.altitude_m.min
    assert water is not None
    if wp.control_mode != "altitude" and wp.depth_m is not None and wp.depth_m > water - clearance:
        return [(("waypoints", i, "depth_m"), f"{wp.depth_m:g} m is deeper than the water holds: limits.water_depth_m {water:g} m less "
                 f"limits.altitude_m.min {clearance:g} m above the seabed: at most {max(0.0, water - clearance):g} m")]  # fmt: skip
    if wp.control_mode == "altitude" and wp.altitude_m is not None and wp.altitude_m > water:
        return [(("waypoints", i, "altitude_m"), f"{wp.altitude_m:g} m above the seabed is above the surface: "
                 f"limits.water_depth_m is {water:g} m")]  # fmt: skip
    return []


def seabed_clearance(mission: Mission) -> float | None:
    """How close to the seabed a sub may go, as its sonar reads it (``limits.altitude_m.min``); None: not a sub."""
    return mission.limits.altitude_m.min if mission.vehicle == "sub" else None


def height_tolerance(mission: Mission) -> float | None:
    """How near its height (``alt_m``, but 0) a vtol must be for a waypoint to count as reached; None: not a vtol, distance only."""
    return mission.limits.alt_tolerance_m if mission.vehicle == "vtol" else None


def _height_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Every height a vtol is sent to (waypoints, take-off, hover point) within ``limits.alt_m`` above home."""
    allowed = mission.limits.alt_m
    heights: list[tuple[Path, float]] = [(("waypoints", i, "alt_m"), wp.alt_m) for i, wp in enumerate(mission.waypoints) if wp.alt_m != 0.0]
    if mission.vtol is not None:
        heights.append((("vtol", "takeoff_alt_m"), mission.vtol.takeoff_alt_m))
        if mission.vtol.hover_enu is not None:
            heights.append((("vtol", "hover_enu", "up_m"), mission.vtol.hover_enu.up_m))
    elif declared(tree_name(mission)).section == "vtol":  # the options' defaults are flown too
        heights.append((("vtol",), VtolOptions().takeoff_alt_m))
    return [(path, f"{alt:g} m above home is outside limits.alt_m [{allowed.min:g}, {allowed.max:g}]") for path, alt in heights if alt not in allowed]


def _geofence_errors(mission: Mission) -> list[tuple[Path, str]]:
    """The fence is usable, and the home and every waypoint of the mission are inside it."""
    config = mission.geofence
    assert config is not None
    if config.polygon is None and config.max_distance_from_home_m is None and not config.inclusion and not config.keep_out:
        return [(("geofence",), "a geofence needs a polygon, max_distance_from_home_m, inclusion or keep_out zones")]
    polygons: list[tuple[Path, list[Vertex]]] = [(("geofence", "polygon"), config.polygon)] if config.polygon is not None else []
    for zones in ("inclusion", "keep_out"):
        polygons += [(("geofence", zones, i, "polygon"), z.polygon) for i, z in enumerate(getattr(config, zones)) if z.polygon is not None]
    errors = zone_shape_errors(mission)
    for path, polygon in polygons:
        errors += [((*path, i), why) for i, why in polygon_problems(open_ring([(v.lat, v.lon) for v in polygon]))]
    if errors:
        return errors
    fence = config.fence()
    if config.inclusion:  # the waypoints inside polygon or an inclusion zone: route_errors judges the union
        fence = Geofence((), fence.max_distance_m)
    home = (mission.home.lat, mission.home.lon) if mission.home else None
    if home is None:  # the distance rule waits for the autopilot's home, at run time
        fence = Geofence(fence.polygon)
    points: list[tuple[Path, float, float]] = [(("home",), *home)] if home else []
    points += [(("waypoints", i), wp.lat, wp.lon) for i, wp in enumerate(mission.waypoints)]
    for path, lat, lon in points:
        why = fence.why_outside(lat, lon, home)
        if why:
            errors.append((path, f"outside the geofence: {why}"))
    return errors + route_errors(mission)


def _leg_time_errors(mission: Mission) -> list[tuple[Path, str]]:
    """Each leg (from home where known) drivable within ``limits.leg_timeout_s``: its length less the acceptance radius at its speed
    (the waypoint's ``speed_m_s``, else the cap ``limits.speed_m_s.max``, a vehicle kind's default limits included)."""
    if not declared(tree_name(mission)).timed_legs or mission.vehicle == "vtol":  # a vtol flies its legs at its airspeed
        return []
    limits, wps = mission.limits, mission.waypoints
    points = [("home", mission.home.lat, mission.home.lon)] if mission.home else []
    points += [(f"waypoints[{i}]", wp.lat, wp.lon) for i, wp in enumerate(wps)]
    first = len(points) - len(wps)
    errors: list[tuple[Path, str]] = []
    lats, lons = [p[1] for p in points], [p[2] for p in points]
    lengths = chord_m(lats[:-1], lons[:-1], lats[1:], lons[1:]) - limits.acceptance_radius_m
    for (start, *_), (end, *_), i, length in zip(points, points[1:], range(1 - first, len(wps)), lengths.tolist(), strict=False):
        speed = wps[i].speed_m_s or limits.speed_m_s.max
        if length > 0.0 and length / speed > limits.leg_timeout_s:
            at = f"at {speed:g} m/s (waypoints[{i}].speed_m_s)" if wps[i].speed_m_s else f"at most {speed:g} m/s"
            errors.append((("waypoints", i), f"{start} -> {end}: {length:.0f} m {at} takes {length / speed:.0f} s, "
                           f"over limits.leg_timeout_s {limits.leg_timeout_s:g}: it can only time out"))  # fmt: skip
    return errors


def waits_for_the_vehicle(mission: Mission) -> list[str]:
    """The checks a mission without ``home:`` leaves to the vehicle's position at start (empty with a home).

    The first leg's time is not among them: it is judged only from ``home:`` (at start the vehicle may be anywhere).
    """
    if mission.home is not None or not mission.waypoints:
        return []
    waits = [f"every waypoint within limits.max_goal_distance_m ({mission.limits.max_goal_distance_m:g} m) of the vehicle"]
    if mission.geofence is not None and (mission.geofence.keep_out or mission.geofence.inclusion):
        waits.append("the first leg against the keep-out and inclusion zones")
    if mission.geofence is not None and mission.geofence.max_distance_from_home_m is not None:
        waits.append("geofence.max_distance_from_home_m (from the autopilot's home)")
    return waits
