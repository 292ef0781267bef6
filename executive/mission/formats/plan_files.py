"""Ground-station mission files: QGroundControl ``.plan`` (JSON) and Mission Planner ``QGC WPL 110`` (text), in and out.

What maps, both ways:

- ``NAV_WAYPOINT`` (16) items <-> waypoints. Frames: relative to home (3, 6) <-> ``alt_m``; above mean
  sea level (0, 5) -> ``alt_m`` less the planned home's altitude (with a warning); above terrain
  (10, 11) <-> ``altitude_m`` with control mode ``altitude`` on a sub (above the seabed), elsewhere
  -> ``alt_m`` (with a warning). A sub's altitude below zero is a depth, as ArduSub has it: ``depth_m``
  with control mode ``depth``.
- ``DO_CHANGE_SPEED`` (178) <-> ``speed_m_s`` of the waypoints after it. A speed outside the default
  ``limits.speed_m_s`` widens the limits, with a warning.
- ``plannedHomePosition`` / the WPL's line of item 0 <-> ``home``.
- ``.plan`` only: the first inclusion polygon of ``geoFence`` <-> ``geofence.polygon``; an inclusion
  circle centred on home <-> ``geofence.max_distance_from_home_m``; every other inclusion polygon or
  circle <-> ``geofence.inclusion``, every exclusion one <-> ``geofence.keep_out`` (a zone's name is
  not carried: a plan's shapes have none); ``rallyPoints`` <-> ``rally_points``. A survey or corridor scan
  (``ComplexItem``) is imported as the mission items QGroundControl generated for it (its
  ``TransectStyleComplexItem.Items``), with a warning that the pattern itself is not kept.

Everything else is reported as a located warning, never dropped silently: other commands, a
waypoint's hold time, acceptance or pass radius and yaw, ``autoContinue`` false. Bad input raises :class:`MissionError`, every problem
as ``FILE:LINE:COL: FIELD: message`` (JSON: the decoder's position, or where the offending value
starts; WPL: the line and the column of the field). Export writes what a mission holds, and says
(as ``(path, why)`` pairs) what the format cannot carry: waypoint names, sample flags, a geofence in
a ``.waypoints`` file. Executive settings (tree, limits, RC, ...) are not part of either format.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import yaml

from executive.mission.declaration import vehicle_profile
from executive.mission.errors import FieldError, MissionError, Path
from executive.mission.formats.mp_zone_files import read_zone_file
from executive.mission.formats.plan_items import (
    ARDUPILOT,
    CMD_CHANGE_SPEED,
    CMD_WAYPOINT,
    FRAME_AMSL,
    FRAME_MISSION,
    FRAME_RELATIVE,
    FRAME_TERRAIN,
    HOME_CIRCLE_M,
    QGC_ALTITUDE_RELATIVE,
    QGC_ALTITUDE_TERRAIN_FRAME,
    WPL_HEADER,
    WPL_SUFFIXES,
    At,
    FileContents,
    Item,
    command_name,
    frame_name,
)
from executive.mission.formats.plan_reading import read_plan, read_waypoints
from executive.mission.loader import load_mission_text
from executive.mission.model import VEHICLE_LIMITS, VTOL_MIN_ACCEPTANCE_RADIUS_M, Limits, Mission
from executive.world.dialect import mavlink
from executive.world.geo import distance

MAX_BYTES = 16 * 1024 * 1024  # a survey of a large area makes a big .plan


@dataclass(frozen=True)
class Imported:
    """A ground-station file made into a mission: the YAML text (valid), its mission, and what was not imported."""

    mission: Mission
    yaml_text: str
    warnings: tuple[FieldError, ...]


@dataclass(frozen=True)
class Exported:
    """A mission as a ground-station file, and what the format could not carry (path in the mission, why)."""

    text: str
    warnings: tuple[tuple[Path, str], ...]


# -- from what a file says to a mission -------------------------------------------------------


#: What ``executive import`` takes, said of any other file.
IMPORTED_KINDS = (
    "it takes a QGroundControl .plan (JSON), a Mission Planner .waypoints (QGC WPL 110; .txt, .mission) or a BehaviorTree.CPP / Groot2 tree (.xml)"
)

#: Said in an imported mission's header and by ``executive import`` when it was imported without ``--auto-arm``.
WAITS_FOR_ARMING = (
    "The mission waits for a person to arm the vehicle (`executive ctl arm`, a ground station); "
    "import with --auto-arm (auto_arm: true) to have it armed in pre-flight."
)


class _IndentedDumper(yaml.SafeDumper):
    """Lists indented under their key, as the example missions are written."""

    def increase_indent(self, flow: bool = False, indentless: bool = False) -> None:
        super().increase_indent(flow, False)


def _build(src: FileContents, kind_given: str | None, name: str, auto_arm: bool, what: str, zones: Sequence[FileContents] = ()) -> Imported:
    """The mission a source describes (with the zones and rally points of ``zones``), validated; every problem located in its file."""
    for other in zones:
        src.merge(other)
    kind = kind_given or src.vehicle
    if kind is None and (src.vehicle_at is not None or not src.errors):  # no mission section at all says enough
        src.error(src.vehicle_at or src.start, src.vehicle_why or "no vehicle kind: pass --vehicle")
    elif kind_given and src.vehicle and src.vehicle != kind_given and src.vehicle_at:
        src.warn(src.vehicle_at, f"the file is for a {src.vehicle}; imported for a {kind_given} as --vehicle says")
    doc: dict[str, Any] = {"version": 1, "name": name, "vehicle": kind}
    if auto_arm:
        doc["auto_arm"] = True
    sources: dict[str, At] = {}
    home_alt = src.home[2] if src.home else None
    if src.home is not None and src.home_at is not None:
        doc["home"] = {"lat": src.home[0], "lon": src.home[1]}
        sources["home"] = src.home_at
    fence = _fence(src, sources)
    if fence:
        doc["geofence"] = fence
    rally = _rally(src, sources)
    if rally:
        doc["rally_points"] = rally
    waypoints: list[dict[str, Any]] = []
    speed: tuple[float, At] | None = None
    skipped: dict[tuple[str, int], list[At]] = {}
    for item in src.items:
        if item.command == CMD_CHANGE_SPEED:
            speed = _speed_change(src, item, speed)
            continue
        if item.command != CMD_WAYPOINT:
            if item.group is None:
                src.warn(item.at, f"not imported: {command_name(item.command)}: a mission file holds waypoints and their speeds only")
            else:
                skipped.setdefault((item.group, item.command), []).append(item.at)
            continue
        wp = _waypoint(src, item, kind, home_alt)
        if wp is None:
            continue
        here = f"waypoints[{len(waypoints)}]"
        sources |= {here: item.at, f"{here}.lat": item.param_at[4], f"{here}.lon": item.param_at[5]}
        sources |= {f"{here}.{key}": item.param_at[6] for key in ("alt_m", "depth_m", "altitude_m")} | {f"{here}.control_mode": item.frame_at}
        if speed is not None:
            wp["speed_m_s"] = speed[0]
            sources[f"{here}.speed_m_s"] = speed[1]
        waypoints.append(wp)
    for (group, command), places in skipped.items():
        more = f" and {len(places) - 1} more like it" if len(places) > 1 else ""
        src.warn(places[0], f"not imported: {command_name(command)}{more} in {group}")
    limits: dict[str, Any] = {}
    notes: list[str] = []
    if kind == "vtol":  # the mission rules ask it of every vtol; no ground-station file has it
        limits["acceptance_radius_m"] = VTOL_MIN_ACCEPTANCE_RADIUS_M
        notes.append(f"limits.acceptance_radius_m is {VTOL_MIN_ACCEPTANCE_RADIUS_M:g} m, the least for a vtol (it circles its points as a plane).")
    if speeds := _speed_limits(src, waypoints, sources):
        limits["speed_m_s"] = speeds
    if (timeout := _leg_timeout(src, kind, doc.get("home"), waypoints, limits, sources)) is not None:
        limits["leg_timeout_s"] = timeout
    if limits:
        doc["limits"] = limits
    doc["waypoints"] = waypoints
    sources["waypoints"] = src.items_at or src.start
    if src.errors:
        raise MissionError(src.errors)
    header = [f"Imported from {os.path.basename(src.filename)} ({what}) by `executive import`.", *notes]
    if not auto_arm:
        header.append(WAITS_FOR_ARMING)
    if src.warnings:
        header.append("Not imported or changed on the way (details in the import's warnings):")
        where = {w: (f"{os.path.basename(w.file)} " if w.file != src.filename else "") + f"line {w.line}" for w in src.warnings}
        header += [f"  {where[w]}: {w.field}: {w.message}" for w in sorted(src.warnings, key=lambda w: (w.file != src.filename, w.line, w.column))]
    text = "".join(f"# {line}\n" for line in header) + yaml.dump(
        doc, Dumper=_IndentedDumper, sort_keys=False, default_flow_style=None, allow_unicode=True, width=150
    )
    try:
        mission = load_mission_text(text, src.filename)
    except MissionError as exc:
        raise MissionError([_relocate(e, sources, src) for e in exc.errors]) from None
    return Imported(mission, text, tuple(sorted(src.warnings, key=lambda w: (w.line, w.column, w.field))))


def _relocate(error: FieldError, sources: dict[str, At], src: FileContents) -> FieldError:
    """An error found in the generated YAML, located at what it came from in the source file."""
    keys = [k for k in sources if error.field == k or error.field.startswith((f"{k}.", f"{k}["))]
    at = sources[max(keys, key=len)] if keys else src.start
    return FieldError(at.filename or src.filename, at.line, at.column, at.field, f"{error.message} (as {error.field} of the mission)")


def _speed_change(src: FileContents, item: Item, speed: tuple[float, At] | None) -> tuple[float, At] | None:
    """The speed in force after a DO_CHANGE_SPEED (param2; -1 = unchanged)."""
    value = item.params[1]
    throttle = item.params[2]
    if throttle not in (None, -1.0, 0.0):
        src.warn(item.param_at[2], f"throttle {throttle:g} % not imported: a mission file sets speeds, not throttle")
    if value is None or value == -1.0:
        return speed
    if value <= 0.0:
        src.warn(item.param_at[1], f"speed {value:g} m/s not imported (only a positive speed sets one)")
        return speed
    return value, item.param_at[1]


def _waypoint(src: FileContents, item: Item, kind: str | None, home_alt: float | None) -> dict[str, Any] | None:
    """A NAV_WAYPOINT as a mission waypoint; None (with an error) if it cannot be one."""
    p = item.params
    lat, lon, alt = p[4], p[5], 0.0 if p[6] is None else p[6]
    if lat is None or lon is None:
        src.error(item.param_at[4 if lat is None else 5], "a waypoint needs a latitude and a longitude")
        return None
    wp: dict[str, Any] = {"lat": lat, "lon": lon}
    if item.frame in FRAME_AMSL:
        if home_alt is None:
            src.error(item.frame_at, f"{frame_name(item.frame)}: an altitude above mean sea level needs the home's altitude, and there is none")
            return None
        src.warn(item.param_at[6], f"altitude {alt:g} m above mean sea level imported as {alt - home_alt:g} m above home (home at {home_alt:g} m)")
        alt -= home_alt
    elif item.frame in FRAME_TERRAIN:
        if kind == "sub":
            wp |= {"altitude_m": alt, "control_mode": "altitude"}
            return _waypoint_params(src, item, wp)
        src.warn(item.frame_at, f"{frame_name(item.frame)}: the altitude above terrain is imported as {alt:g} m above home")
    elif item.frame not in FRAME_RELATIVE:
        src.error(item.frame_at, f"{frame_name(item.frame)}: a waypoint needs a global frame (0, 3, 10 or their _INT forms)")
        return None
    if kind == "sub" and math.copysign(1.0, alt) < 0.0:  # ArduSub: below the surface; -0.0 is depth 0
        wp |= {"depth_m": -alt, "control_mode": "depth"}
    else:
        wp["alt_m"] = alt
    return _waypoint_params(src, item, wp)


def _waypoint_params(src: FileContents, item: Item, wp: dict[str, Any]) -> dict[str, Any]:
    """Report what a NAV_WAYPOINT says that a mission waypoint cannot."""
    hold, radius, passing, yaw = item.params[:4]
    if hold:
        src.warn(item.param_at[0], f"hold time {hold:g} s not imported: the executive does not wait at a waypoint")
    if radius:
        src.warn(item.param_at[1], f"acceptance radius {radius:g} m not imported: limits.acceptance_radius_m applies to every waypoint")
    if passing:
        src.warn(item.param_at[2], f"pass radius {passing:g} m not imported")
    if yaw:  # None (NaN) or 0 is unset: ArduPilot ignores it, Mission Planner writes 0
        src.warn(item.param_at[3], f"yaw {yaw:g}° not imported: the vehicle heads for the next waypoint")
    if not item.autocontinue:
        src.warn(item.at, "autocontinue false (wait at this waypoint) not imported: the executive goes on")
    return wp


def _fence(src: FileContents, sources: dict[str, At]) -> dict[str, Any]:
    """The plan's geoFence as a mission's: the first inclusion polygon is ``polygon``, an inclusion circle on home
    ``max_distance_from_home_m``; other inclusion shapes are ``inclusion`` zones, exclusion shapes ``keep_out`` zones."""
    fence: dict[str, Any] = {}
    zones: dict[str, list[dict[str, Any]]] = {"inclusion": [], "keep_out": []}
    for polygon in src.polygons:
        corners = [{"lat": lat, "lon": lon} for lat, lon, _ in polygon.corners]
        if polygon.inclusion and "polygon" not in fence:
            fence["polygon"], here = corners, "geofence.polygon"
        else:
            kind = "inclusion" if polygon.inclusion else "keep_out"
            zones[kind].append({"polygon": corners})
            here = f"geofence.{kind}[{len(zones[kind]) - 1}].polygon"
        sources[here] = polygon.at
        sources |= {f"{here}[{i}]": at for i, (_, _, at) in enumerate(polygon.corners)}
    for circle in src.circles:
        on_home = src.home is not None and distance(circle.lat, circle.lon, src.home[0], src.home[1]) <= HOME_CIRCLE_M
        if circle.inclusion and on_home and "max_distance_from_home_m" not in fence:
            fence["max_distance_from_home_m"] = circle.radius_m
            sources["geofence.max_distance_from_home_m"] = circle.at
            continue
        kind = "inclusion" if circle.inclusion else "keep_out"
        zones[kind].append({"circle": {"lat": circle.lat, "lon": circle.lon, "radius_m": circle.radius_m}})
        sources[f"geofence.{kind}[{len(zones[kind]) - 1}]"] = circle.at
    fence |= {kind: found for kind, found in zones.items() if found}
    if fence:
        first = src.polygons[0].at if src.polygons else src.circles[0].at
        sources["geofence"] = first
    return fence


def _rally(src: FileContents, sources: dict[str, At]) -> list[dict[str, Any]]:
    sources |= {f"rally_points[{i}]": at for i, (*_, at) in enumerate(src.rally)}
    return [{"lat": lat, "lon": lon, "alt_m": alt} for lat, lon, alt, _ in src.rally]


def _leg_timeout(
    src: FileContents,
    kind: str | None,
    home: dict[str, float] | None,
    waypoints: list[dict[str, Any]],
    limits: dict[str, Any],
    sources: dict[str, At],
) -> float | None:
    """limits.leg_timeout_s widened to twice the longest leg's shortest time, where the default would refuse it (with a warning):
    a plan has no leg time limit, and a slow survey line is not a mistake (the rule: executive.mission.rules)."""
    if kind == "vtol" or not waypoints:
        return None
    default = Limits()
    cap = limits.get("speed_m_s", {}).get("max", (VEHICLE_LIMITS.get(kind or "", {}).get("speed_m_s") or {"max": default.speed_m_s.max})["max"])
    points = ([(home["lat"], home["lon"])] if home else []) + [(wp["lat"], wp["lon"]) for wp in waypoints]
    first = len(points) - len(waypoints)
    legs = [
        ((distance(*a, *b) - default.acceptance_radius_m) / (waypoints[i].get("speed_m_s") or cap), i)
        for a, b, i in zip(points, points[1:], range(1 - first, len(waypoints)), strict=False)
    ]
    longest, i = max(legs, default=(0.0, 0))
    if not longest > default.leg_timeout_s:  # NaN too: a bad coordinate is reported as such
        return None
    timeout = float(math.ceil(2.0 * longest))
    why = f"this leg takes at least {longest:.0f} s: limits.leg_timeout_s set to {timeout:g} (the default {default.leg_timeout_s:g} would refuse it)"
    src.warn(sources[f"waypoints[{i}]"], why)
    return timeout


def _speed_limits(src: FileContents, waypoints: list[dict[str, Any]], sources: dict[str, At]) -> dict[str, float] | None:
    """limits.speed_m_s widened to the speeds the file asks for, if the defaults do not hold them (with a warning)."""
    default = Limits().speed_m_s
    speeds = [(wp["speed_m_s"], i) for i, wp in enumerate(waypoints) if "speed_m_s" in wp]
    if not speeds:
        return None
    (low, low_i), (high, high_i) = min(speeds), max(speeds)
    if default.min <= low and high <= default.max:
        return None
    limits = {"min": min(low, default.min), "max": max(high, default.max)}
    for value, i, bound in ((low, low_i, "min"), (high, high_i, "max")):
        if value == limits[bound] and value != getattr(default, bound):
            src.warn(sources[f"waypoints[{i}].speed_m_s"], f"speed {value:g} m/s is outside the default limits: limits.speed_m_s.{bound} set to it")
    return limits


# -- importing --------------------------------------------------------------------------------


def import_plan(
    text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False, zones: Sequence[FileContents] = ()
) -> Imported:
    """A QGroundControl .plan as a mission; ``vehicle`` overrides the plan's vehicleType. Raises :class:`MissionError`."""
    src = read_plan(text.removeprefix("\ufeff"), filename)
    return _build(src, vehicle, name or _default_name(filename), auto_arm, "QGroundControl plan", zones)


