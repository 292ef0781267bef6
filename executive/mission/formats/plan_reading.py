"""Reading the two formats into :class:`~executive.mission.formats.plan_items.FileContents`: QGroundControl ``.plan`` (JSON), ``QGC WPL 110`` (text).

Every value is located: JSON at the decoder's position or where the offending value starts, WPL at
the line and the column of the field.
"""

from __future__ import annotations

import bisect
import json
import math
import re
from json.decoder import scanstring
from typing import Any

from executive.mission.errors import FieldError, MissionError, Path, format_path
from executive.mission.formats.plan_items import (
    WPL_COLUMNS,
    WPL_HEADER,
    At,
    FenceCircle,
    FencePolygon,
    FileContents,
    Item,
    command_name,
    describe_json,
    finite,
)
from executive.world.dialect import mavlink
from executive.world.vehicles import profile_for_mav_type

MAX_JSON_DEPTH = 64
_WPL_INTEGERS = {"index", "current", "frame", "command", "autocontinue"}


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
        self.src = FileContents(filename, At(1, 1, "(plan)"))
        self._offsets = _json_offsets(text)
        self._newlines = [m.start() for m in re.finditer("\n", text)]

    def at(self, path: Path) -> At:
        """The position of the value at ``path`` (or of its nearest enclosing value in the file)."""
        found = next((path[:n] for n in range(len(path), -1, -1) if path[:n] in self._offsets), ())
        offset = self._offsets.get(found, 0)
        line = bisect.bisect_left(self._newlines, offset)
        column = offset - (self._newlines[line - 1] if line else -1)
        return At(line + 1, column, format_path(path) if path else "(plan)")

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
        number = finite(value)
        if kind in ("number", "integer"):
            if number is not None and (kind == "number" or number.is_integer()):
                return number if kind == "number" else int(number)
        elif isinstance(value, {"object": dict, "array": list, "bool": bool, "string": str}[kind]):
            return value
        article = "an" if kind[0] in "aeiou" else "a"
        self.src.error(self.at(path), f"expected {article} {kind}{' or null' if nullable else ''}, got {describe_json(value)}")
        return None

    def read(self, data: Any) -> FileContents:
        src = self.src
        if not isinstance(data, dict):
            src.error(self.at(()), f"expected a JSON object (a QGroundControl plan), got {describe_json(data)}")
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
        for i, point in enumerate(points or []):
            path = ("rallyPoints", "points", i)
            if self.check(point, path, "array") is None:
                continue
            if len(point) != 3:  # QGroundControl writes [latitude, longitude, altitude] (RallyPointController::save)
                src.error(self.at(path), f"expected [latitude, longitude, altitude], got {len(point)} values")
                continue
            lat, lon, alt = (self.check(v, (*path, j), "number") for j, v in enumerate(point))
            if lat is not None and lon is not None and alt is not None:
                src.rally.append((lat, lon, alt, self.at(path)))
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
            Item(
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
            src.polygons.append(FencePolygon(inclusion is not False, corners, self.at((*path, "polygon"))))
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
            src.circles.append(FenceCircle(inclusion is not False, lat, lon, radius, self.at(path)))


def read_plan(text: str, filename: str) -> FileContents:
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


def read_waypoints(text: str, filename: str) -> FileContents:
    lines = text.splitlines()
    header = lines[0].strip() if lines else ""
    src = FileContents(filename, At(1, 1, "(header)"))
    src.items_at = src.start
    src.vehicle_at, src.vehicle_why = src.start, "a .waypoints file does not say which vehicle it is for: pass --vehicle"
    if header != WPL_HEADER:
        found = repr(header[:40]) if header else "an empty line"
        src.error(src.start, f"expected {WPL_HEADER!r} on the first line (a Mission Planner waypoint file), got {found}")
        return src
    number = 0
    zones: list[Item] = []
    for line_no, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        fields = [(m.start() + 1, m.group()) for m in re.finditer(r"\S+", line)]
        name = f"item[{number}]"
        if len(fields) != len(WPL_COLUMNS):
            column = fields[len(WPL_COLUMNS)][0] if len(fields) > len(WPL_COLUMNS) else len(line.rstrip()) + 1
            src.error(At(line_no, column, name), f"expected {len(WPL_COLUMNS)} tab-separated fields ({', '.join(WPL_COLUMNS)}), got {len(fields)}")
            number += 1
            continue
        before = len(src.errors)
        at = [At(line_no, column, f"{name}.{col}") for (column, _), col in zip(fields, WPL_COLUMNS, strict=True)]
        values = [_wpl_value(src, where, token) for where, (_, token) in zip(at, fields, strict=True)]
        number += 1
        if len(src.errors) > before:
            continue
        index, _, frame, command, *params, autocontinue = values
        lat, lon, alt = params[4:]
        zone_item = int(command) in ZONE_COMMANDS
        if number == 1 and not zone_item:  # line 0 is home; 0, 0 = not set (a fence or rally file may start with its first item)
            if (lat, lon) != (0.0, 0.0):
                src.home, src.home_at = (lat, lon, alt), At(line_no, at[8].column, name)
            continue
        if index != number - 1 and not (zone_item and index == number - 2):
            src.warn(at[0], f"index {index:g} out of sequence (expected {number - 1}): items are taken in file order")
        unset = tuple(None if math.isnan(p) else p for p in params)  # params 1-4 may be NaN
        item = Item(int(command), int(frame), unset, bool(autocontinue), At(line_no, 1, name), at[2], tuple(at[4:11]))
        if zone_item:
            zones.append(item)
        else:
            src.items.append(item)
    _zones(src, zones)
    return src


#: Mission Planner's Fence and Rally plans (and a route file) hold these; they become zones and rally points.
_POLYGON_VERTEX = {mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION: True, mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION: False}
_CIRCLE = {mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION: True, mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION: False}
ZONE_COMMANDS = frozenset({*_POLYGON_VERTEX, *_CIRCLE, mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT, mavlink.MAV_CMD_NAV_RALLY_POINT})


def _zones(src: FileContents, items: list[Item]) -> None:
    """Fence items as polygons (runs of param1 corners) and circles, rally points as rally points, each located."""
    run: list[Item] = []

    def close() -> None:
        if not run:
            return
        count = int(run[0].params[0] or 0)
        if count < 3 or len(run) != count:
            src.error(run[0].param_at[0], f"a fence polygon of {count} corners (param1) has {len(run)} vertex items here")
        else:
            corners = [(i.params[4] or 0.0, i.params[5] or 0.0, i.param_at[4]) for i in run]
            src.polygons.append(FencePolygon(_POLYGON_VERTEX[run[0].command], corners, run[0].at))
        run.clear()

    for item in items:
        if item.command in _POLYGON_VERTEX:
            if run and (item.command != run[0].command or item.params[0] != run[0].params[0] or len(run) == int(run[0].params[0] or 0)):
                close()
            run.append(item)
            continue
        close()
        lat, lon = item.params[4], item.params[5]
        if lat is None or lon is None:
            src.error(item.param_at[4], f"{command_name(item.command)} needs a latitude and a longitude")
        elif item.command in _CIRCLE:
            radius = item.params[0] or 0.0
            if radius <= 0:
                src.error(item.param_at[0], f"a fence circle needs a radius over 0 m (param1), got {radius:g}")
            else:
                src.circles.append(FenceCircle(_CIRCLE[item.command], lat, lon, radius, item.at))
        elif item.command == mavlink.MAV_CMD_NAV_RALLY_POINT:
            src.rally.append((lat, lon, item.params[6] or 0.0, item.at))
        else:
            src.warn(item.at, "the fence's return point is not imported: a return goes to a rally point or home")
    close()


def _wpl_value(src: FileContents, at: At, token: str) -> float:
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
