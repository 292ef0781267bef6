"""A ground-station mission file as read, before it becomes a mission: its items, home, fence and vehicle, each located in the file.

The MAVLink numbers both formats use (commands, frames) and the names they are said by in messages.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from typing import Any

import executive
from executive.mission.errors import FieldError
from executive.world.dialect import mavlink

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


@dataclass(frozen=True)
class At:
    """Where something is in the source file (1-based line and column) and what it is called there."""

    line: int
    column: int
    field: str
    filename: str | None = None  # another file than the import's (a fence or rally file imported with it)


@dataclass(frozen=True)
class Item:
    """One mission item as either format has it."""

    command: int
    frame: int
    params: tuple[float | None, ...]  # param1-4, x (lat), y (lon), z (alt); None = unset (NaN, null)
    autocontinue: bool
    at: At
    frame_at: At
    param_at: tuple[At, ...]
    group: str | None = None  # the complex item it was generated for, if any


@dataclass(frozen=True)
class FencePolygon:
    """A geoFence polygon: inclusion or exclusion, its corners (lat, lon, where) and where its corner list is."""

    inclusion: bool
    corners: list[tuple[float, float, At]]
    at: At


@dataclass(frozen=True)
class FenceCircle:
    """A geoFence circle: inclusion or exclusion, centre, radius, where."""

    inclusion: bool
    lat: float
    lon: float
    radius_m: float
    at: At


@dataclass
class FileContents:
    """What a file says, before it becomes a mission."""

    filename: str
    start: At  # the whole file (the header line for WPL)
    items: list[Item] = field(default_factory=list)
    items_at: At | None = None
    home: tuple[float, float, float | None] | None = None  # lat, lon, altitude above mean sea level
    home_at: At | None = None
    polygons: list[FencePolygon] = field(default_factory=list)
    circles: list[FenceCircle] = field(default_factory=list)
    rally: list[tuple[float, float, float, At]] = field(default_factory=list)  # lat, lon, altitude (QGroundControl: above home)
    vehicle: str | None = None
    vehicle_at: At | None = None
    vehicle_why: str = ""  # why no vehicle kind could be inferred
    errors: list[FieldError] = field(default_factory=list)
    warnings: list[FieldError] = field(default_factory=list)

    def error(self, at: At, message: str) -> None:
        self.errors.append(FieldError(at.filename or self.filename, at.line, at.column, at.field, message))

    def warn(self, at: At, message: str) -> None:
        self.warnings.append(FieldError(at.filename or self.filename, at.line, at.column, at.field, message))

    def merge(self, other: FileContents) -> None:
        """Take ``other``'s zones, rally points and problems (a fence or rally file imported with this one), located in its file."""

        def there(at: At) -> At:
            return replace(at, filename=at.filename or other.filename)

        self.polygons += [FencePolygon(p.inclusion, [(a, b, there(at)) for a, b, at in p.corners], there(p.at)) for p in other.polygons]
        self.circles += [replace(c, at=there(c.at)) for c in other.circles]
        self.rally += [(lat, lon, alt, there(at)) for lat, lon, alt, at in other.rally]
        self.errors += other.errors
        self.warnings += other.warnings


def command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return f"{entry.name.removeprefix('MAV_CMD_')} ({command})" if entry else f"command {command}"


def frame_name(frame: int) -> str:
    entry = mavlink.enums["MAV_FRAME"].get(frame)
    return f"{entry.name.removeprefix('MAV_FRAME_')} ({frame})" if entry else f"frame {frame}"


def finite(value: Any) -> float | None:
    """A JSON number as a finite float; None for anything else (bool, NaN, Infinity, an integer too big for a float)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def describe_json(value: Any) -> str:
    """A JSON value, as found: ``string "47.3"``, ``null``, ``an object``."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"bool {str(value).lower()}"
    if isinstance(value, dict | list):
        return "an object" if isinstance(value, dict) else "an array"
    if isinstance(value, int) and finite(value) is None:
        return "an integer too big for a number"
    text = json.dumps(value) if isinstance(value, str) else repr(value)
    kind = "string" if isinstance(value, str) else "number"
    return f"{kind} {text if len(text) <= 40 else text[:37] + '...'}"


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Source is FileContents
    return executive.moved_attribute(__name__, name)