def import_waypoints(
    text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False, zones: Sequence[FileContents] = ()
) -> Imported:
    """A Mission Planner ``QGC WPL 110`` file as a mission; it does not name its vehicle, so ``vehicle`` is needed. Raises :class:`MissionError`."""
    src = read_waypoints(text.removeprefix("\ufeff"), filename)
    return _build(src, vehicle, name or _default_name(filename), auto_arm, "Mission Planner waypoints", zones)


def import_text(
    text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False, zones: Sequence[FileContents] = ()
) -> Imported:
    """Either format, told apart by content (``QGC WPL``) or the file name's suffix (.waypoints, .txt, .mission); ``zones``: Mission
    Planner fence and rally files read (:func:`~executive.mission.formats.mp_zone_files.read_zone_file`), their zones and rally points added."""
    is_wpl = text.removeprefix("\ufeff").startswith("QGC WPL") or filename.lower().endswith(WPL_SUFFIXES)
    if not is_wpl and not filename.lower().endswith(".plan") and not text.removeprefix("\ufeff").lstrip().startswith("{"):
        raise MissionError([FieldError(filename, 1, 1, "(file)", f"not a file import reads: {IMPORTED_KINDS}")])
    reader: Callable[..., Imported] = import_waypoints if is_wpl else import_plan
    return reader(text, filename, vehicle=vehicle, name=name, auto_arm=auto_arm, zones=zones)


