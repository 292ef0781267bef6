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
  circle centred on home <-> ``geofence.max_distance_from_home_m``. A survey or corridor scan
  (``ComplexItem``) is imported as the mission items QGroundControl generated for it (its
  ``TransectStyleComplexItem.Items``), with a warning that the pattern itself is not kept.

Everything else is reported as a located warning, never dropped silently: other commands, a
waypoint's hold time, acceptance or pass radius and yaw, ``autoContinue`` false, exclusion fences,
circles not centred on home, rally points. Bad input raises :class:`MissionError`, every problem
as ``FILE:LINE:COL: FIELD: message`` (JSON: the decoder's position, or where the offending value
starts; WPL: the line and the column of the field). Export writes what a mission holds, and says
(as ``(path, why)`` pairs) what the format cannot carry: waypoint names, sample flags, a geofence in
a ``.waypoints`` file. Executive settings (tree, limits, RC, ...) are not part of either format.
"""

from __future__ import annotations

import bisect
import json
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from json.decoder import scanstring
from typing import Any

import yaml

from executive.geo import distance
from executive.io.mavlink.dialect import mavlink
from executive.mission.errors import FieldError, MissionError, Path, format_path
from executive.mission.loader import load_mission_text
from executive.mission.model import VTOL_MIN_ACCEPTANCE_RADIUS_M, Limits, Mission
from executive.vehicles import PROFILES, profile_for_mav_type

MAX_BYTES = 16 * 1024 * 1024  # a survey of a large area makes a big .plan
MAX_JSON_DEPTH = 64

CMD_WAYPOINT = mavlink.MAV_CMD_NAV_WAYPOINT
CMD_CHANGE_SPEED = mavlink.MAV_CMD_DO_CHANGE_SPEED
FRAME_AMSL = (mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT)
FRAME_RELATIVE = (mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
FRAME_TERRAIN = (mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT, mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT)
FRAME_MISSION = mavlink.MAV_FRAME_MISSION
ARDUPILOT = mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
QGC_ALTITUDE_RELATIVE, QGC_ALTITUDE_TERRAIN_FRAME = 1, 4  # QGroundControl's AltitudeMode values
HOME_CIRCLE_M = 1.0  # an inclusion circle centred this close to home is a maximum distance from home

WPL_HEADER = "QGC WPL 110"
WPL_COLUMNS = ("index", "current", "frame", "command", "param1", "param2", "param3", "param4", "latitude", "longitude", "altitude", "autocontinue")
WPL_SUFFIXES = (".waypoints", ".txt", ".mission")
_WPL_INTEGERS = {"index", "current", "frame", "command", "autocontinue"}


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


# -- reading ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _At:
    """Where something is in the source file (1-based line and column) and what it is called there."""

    line: int
    column: int
    field: str


@dataclass(frozen=True)
class _Item:
    """One mission item as either format has it."""

    command: int
    frame: int
    params: tuple[float | None, ...]  # param1-4, x (lat), y (lon), z (alt); None = unset (NaN, null)
    autocontinue: bool
    at: _At
    frame_at: _At
    param_at: tuple[_At, ...]
    group: str | None = None  # the complex item it was generated for, if any


@dataclass
class _Source:
    """What a file says, before it becomes a mission."""

    filename: str
    start: _At  # the whole file (the header line for WPL)
    items: list[_Item] = field(default_factory=list)
    items_at: _At | None = None
    home: tuple[float, float, float | None] | None = None  # lat, lon, altitude above mean sea level
    home_at: _At | None = None
    polygon: list[tuple[float, float, _At]] | None = None
    polygon_at: _At | None = None
    circles: list[tuple[float, float, float, _At]] = field(default_factory=list)  # inclusion circles: lat, lon, radius
    vehicle: str | None = None
    vehicle_at: _At | None = None
    vehicle_why: str = ""  # why no vehicle kind could be inferred
    errors: list[FieldError] = field(default_factory=list)
    warnings: list[FieldError] = field(default_factory=list)

    def error(self, at: _At, message: str) -> None:
        self.errors.append(FieldError(self.filename, at.line, at.column, at.field, message))

    def warn(self, at: _At, message: str) -> None:
        self.warnings.append(FieldError(self.filename, at.line, at.column, at.field, message))


def _command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return f"{entry.name.removeprefix('MAV_CMD_')} ({command})" if entry else f"command {command}"


def _frame_name(frame: int) -> str:
    entry = mavlink.enums["MAV_FRAME"].get(frame)
    return f"{entry.name.removeprefix('MAV_FRAME_')} ({frame})" if entry else f"frame {frame}"


def _finite(value: Any) -> float | None:
    """A JSON number as a finite float; None for anything else (bool, NaN, Infinity, an integer too big for a float)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _describe(value: Any) -> str:
    """A JSON value, as found: ``string "47.3"``, ``null``, ``an object``."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"bool {str(value).lower()}"
    if isinstance(value, dict | list):
        return "an object" if isinstance(value, dict) else "an array"
    if isinstance(value, int) and _finite(value) is None:
        return "an integer too big for a number"
    text = json.dumps(value) if isinstance(value, str) else repr(value)
    kind = "string" if isinstance(value, str) else "number"
    return f"{kind} {text if len(text) <= 40 else text[:37] + '...'}"


# -- .plan (JSON) -----------------------------------------------------------------------------

_WS = re.compile(r"[ \t\n\r]*")
_SCALAR = re.compile(r"-?(?:0|[1-9]\d*)(?:\.\d+)?(?:[eE][-+]?\d+)?|true|false|null|NaN|-?Infinity")


def _json_offsets(text: str) -> dict[Path, int]:
    """Where each value of a (valid) JSON document starts, by path: the decoder keeps no positions."""
    offsets: dict[Path, int] = {}

    def skip(i: int) -> int:
        return _WS.match(text, i).end()  # type: ignore[union-attr]  # `*` always matches

    def value(i: int, path: Path) -> int:
        if len(path) > MAX_JSON_DEPTH:
            raise RecursionError
        i = skip(i)
        offsets[path] = i
        opening = text[i]
        if opening in "{[":
            closing, n = ("}" if opening == "{" else "]"), 0
            i = skip(i + 1)
            while text[i] != closing:
                if opening == "{":
                    key, i = scanstring(text, i + 1)
                    i = value(skip(i) + 1, (*path, key))  # past the colon
                else:
                    i = value(i, (*path, n))
                n += 1
                i = skip(i)
                if text[i] == ",":
                    i = skip(i + 1)
            return i + 1
        if opening == '"':
            return scanstring(text, i + 1)[1]
        return _SCALAR.match(text, i).end()  # type: ignore[union-attr]  # the document is valid JSON

    value(0, ())
    return offsets


class _PlanReader:
    """Reads a .plan document, every problem located at the value it is about."""

    def __init__(self, text: str, filename: str) -> None:
        self.src = _Source(filename, _At(1, 1, "(plan)"))
        self._offsets = _json_offsets(text)
        self._newlines = [m.start() for m in re.finditer("\n", text)]

    def at(self, path: Path) -> _At:
        """The position of the value at ``path`` (or of its nearest enclosing value in the file)."""
        found = next((path[:n] for n in range(len(path), -1, -1) if path[:n] in self._offsets), ())
        offset = self._offsets.get(found, 0)
        line = bisect.bisect_left(self._newlines, offset)
        column = offset - (self._newlines[line - 1] if line else -1)
        return _At(line + 1, column, format_path(path) if path else "(plan)")

    def get(self, parent: dict[str, Any], path: Path, kind: str, *, required: bool = True) -> Any:
        """``parent[path[-1]]`` if it is of ``kind`` (object, array, number, integer, bool, string); else None, with an error."""
        key = path[-1]
        assert isinstance(key, str)
        if key not in parent:
            if required:
                self.src.error(self.at(path[:-1]), f"{key}: required field is missing")
            return None
        return self.check(parent[key], path, kind)

    def check(self, value: Any, path: Path, kind: str, *, nullable: bool = False) -> Any:
        """``value`` if it is of ``kind`` (None if null and ``nullable``); else None, with an error."""
        if value is None and nullable:
            return None
        number = _finite(value)
        if kind in ("number", "integer"):
            if number is not None and (kind == "number" or number.is_integer()):
                return number if kind == "number" else int(number)
        elif isinstance(value, {"object": dict, "array": list, "bool": bool, "string": str}[kind]):
            return value
        article = "an" if kind[0] in "aeiou" else "a"
        self.src.error(self.at(path), f"expected {article} {kind}{' or null' if nullable else ''}, got {_describe(value)}")
        return None

    def read(self, data: Any) -> _Source:
        src = self.src
        if not isinstance(data, dict):
            src.error(self.at(()), f"expected a JSON object (a QGroundControl plan), got {_describe(data)}")
            return src
        if (file_type := self.get(data, ("fileType",), "string")) is not None and file_type != "Plan":
            src.error(self.at(("fileType",)), f"{file_type!r}: not a QGroundControl plan (fileType must be 'Plan')")
        mission = self.get(data, ("mission",), "object")
        if mission is not None:
            self._mission(mission)
        fence = self.get(data, ("geoFence",), "object", required=False)
        if fence is not None:
            self._fence(fence)
        rally = self.get(data, ("rallyPoints",), "object", required=False)
        points = self.get(rally, ("rallyPoints", "points"), "array", required=False) if rally is not None else None
        if points:
            src.warn(self.at(("rallyPoints", "points")), f"{len(points)} rally point(s) not imported: a mission file has no rally points")
        return src

    def _mission(self, mission: dict[str, Any]) -> None:
        src, here = self.src, ("mission",)
        version = self.get(mission, (*here, "version"), "integer")
        if version is not None and version != 2:
            src.error(self.at((*here, "version")), f"mission version {version}: only version 2 (the current format) is read")
        vehicle_type = self.get(mission, (*here, "vehicleType"), "integer", required=False)
        if vehicle_type is not None:
            src.vehicle_at = self.at((*here, "vehicleType"))
            profile = profile_for_mav_type(vehicle_type)
            if profile is not None:
                src.vehicle = profile.kind
            else:
                entry = mavlink.enums["MAV_TYPE"].get(vehicle_type)
                name = entry.name.removeprefix("MAV_TYPE_") if entry else "unknown"
                src.vehicle_why = f"vehicleType {vehicle_type} ({name}) is not a vehicle the executive drives: pass --vehicle"
        else:
            src.vehicle_at, src.vehicle_why = self.at(here), "the plan has no vehicleType: pass --vehicle"
        home = self.get(mission, (*here, "plannedHomePosition"), "array", required=False)
        if home is not None:
            self._home(home, (*here, "plannedHomePosition"))
        items = self.get(mission, (*here, "items"), "array")
        src.items_at = self.at((*here, "items"))
        for i, item in enumerate(items or []):
            self._item(item, (*here, "items", i), None)

    def _home(self, home: list[Any], path: Path) -> None:
        if len(home) not in (2, 3):
            self.src.error(self.at(path), f"expected [latitude, longitude, altitude], got {len(home)} values")
            return
        lat, lon = self.check(home[0], (*path, 0), "number"), self.check(home[1], (*path, 1), "number")
        alt = self.check(home[2], (*path, 2), "number", nullable=True) if len(home) == 3 else None
        if lat is not None and lon is not None:
            self.src.home, self.src.home_at = (lat, lon, alt), self.at(path)

    def _item(self, item: Any, path: Path, group: str | None) -> None:
        src = self.src
        if self.check(item, path, "object") is None:
            return
        kind = self.get(item, (*path, "type"), "string")
        if kind == "ComplexItem":
            self._complex_item(item, path)
            return
        if kind != "SimpleItem":
            if kind is not None:
                src.warn(self.at((*path, "type")), f"not imported: a {kind!r} item (only SimpleItem and ComplexItem are known)")
            return
        command = self.get(item, (*path, "command"), "integer")
        frame = self.get(item, (*path, "frame"), "integer")
        autocontinue = self.get(item, (*path, "autoContinue"), "bool", required=False)
        params = self.get(item, (*path, "params"), "array")
        if params is not None and len(params) != 7:
            src.error(self.at((*path, "params")), f"expected 7 params (param1-4, latitude, longitude, altitude), got {len(params)}")
            return
        before = len(src.errors)
        values = tuple(self.check(p, (*path, "params", i), "number", nullable=True) for i, p in enumerate(params or []))
        if command is None or frame is None or params is None or len(src.errors) > before:
            return
        src.items.append(
            _Item(
                command,
                frame,
                values,
                autocontinue is not False,
                self.at(path),
                self.at((*path, "frame")),
                tuple(self.at((*path, "params", i)) for i in range(7)),
                group,
            )
        )

    def _complex_item(self, item: dict[str, Any], path: Path) -> None:
        kind = item.get("complexItemType", "complex item")
        transect = item.get("TransectStyleComplexItem")
        generated = transect.get("Items") if isinstance(transect, dict) else None
        if not isinstance(generated, list):
            self.src.warn(self.at(path), f"not imported: {kind} (no generated mission items in the file: convert it to waypoints in QGroundControl)")
            return
        self.src.warn(
            self.at(path), f"{kind}: imported as the {len(generated)} mission items QGroundControl generated for it; the {kind} itself is not kept"
        )
        for j, sub in enumerate(generated):
            self._item(sub, (*path, "TransectStyleComplexItem", "Items", j), format_path(path))

    def _fence(self, fence: dict[str, Any]) -> None:
        src, here = self.src, ("geoFence",)
        for i, polygon in enumerate(self.get(fence, (*here, "polygons"), "array", required=False) or []):
            path = (*here, "polygons", i)
            if self.check(polygon, path, "object") is None:
                continue
            inclusion = self.get(polygon, (*path, "inclusion"), "bool", required=False)
            vertices = self.get(polygon, (*path, "polygon"), "array")
            if vertices is None:
                continue
            if inclusion is False:
                src.warn(self.at(path), "not imported: an exclusion polygon (a mission geofence is one inclusion polygon)")
                continue
            if src.polygon is not None:
                src.warn(self.at(path), "not imported: a second inclusion polygon (a mission geofence is one polygon)")
                continue
            corners = []
            for j, vertex in enumerate(vertices):
                vpath = (*path, "polygon", j)
                if self.check(vertex, vpath, "array") is None:
                    continue
                if len(vertex) != 2:
                    src.error(self.at(vpath), f"expected [latitude, longitude], got {len(vertex)} values")
                    continue
                lat, lon = self.check(vertex[0], (*vpath, 0), "number"), self.check(vertex[1], (*vpath, 1), "number")
                if lat is not None and lon is not None:
                    corners.append((lat, lon, self.at(vpath)))
            src.polygon, src.polygon_at = corners, self.at((*path, "polygon"))
        for i, circle in enumerate(self.get(fence, (*here, "circles"), "array", required=False) or []):
            path = (*here, "circles", i)
            if self.check(circle, path, "object") is None:
                continue
            inclusion = self.get(circle, (*path, "inclusion"), "bool", required=False)
            shape = self.get(circle, (*path, "circle"), "object")
            if shape is None:
                continue
            centre = self.get(shape, (*path, "circle", "center"), "array")
            radius = self.get(shape, (*path, "circle", "radius"), "number")
            if centre is None or radius is None:
                continue
            if len(centre) != 2:
                src.error(self.at((*path, "circle", "center")), f"expected [latitude, longitude], got {len(centre)} values")
                continue
            lat = self.check(centre[0], (*path, "circle", "center", 0), "number")
            lon = self.check(centre[1], (*path, "circle", "center", 1), "number")
            if lat is None or lon is None:
                continue
            if inclusion is False:
                src.warn(self.at(path), "not imported: an exclusion circle (a mission geofence has none)")
            else:
                src.circles.append((lat, lon, radius, self.at(path)))


def _read_plan(text: str, filename: str) -> _Source:
    try:
        data = json.loads(text)
        reader = _PlanReader(text, filename)
    except json.JSONDecodeError as exc:
        raise MissionError([FieldError(filename, exc.lineno, exc.colno, "(json)", exc.msg)]) from None
    except RecursionError:
        raise MissionError([FieldError(filename, 1, 1, "(json)", f"nested deeper than {MAX_JSON_DEPTH} levels")]) from None
    except ValueError as exc:  # an integer of more digits than Python converts
        digits = re.search(r"\d{4301,}", text)
        offset = digits.start() if digits else 0
        line, column = text.count("\n", 0, offset) + 1, offset - text.rfind("\n", 0, offset)
        raise MissionError([FieldError(filename, line, column, "(json)", str(exc).split(";")[0])]) from None
    return reader.read(data)


# -- QGC WPL 110 (text) -----------------------------------------------------------------------


def _read_waypoints(text: str, filename: str) -> _Source:
    lines = text.splitlines()
    header = lines[0].strip() if lines else ""
    src = _Source(filename, _At(1, 1, "(header)"))
    src.items_at = src.start
    src.vehicle_at, src.vehicle_why = src.start, "a .waypoints file does not say which vehicle it is for: pass --vehicle"
    if header != WPL_HEADER:
        found = repr(header[:40]) if header else "an empty line"
        src.error(src.start, f"expected {WPL_HEADER!r} on the first line (a Mission Planner waypoint file), got {found}")
        return src
    number = 0
    for line_no, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        fields = [(m.start() + 1, m.group()) for m in re.finditer(r"\S+", line)]
        name = f"item[{number}]"
        if len(fields) != len(WPL_COLUMNS):
            column = fields[len(WPL_COLUMNS)][0] if len(fields) > len(WPL_COLUMNS) else len(line.rstrip()) + 1
            src.error(_At(line_no, column, name), f"expected {len(WPL_COLUMNS)} tab-separated fields ({', '.join(WPL_COLUMNS)}), got {len(fields)}")
            number += 1
            continue
        before = len(src.errors)
        at = [_At(line_no, column, f"{name}.{col}") for (column, _), col in zip(fields, WPL_COLUMNS, strict=True)]
        values = [_wpl_value(src, where, token) for where, (_, token) in zip(at, fields, strict=True)]
        number += 1
        if len(src.errors) > before:
            continue
        index, _, frame, command, *params, autocontinue = values
        lat, lon, alt = params[4:]
        if number == 1:  # line 0 is home; 0, 0 = not set
            if (lat, lon) != (0.0, 0.0):
                src.home, src.home_at = (lat, lon, alt), _At(line_no, at[8].column, name)
            continue
        unset = tuple(None if math.isnan(p) else p for p in params)  # params 1-4 may be NaN
        src.items.append(_Item(int(command), int(frame), unset, bool(autocontinue), _At(line_no, 1, name), at[2], tuple(at[4:11])))
        if index != number - 1:
            src.warn(at[0], f"index {index:g} out of sequence (expected {number - 1}): items are taken in file order")
    return src


def _wpl_value(src: _Source, at: _At, token: str) -> float:
    """A WPL field as a number (integral for the integer columns; NaN only for params 1-4, meaning unset); else an error."""
    column = at.field.rsplit(".", 1)[-1]
    try:
        value = float(token)
    except ValueError:
        src.error(at, f"expected a number, got {token[:40]!r}")
        return math.nan
    if column in _WPL_INTEGERS and not value.is_integer():
        src.error(at, f"expected an integer, got {token[:40]!r}")
    elif not math.isfinite(value) and not (column.startswith("param") and math.isnan(value)):
        src.error(at, f"expected a finite number, got {token[:40]!r}")
    return value


# -- from what a file says to a mission -------------------------------------------------------


class _IndentedDumper(yaml.SafeDumper):
    """Lists indented under their key, as the example missions are written."""

    def increase_indent(self, flow: bool = False, indentless: bool = False) -> None:
        super().increase_indent(flow, False)


def _build(src: _Source, kind_given: str | None, name: str, auto_arm: bool, what: str) -> Imported:
    """The mission a source describes, validated; every problem located in the source file."""
    kind = kind_given or src.vehicle
    if kind is None and (src.vehicle_at is not None or not src.errors):  # no mission section at all says enough
        src.error(src.vehicle_at or src.start, src.vehicle_why or "no vehicle kind: pass --vehicle")
    elif kind_given and src.vehicle and src.vehicle != kind_given and src.vehicle_at:
        src.warn(src.vehicle_at, f"the file is for a {src.vehicle}; imported for a {kind_given} as --vehicle says")
    doc: dict[str, Any] = {"version": 1, "name": name, "vehicle": kind}
    if auto_arm:
        doc["auto_arm"] = True
    sources: dict[str, _At] = {}
    home_alt = src.home[2] if src.home else None
    if src.home is not None and src.home_at is not None:
        doc["home"] = {"lat": src.home[0], "lon": src.home[1]}
        sources["home"] = src.home_at
    fence = _fence(src, sources)
    if fence:
        doc["geofence"] = fence
    waypoints: list[dict[str, Any]] = []
    speed: tuple[float, _At] | None = None
    skipped: dict[tuple[str, int], list[_At]] = {}
    for item in src.items:
        if item.command == CMD_CHANGE_SPEED:
            speed = _speed_change(src, item, speed)
            continue
        if item.command != CMD_WAYPOINT:
            if item.group is None:
                src.warn(item.at, f"not imported: {_command_name(item.command)}: a mission file holds waypoints and their speeds only")
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
        src.warn(places[0], f"not imported: {_command_name(command)}{more} in {group}")
    limits: dict[str, Any] = {}
    notes: list[str] = []
    if kind == "vtol":  # the mission rules ask it of every vtol; no ground-station file has it
        limits["acceptance_radius_m"] = VTOL_MIN_ACCEPTANCE_RADIUS_M
        notes.append(f"limits.acceptance_radius_m is {VTOL_MIN_ACCEPTANCE_RADIUS_M:g} m, the least for a vtol (it circles its points as a plane).")
    if speeds := _speed_limits(src, waypoints, sources):
        limits["speed_m_s"] = speeds
    if limits:
        doc["limits"] = limits
    doc["waypoints"] = waypoints
    sources["waypoints"] = src.items_at or src.start
    if src.errors:
        raise MissionError(src.errors)
    header = [f"Imported from {os.path.basename(src.filename)} ({what}) by `executive import`.", *notes]
    if src.warnings:
        header.append("Not imported or changed on the way (details in the import's warnings):")
        header += [f"  line {w.line}: {w.field}: {w.message}" for w in sorted(src.warnings, key=lambda w: (w.line, w.column))]
    text = "".join(f"# {line}\n" for line in header) + yaml.dump(
        doc, Dumper=_IndentedDumper, sort_keys=False, default_flow_style=None, allow_unicode=True, width=150
    )
    try:
        mission = load_mission_text(text, src.filename)
    except MissionError as exc:
        raise MissionError([_relocate(e, sources, src) for e in exc.errors]) from None
    return Imported(mission, text, tuple(sorted(src.warnings, key=lambda w: (w.line, w.column, w.field))))


def _relocate(error: FieldError, sources: dict[str, _At], src: _Source) -> FieldError:
    """An error found in the generated YAML, located at what it came from in the source file."""
    keys = [k for k in sources if error.field == k or error.field.startswith((f"{k}.", f"{k}["))]
    at = sources[max(keys, key=len)] if keys else src.start
    return FieldError(src.filename, at.line, at.column, at.field, f"{error.message} (as {error.field} of the mission)")


def _speed_change(src: _Source, item: _Item, speed: tuple[float, _At] | None) -> tuple[float, _At] | None:
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


def _waypoint(src: _Source, item: _Item, kind: str | None, home_alt: float | None) -> dict[str, Any] | None:
    """A NAV_WAYPOINT as a mission waypoint; None (with an error) if it cannot be one."""
    p = item.params
    lat, lon, alt = p[4], p[5], 0.0 if p[6] is None else p[6]
    if lat is None or lon is None:
        src.error(item.param_at[4 if lat is None else 5], "a waypoint needs a latitude and a longitude")
        return None
    wp: dict[str, Any] = {"lat": lat, "lon": lon}
    if item.frame in FRAME_AMSL:
        if home_alt is None:
            src.error(item.frame_at, f"{_frame_name(item.frame)}: an altitude above mean sea level needs the home's altitude, and there is none")
            return None
        src.warn(item.param_at[6], f"altitude {alt:g} m above mean sea level imported as {alt - home_alt:g} m above home (home at {home_alt:g} m)")
        alt -= home_alt
    elif item.frame in FRAME_TERRAIN:
        if kind == "sub":
            wp |= {"altitude_m": alt, "control_mode": "altitude"}
            return _waypoint_params(src, item, wp)
        src.warn(item.frame_at, f"{_frame_name(item.frame)}: the altitude above terrain is imported as {alt:g} m above home")
    elif item.frame not in FRAME_RELATIVE:
        src.error(item.frame_at, f"{_frame_name(item.frame)}: a waypoint needs a global frame (0, 3, 10 or their _INT forms)")
        return None
    if kind == "sub" and math.copysign(1.0, alt) < 0.0:  # ArduSub: below the surface; -0.0 is depth 0
        wp |= {"depth_m": -alt, "control_mode": "depth"}
    else:
        wp["alt_m"] = alt
    return _waypoint_params(src, item, wp)


def _waypoint_params(src: _Source, item: _Item, wp: dict[str, Any]) -> dict[str, Any]:
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


def _fence(src: _Source, sources: dict[str, _At]) -> dict[str, Any]:
    fence: dict[str, Any] = {}
    if src.polygon is not None and src.polygon_at is not None:
        fence["polygon"] = [{"lat": lat, "lon": lon} for lat, lon, _ in src.polygon]
        sources["geofence.polygon"] = src.polygon_at
        sources |= {f"geofence.polygon[{i}]": at for i, (_, _, at) in enumerate(src.polygon)}
    for lat, lon, radius, at in src.circles:
        if src.home is None:
            src.warn(at, "not imported: an inclusion circle, and no home it could be a distance from")
        elif distance(lat, lon, src.home[0], src.home[1]) > HOME_CIRCLE_M:
            src.warn(at, "not imported: an inclusion circle not centred on home (a mission geofence has a distance from home)")
        elif "max_distance_from_home_m" in fence:
            src.warn(at, "not imported: a second inclusion circle around home")
        else:
            fence["max_distance_from_home_m"] = radius
            sources["geofence.max_distance_from_home_m"] = at
    if fence:
        sources["geofence"] = src.polygon_at or sources["geofence.max_distance_from_home_m"]
    return fence


def _speed_limits(src: _Source, waypoints: list[dict[str, Any]], sources: dict[str, _At]) -> dict[str, float] | None:
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


def import_plan(text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False) -> Imported:
    """A QGroundControl .plan as a mission; ``vehicle`` overrides the plan's vehicleType. Raises :class:`MissionError`."""
    src = _read_plan(text.removeprefix("\ufeff"), filename)
    return _build(src, vehicle, name or _default_name(filename), auto_arm, "QGroundControl plan")


