"""The Foxglove channels of a run: their schemas, and the vehicle's values as the well-known Foxglove messages.

One set of channels for the MCAP file (:mod:`executive.observers.mcap.recording`) and the live Foxglove
server (:mod:`executive.observers.foxglove.live`). Every message is JSON with a JSON schema; the well-known
ones are Foxglove's (their JSON encoding, https://docs.foxglove.dev/docs/sdk/schemas), so a Map,
3D, Plot and Log panel need no set-up. Each MAVLink message kind received or sent has its own
channel (``/mavlink/in/VFR_HUD``, ``/mavlink/out/COMMAND_LONG``): its fields, with a schema made
from the message's definition, so a plot of any field is one click.
"""

from __future__ import annotations

import json
import logging
import math
import operator
from collections.abc import Callable
from typing import Any

from executive.world import frames
from executive.world.dialect import MAVLinkMessage

_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}
_BY_NODE = {"type": "object", "additionalProperties": {"type": "string"}, "description": "node id (pre-order) -> text"}
_VECTOR = {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}}
_QUATERNION = {"type": "object", "properties": {k: {"type": "number"} for k in "xyzw"}}
_POSE = {"type": "object", "properties": {"position": _VECTOR, "orientation": _QUATERNION}}
#: Our schemas, and the well-known Foxglove ones.
SCHEMAS: dict[str, dict[str, Any]] = {
    "executive.Tree": {
        "type": "object",
        "properties": {"nodes": {"type": "array", "items": {"type": "object", "properties": {
            "id": {"type": "integer"}, "name": {"type": "string"}, "type": {"type": "string"}, "parent": {"type": ["integer", "null"]}}}}},
    },
    "executive.TreeTick": {
        "type": "object",
        "properties": {"tick": {"type": "integer"}, "key": {"type": "boolean"}, "end": {"type": "boolean"}, "s": _BY_NODE, "f": _BY_NODE},
    },
    "executive.Blackboard": {
        "type": "object",
        "properties": {"tick": {"type": "integer"}, "key": {"type": "boolean"}, "bb": {"type": "object", "additionalProperties": {"type": "string"}}},
    },
    "executive.MissionState": {
        "type": "object",
        "properties": {"state": {"type": "string"}, "leg_index": {"type": "integer"}, "leg_count": {"type": "integer"}, "reason": {"type": "string"}},
    },
    "executive.Run": {
        "type": "object",
        "properties": {"mission": {"type": "string"}, "vehicle": {"type": "string"}, "resumed_from": {"type": ["integer", "null"]},
                       "started": {"type": "number", "description": "wall clock, s since 1970"},
                       "waypoints": {"type": "array", "items": {"type": "object", "properties": {
                           "lat": {"type": "number"}, "lon": {"type": "number"}, "name": {"type": ["string", "null"]}}}}},
    },
    "executive.MissionEvent": {
        "type": "object", "properties": {"before": {"type": "string"}, "after": {"type": "string"}, "reason": {"type": "string"}},
    },
    "foxglove.LocationFix": {
        "type": "object",
        "properties": {
            "timestamp": _TIME, "frame_id": {"type": "string"}, "latitude": {"type": "number"}, "longitude": {"type": "number"},
            "altitude": {"type": "number"}, "position_covariance": {"type": "array", "items": {"type": "number"}, "minItems": 9, "maxItems": 9},
            "position_covariance_type": {"type": "integer"},
        },
    },
    "foxglove.GeoJSON": {"type": "object", "properties": {"geojson": {"type": "string"}}},
    "foxglove.PoseInFrame": {"type": "object", "properties": {"timestamp": _TIME, "frame_id": {"type": "string"}, "pose": _POSE}},
    "foxglove.FrameTransforms": {
        "type": "object",
        "properties": {"transforms": {"type": "array", "items": {"type": "object", "properties": {
            "timestamp": _TIME, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
            "translation": _VECTOR, "rotation": _QUATERNION}}}},
    },
    "foxglove.Log": {
        "type": "object",
        "properties": {
            "timestamp": _TIME, "level": {"type": "integer"}, "message": {"type": "string"}, "name": {"type": "string"},
            "file": {"type": "string"}, "line": {"type": "integer"},
        },
    },
}  # fmt: skip
#: Topic -> schema name, for every channel but the MAVLink ones (one per message kind, made as they come).
CHANNELS = {
    "/tree": "executive.Tree",
    "/tree/tick": "executive.TreeTick",
    "/blackboard": "executive.Blackboard",
    "/mission/run": "executive.Run",
    "/mission/state": "executive.MissionState",
    "/mission/events": "executive.MissionEvent",
    "/mission/route": "foxglove.GeoJSON",
    "/vehicle/location": "foxglove.LocationFix",
    "/vehicle/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransforms",
    "/log": "foxglove.Log",
}
#: The frame the poses are in: east, north, up from the autopilot's home (HOME_POSITION), the one the mission returns to.
HOME_FRAME = "home"
VEHICLE_FRAME = "vehicle"
#: Python's levels as foxglove.Log's (DEBUG 1, INFO 2, WARNING 3, ERROR 4, FATAL 5).
LOG_LEVELS = {logging.DEBUG: 1, logging.INFO: 2, logging.WARNING: 3, logging.ERROR: 4, logging.CRITICAL: 5}