def import_file(
    path: str | os.PathLike[str], *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False, zone_files: Sequence[str] = ()
) -> Imported:
    """Read a .plan or .waypoints file and import it, with Mission Planner fence and rally files (``zone_files``: .fen, .poly,
    .rally, or QGC WPL 110 fence/rally plans); every problem located. Raises :class:`MissionError`."""
    zones = [read_zone_file(*_text_of(zone_file)) for zone_file in zone_files]
    text, filename = _text_of(path)
    return import_text(text, filename, vehicle=vehicle, name=name, auto_arm=auto_arm, zones=zones)


def _text_of(path: str | os.PathLike[str]) -> tuple[str, str]:
    """A file's text and name; MissionError (located) if it cannot be read as UTF-8 text of at most MAX_BYTES."""
    filename = os.fsdecode(path)
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_BYTES + 1)
    except OSError as exc:
        raise MissionError([FieldError(filename, 1, 1, "(file)", exc.strerror or str(exc))]) from None
    if len(data) > MAX_BYTES:
        raise MissionError([FieldError(filename, 1, 1, "(file)", f"larger than {MAX_BYTES // (1024 * 1024)} MiB")])
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start].decode("utf-8", "replace")
        line, column = before.count("\n") + 1, len(before) - before.rfind("\n")
        raise MissionError([FieldError(filename, line, column, "(file)", f"not UTF-8 text: byte 0x{data[exc.start]:02x}")]) from None
    return text, filename


