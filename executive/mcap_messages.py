"""The Foxglove channels of a run: their schemas, and the vehicle's values as the well-known Foxglove messages.

One set of channels for the MCAP file (:mod:`executive.mcap_recording`) and the live Foxglove
server (:mod:`executive.foxglove_live`). Every message is JSON with a JSON schema; the well-known
ones are Foxglove's (their JSON encoding, https://docs.foxglove.dev/docs/sdk/schemas), so a Map,
3D, Plot and Log panel need no set-up. Each MAVLink message kind received or sent has its own
channel (``/mavlink/in/VFR_HUD``, ``/mavlink/out/COMMAND_LONG``): its fields, with a schema made
from the message's definition, so a plot of any field is one click.
"""

from __future__ import annotations

import json
import logging
import math
from typing import Any

from executive import frames
from executive.mavlink_dialect import MAVLinkMessage

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


def pose(home: Any, fix: Any, attitude: Any | None, t: float) -> tuple[dict[str, Any], dict[str, Any]]:
    """The vehicle in the home frame (east, north, up in metres): as ``foxglove.PoseInFrame`` and as ``foxglove.FrameTransforms``."""
    north, east = frames.global_to_local(home.lat, home.lon, fix.lat, fix.lon)
    position = {"x": east, "y": north, "z": fix.alt_rel_m}
    rotation = orientation(attitude) if attitude is not None else {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
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


def mavlink_schema(msg: MAVLinkMessage) -> tuple[str, bytes]:
    """The schema of a MAVLink message kind's channel (``mavlink.VFR_HUD``): its fields from the message definition."""
    properties: dict[str, Any] = {}
    for name, kind, length in zip(msg.fieldnames, msg.fieldtypes, msg.array_lengths, strict=True):
        scalar = {"type": _MAVLINK_TYPES.get(kind, "integer")}
        properties[name] = {"type": "array", "items": scalar} if length and kind != "char" else scalar
    properties["sysid"] = properties["compid"] = {"type": "integer"}
    return f"mavlink.{msg.get_type()}", json.dumps({"type": "object", "properties": properties}).encode()


def mavlink_fields(msg: MAVLinkMessage) -> bytes:
    """A MAVLink message's fields (and who sent it) as JSON; NaN (PX4 sends it for 'unknown') as null, as JSON has no NaN."""
    fields = {name: getattr(msg, name) for name in msg.fieldnames}
    fields["sysid"], fields["compid"] = msg.get_srcSystem(), msg.get_srcComponent()
    try:
        return json.dumps(fields, separators=(",", ":"), allow_nan=False).encode()
    except (ValueError, TypeError):
        return json.dumps({k: _plain(v) for k, v in fields.items()}, separators=(",", ":")).encode()


def _plain(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, bytes | bytearray):
        return value.decode("latin-1")
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value