def ns(t: float) -> int:
    """Clock seconds as a log time, nanoseconds."""
    return max(0, round(t * 1e9))


def stamp(t: float) -> dict[str, int]:
    """Clock seconds as a Foxglove ``timestamp``."""
    whole = ns(t)
    return {"sec": whole // 1_000_000_000, "nsec": whole % 1_000_000_000}


def schema_bytes(name: str) -> bytes:
    return json.dumps(SCHEMAS[name]).encode()


def location_fix(fix: Any) -> dict[str, Any]:
    """A GlobalPosition as ``foxglove.LocationFix`` (altitude: above home, as the autopilot reports it)."""
    return {
        "timestamp": stamp(fix.time), "frame_id": "wgs84", "latitude": fix.lat, "longitude": fix.lon, "altitude": fix.alt_rel_m,
        "position_covariance": [0.0] * 9, "position_covariance_type": 0,
    }  # fmt: skip


def orientation(attitude: Any) -> dict[str, float]:
    """ATTITUDE (roll, pitch, yaw from north clockwise) as a quaternion of the body (forward, left, up) in east-north-up."""
    yaw = frames.yaw_ned_to_enu(math.radians(attitude.yaw_deg))
    pitch, roll = -math.radians(attitude.pitch_deg), math.radians(attitude.roll_deg)
    cy, sy, cp, sp, cr, sr = math.cos(yaw / 2), math.sin(yaw / 2), math.cos(pitch / 2), math.sin(pitch / 2), math.cos(roll / 2), math.sin(roll / 2)
    return {"x": sr * cp * cy - cr * sp * sy, "y": cr * sp * cy + sr * cp * sy, "z": cr * cp * sy - sr * sp * cy, "w": cr * cp * cy + sr * sp * sy}


_A, _E2 = 6378137.0, 6.69437999014e-3  # WGS84


def east_north(home: Any, fix: Any) -> tuple[float, float]:
    """Metres east and north of home on the plane tangent there (WGS84's radii at home: within a centimetre over a few km).

    A geodesic (:func:`executive.world.frames.global_to_local`) costs ~20 µs; this runs at every fix.
    """
    lat0 = math.radians(home.lat)
    w = 1.0 - _E2 * math.sin(lat0) ** 2
    meridian, normal = _A * (1.0 - _E2) / w**1.5, _A / math.sqrt(w)
    return math.radians(fix.lon - home.lon) * normal * math.cos(lat0), math.radians(fix.lat - home.lat) * meridian


def pose(home: Any, fix: Any, attitude: Any | None, t: float) -> tuple[dict[str, Any], dict[str, Any]]:
    """The vehicle in the home frame (east, north, up in metres): as ``foxglove.PoseInFrame`` and as ``foxglove.FrameTransforms``."""
    east, north = east_north(home, fix)
    position = {"x": round(east, 3), "y": round(north, 3), "z": round(fix.alt_rel_m, 3)}  # mm: a short text, quick to write
    rotation = {k: round(v, 6) for k, v in orientation(attitude).items()} if attitude is not None else {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
    when = stamp(t)
    transform = {"timestamp": when, "parent_frame_id": HOME_FRAME, "child_frame_id": VEHICLE_FRAME, "translation": position, "rotation": rotation}
    return {"timestamp": when, "frame_id": HOME_FRAME, "pose": {"position": position, "orientation": rotation}}, {"transforms": [transform]}


def route_geojson(waypoints: list[tuple[float, float]]) -> dict[str, str]:
    """The route as ``foxglove.GeoJSON``: a line through the waypoints, and each waypoint a point named by its number."""
    line = [[lon, lat] for lat, lon in waypoints]  # GeoJSON: longitude first
    points = [
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": p}, "properties": {"name": f"waypoint {i}"}} for i, p in enumerate(line, 1)
    ]
    route = {"type": "Feature", "geometry": {"type": "LineString", "coordinates": line}, "properties": {"name": "route"}}
    return {"geojson": json.dumps({"type": "FeatureCollection", "features": [route, *points]})}


def log_line(record: logging.LogRecord, t: float) -> dict[str, Any]:
    """A log record as ``foxglove.Log``."""
    level = LOG_LEVELS.get(record.levelno, 3 if record.levelno < logging.ERROR else 4)
    return {
        "timestamp": stamp(t),
        "level": level,
        "message": record.getMessage(),
        "name": record.name,
        "file": record.pathname,
        "line": record.lineno,
    }


_MAVLINK_TYPES = {"float": "number", "double": "number", "char": "string"}
_STRICT_JSON = json.JSONEncoder(separators=(",", ":"), allow_nan=False).encode


def mavlink_schema(msg: MAVLinkMessage) -> tuple[str, bytes]:
    """The schema of a MAVLink message kind's channel (``mavlink.VFR_HUD``): its fields from the message definition."""
    properties: dict[str, Any] = {}
    for name, kind, length in _definition(msg):
        scalar = {"type": _MAVLINK_TYPES.get(kind, "integer")}
        properties[name] = {"type": "array", "items": scalar} if length and kind != "char" else scalar
    properties["sysid"] = properties["compid"] = {"type": "integer"}
    return f"mavlink.{msg.get_type()}", json.dumps({"type": "object", "properties": properties}).encode()


class MavlinkJson:
    """MAVLink messages' fields (and who sent them) as JSON, by a template made once per kind.

    ``json.dumps`` writes a float32 field's shortest repr (17 digits): ~3 µs a field, 40 µs an
    ATTITUDE. Nine significant digits give the same float32 back, and a ``%`` template skips the
    encoder. A kind with arrays or text, or a value JSON cannot hold (NaN, PX4's 'unknown'), takes ``json.dumps``.
    """

    def __init__(self) -> None:
        self._kinds: dict[str, _KindEncoder] = {}

    def encode(self, msg: MAVLinkMessage, source: tuple[int, int] | None = None) -> bytes:
        """``msg`` as JSON; ``source``: its sysid and compid as they were when it was heard (default: as the message holds them now)."""
        kind = msg.get_type()
        encoder = self._kinds.get(kind)
        if encoder is None:
            encoder = self._kinds[kind] = _KindEncoder(msg)
        return encoder.encode(msg, source or (msg.get_srcSystem(), msg.get_srcComponent()))


class _KindEncoder:
    """One kind's template, and getters of its fields (all of them; its floats, checked finite) made once."""

    def __init__(self, msg: MAVLinkMessage) -> None:
        self.fieldnames = list(msg.fieldnames)
        self.template = _template(msg)
        self._values = _getter(self.fieldnames)
        self._floats = _getter([name for name, kind, _ in _definition(msg) if kind in ("float", "double")])

    def encode(self, msg: MAVLinkMessage, source: tuple[int, int]) -> bytes:
        if self.template is not None:
            text, arrays = self.template
            floats = self._floats(msg)
            if all(map(math.isfinite, floats)):
                values = self._values(msg)
                if arrays:
                    values = list(values)
                    for i in arrays:
                        values[i] = list(values[i])  # pymavlink may hold an array as a tuple: "(0, 0)" is no JSON
                return (text % (*values, *source)).encode()
        fields = dict(zip(self.fieldnames, self._values(msg), strict=True))
        fields["sysid"], fields["compid"] = source
        try:
            return _STRICT_JSON(fields).encode()
        except (ValueError, TypeError):
            return _STRICT_JSON({k: _plain(v) for k, v in fields.items()}).encode()


def _getter(names: list[str]) -> Callable[[Any], tuple[Any, ...]]:
    """The values of ``names`` as a tuple (``attrgetter`` gives a lone value bare)."""
    if len(names) == 1:
        one = operator.attrgetter(names[0])
        return lambda msg: (one(msg),)
    return operator.attrgetter(*names) if names else lambda msg: ()


def _template(msg: MAVLinkMessage) -> tuple[str, tuple[int, ...]] | None:
    """``{"field":%d,...}`` and where its arrays are, for a kind of numbers and arrays of integers (None: text or arrays of floats)."""
    parts, arrays = [], []
    for i, (name, kind, length) in enumerate(_definition(msg)):
        if kind == "char" or (length and kind in ("float", "double")):
            return None
        if length:
            arrays.append(i)
        parts.append(f'"{name}":' + ("%s" if length else "%.9g" if kind == "float" else "%r" if kind == "double" else "%d"))
    return "{" + ",".join([*parts, '"sysid":%d', '"compid":%d']) + "}", tuple(arrays)


def _definition(msg: MAVLinkMessage) -> list[tuple[str, str, int]]:
    """Each field's name, type and array length (0: not an array), in the order of ``fieldnames``.

    pymavlink keeps ``fieldtypes`` in that order but ``array_lengths`` in the wire's (``ordered_fieldnames``).
    """
    lengths = dict(zip(msg.ordered_fieldnames, msg.array_lengths, strict=True))
    return [(name, kind, lengths[name]) for name, kind in zip(msg.fieldnames, msg.fieldtypes, strict=True)]


def _plain(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, bytes | bytearray):
        return value.decode("latin-1")
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value