def _default_name(filename: str) -> str:
    stem = os.path.splitext(os.path.basename(filename))[0]
    return stem[:128] or "imported"


# -- exporting --------------------------------------------------------------------------------

_Row = tuple[int, int, list[float | None]]  # command, frame, param1-4, lat, lon, alt


def _route(mission: Mission) -> tuple[list[_Row], list[tuple[Path, str]]]:
    """The mission items of a mission's route, and what they cannot say."""
    rows: list[_Row] = []
    warnings: list[tuple[Path, str]] = []
    speed: float | None = None
    for i, wp in enumerate(mission.waypoints):
        here: Path = ("waypoints", i)
        if wp.speed_m_s is not None and wp.speed_m_s != speed:
            rows.append((CMD_CHANGE_SPEED, FRAME_MISSION, [1.0, wp.speed_m_s, -1.0, 0.0, 0.0, 0.0, 0.0]))
            speed = wp.speed_m_s
        elif wp.speed_m_s is None and speed is not None:
            warnings.append(
                ((*here, "speed_m_s"), f"not set after a waypoint at {speed:g} m/s: the vehicle keeps that speed (no command restores the default)")
            )
        frame, alt = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, wp.alt_m
        if mission.vehicle == "sub":
            if wp.control_mode == "altitude" and wp.altitude_m is not None:
                frame, alt = mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT, wp.altitude_m
            elif wp.depth_m is not None:
                alt = -wp.depth_m
            elif wp.control_mode is not None:
                warnings.append(((*here, "control_mode"), f"control_mode {wp.control_mode} without its target: exported as a plain waypoint"))
            if (wp.altitude_m is not None or wp.depth_m is not None) and wp.alt_m != 0.0:
                warnings.append(((*here, "alt_m"), "not exported: a sub's mission item altitude carries its depth or its altitude above the seabed"))
        if wp.name is not None:
            warnings.append(((*here, "name"), "not exported: a mission item has no name"))
        if wp.sample:
            warnings.append(((*here, "sample"), "not exported: a mission item cannot ask for a sample"))
        rows.append((CMD_WAYPOINT, frame, [0.0, 0.0, 0.0, None, wp.lat, wp.lon, alt]))
    if mission.home is not None and mission.home.heading_deg != 0.0:
        warnings.append((("home", "heading_deg"), "not exported: a planned home has no heading"))
    return rows, warnings