def import_waypoints(text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False) -> Imported:
    """A Mission Planner ``QGC WPL 110`` file as a mission; it does not name its vehicle, so ``vehicle`` is needed. Raises :class:`MissionError`."""
    src = _read_waypoints(text.removeprefix("\ufeff"), filename)
    return _build(src, vehicle, name or _default_name(filename), auto_arm, "Mission Planner waypoints")


def import_text(text: str, filename: str, *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False) -> Imported:
    """Either format, told apart by content (``QGC WPL``) or the file name's suffix (.waypoints, .txt, .mission)."""
    is_wpl = text.removeprefix("\ufeff").startswith("QGC WPL") or filename.lower().endswith(WPL_SUFFIXES)
    reader: Callable[..., Imported] = import_waypoints if is_wpl else import_plan
    return reader(text, filename, vehicle=vehicle, name=name, auto_arm=auto_arm)


def import_file(path: str | os.PathLike[str], *, vehicle: str | None = None, name: str | None = None, auto_arm: bool = False) -> Imported:
    """Read a .plan or .waypoints file and import it; every problem located. Raises :class:`MissionError`."""
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
    return import_text(text, filename, vehicle=vehicle, name=name, auto_arm=auto_arm)


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
            "vehicleType": PROFILES[mission.vehicle].mav_type,
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
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
    lines = [WPL_HEADER, _wpl_line(0, 1, mavlink.MAV_FRAME_GLOBAL, CMD_WAYPOINT, [0.0, 0.0, 0.0, 0.0, *home, 0.0])]
    lines += [_wpl_line(n, 0, frame, command, params) for n, (command, frame, params) in enumerate(rows, start=1)]
    return Exported("\n".join(lines) + "\n", tuple(warnings))


def _wpl_line(index: int, current: int, frame: int, command: int, params: list[float | None]) -> str:
    """One item, tab-separated, with Mission Planner's precision (8 decimals; 6 for the altitude)."""
    values = [f"{0.0 if p is None else p:.8f}" for p in params[:6]] + [f"{0.0 if params[6] is None else params[6]:.6f}"]
    return "\t".join([str(index), str(current), str(frame), str(command), *values, "1"])