def export_plan(mission: Mission) -> Exported:
    """The mission as a QGroundControl .plan (JSON, as QGroundControl 4 writes it)."""
    rows, warnings = _route(mission)
    items = []
    for jump_id, (command, frame, params) in enumerate(rows, start=1):
        item: dict[str, Any] = {"autoContinue": True, "command": command, "doJumpId": jump_id, "frame": frame, "params": params, "type": "SimpleItem"}
        if command == CMD_WAYPOINT:
            mode = QGC_ALTITUDE_TERRAIN_FRAME if frame in FRAME_TERRAIN else QGC_ALTITUDE_RELATIVE
            item |= {"AMSLAltAboveTerrain": None, "Altitude": params[6], "AltitudeMode": mode}
        items.append(dict(sorted(item.items())))
    if mission.home is not None:
        home = [mission.home.lat, mission.home.lon, 0.0]
    else:
        home = [mission.waypoints[0].lat, mission.waypoints[0].lon, 0.0] if mission.waypoints else [0.0, 0.0, 0.0]
        warnings.append((("home",), "no home: the plan's planned home is the first waypoint"))
    polygons, circles = [], []
    if mission.geofence is not None:
        if mission.geofence.polygon is not None:
            ring = [[v.lat, v.lon] for v in mission.geofence.polygon]
            if len(ring) > 3 and ring[0] == ring[-1]:
                ring.pop()  # QGroundControl's polygons do not repeat the first vertex
            polygons.append({"inclusion": True, "polygon": ring, "version": 1})
        if mission.geofence.max_distance_from_home_m is not None:
            if mission.home is not None:
                circles.append({"circle": {"center": home[:2], "radius": mission.geofence.max_distance_from_home_m}, "inclusion": True, "version": 1})
            else:
                warnings.append((("geofence", "max_distance_from_home_m"), "not exported: no home to centre the circle on"))
        for kind, inclusion in (("inclusion", True), ("keep_out", False)):
            for i, zone in enumerate(getattr(mission.geofence, kind)):
                if zone.name:  # QGroundControl's fence shapes have no names
                    warnings.append((("geofence", kind, i, "name"), f"not exported: {zone.name!r} (a plan's fence shapes have no names)"))
                if zone.circle is not None:
                    centre = [zone.circle.lat, zone.circle.lon]
                    circles.append({"circle": {"center": centre, "radius": zone.circle.radius_m}, "inclusion": inclusion, "version": 1})
                else:
                    ring = [[v.lat, v.lon] for v in zone.polygon or ()]
                    if len(ring) > 3 and ring[0] == ring[-1]:
                        ring.pop()
                    polygons.append({"inclusion": inclusion, "polygon": ring, "version": 1})
    rally = []
    for i, point in enumerate(mission.rally_points):
        rally.append([point.lat, point.lon, point.alt_m])  # RallyPointController::save: [latitude, longitude, altitude]
        if point.name:
            warnings.append((("rally_points", i, "name"), f"not exported: {point.name!r} (a plan's rally points have no names)"))
    speeds = [wp.speed_m_s for wp in mission.waypoints if wp.speed_m_s is not None]
    plan = {
        "fileType": "Plan",
        "geoFence": {"circles": circles, "polygons": polygons, "version": 2},
        "groundStation": "executive",
        "mission": {
            "cruiseSpeed": speeds[0] if speeds else 15.0 if mission.vehicle == "vtol" else 2.0,
            "firmwareType": ARDUPILOT,
            "globalPlanAltitudeMode": QGC_ALTITUDE_RELATIVE,
            "hoverSpeed": 5.0,
            "items": items,
            "plannedHomePosition": home,
            "vehicleType": vehicle_profile(mission.vehicle).mav_type,
            "version": 2,
        },
        "rallyPoints": {"points": rally, "version": 2},
        "version": 1,
    }
    return Exported(json.dumps(plan, indent=4) + "\n", tuple(warnings))


def export_waypoints(mission: Mission) -> Exported:
    """The mission as a Mission Planner ``QGC WPL 110`` file (line 0 is home; 0, 0 when the mission has none)."""
    rows, warnings = _route(mission)
    home = (mission.home.lat, mission.home.lon) if mission.home else (0.0, 0.0)
    if mission.home is not None and round(home[0], 8) == round(home[1], 8) == 0.0:  # as written, 8 decimals
        warnings.append((("home",), "a home at 0°, 0° reads as no home in a .waypoints file"))
    if mission.geofence is not None:
        warnings.append((("geofence",), "not exported: a .waypoints file has no geofence"))
    if mission.rally_points:
        warnings.append((("rally_points",), "not exported: a .waypoints file has no rally points (Mission Planner keeps them in a .rally file)"))
    lines = [WPL_HEADER, _wpl_line(0, 1, mavlink.MAV_FRAME_GLOBAL, CMD_WAYPOINT, [0.0, 0.0, 0.0, 0.0, *home, 0.0])]
    lines += [_wpl_line(n, 0, frame, command, params) for n, (command, frame, params) in enumerate(rows, start=1)]
    return Exported("\n".join(lines) + "\n", tuple(warnings))


def _wpl_line(index: int, current: int, frame: int, command: int, params: list[float | None]) -> str:
    """One item, tab-separated, with Mission Planner's precision (8 decimals; 6 for the altitude)."""
    values = [f"{0.0 if p is None else p:.8f}" for p in params[:6]] + [f"{0.0 if params[6] is None else params[6]:.6f}"]
    return "\t".join([str(index), str(current), str(frame), str(command), *values, "1"])
