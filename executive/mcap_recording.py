"""The snapshot recorder's MCAP back end (``run --snapshots FILE.mcap``): a run as Foxglove and the MCAP tools read it.

MCAP is the container Foxglove, PlotJuggler and rosbag2 share: chunked (zstd), indexed for seeking.
It is written with the ``mcap`` library (pure Python, what Foxglove's SDK writes on top of), every
message JSON with a JSON schema, timed in vehicle time (the injected clock, nanoseconds), so a run
recorded at ``--speedup 20`` draws true speeds. The channels:

- ``/tree`` (``executive.Tree``): the tree's nodes in pre-order (id, name, type, parent id), when a
  run's tree starts (and again at the top of each rotated file);
- ``/tree/tick`` (``executive.TreeTick``): every tick: ``tick``, ``key`` (a keyframe: everything),
  ``end`` (the run's end), ``s`` (node id -> status S/F/R/-, changed ones) and ``f`` (node id ->
  feedback, changed ones), as the JSON-lines snapshot file holds them;
- ``/blackboard`` (``executive.Blackboard``): ``tick``, ``key``, ``bb`` (key -> value as short text), the changed keys;
- ``/mission/state`` (``executive.MissionState``): state, leg_index, leg_count, reason, when one changes;
- ``/mission/events`` (``executive.MissionEvent``): each mission transition: before, after, reason;
- ``/mission/route`` (``foxglove.GeoJSON``): the route each run starts on, a line through its waypoints (edits are not);
- ``/vehicle/location`` (``foxglove.LocationFix``): each new GLOBAL_POSITION_INT, for the Map panel;
- ``/log`` (``foxglove.Log``): the executive's log lines (what its logger lets through), for the Log panel.

Past ``max_bytes`` the file is finished (its index written) and rotated to ``FILE.1`` (the one
before is dropped), as the JSON-lines file is. A finished file's metadata ``executive.keyframes``
lists each keyframe (tick, its time, its tree's time): a replay of tick N seeks to the keyframe
before it through the MCAP index, whatever the file's length.
"""

from __future__ import annotations

import collections
import json
import logging
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType, Writer

from executive import blackboard
from executive.clock import Clock
from executive.io.storage import AppendFile, Storage

#: Small enough that a crash loses little (a chunk is written whole, when full), large enough that zstd compresses well.
CHUNK_BYTES = 256 << 10
MISSION_KEYS = ("/mission/state", "/mission/leg_index", "/mission/leg_count", "/mission/reason")

_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}
_BY_NODE = {"type": "object", "additionalProperties": {"type": "string"}, "description": "node id (pre-order) -> text"}
#: Our schemas, and the two well-known Foxglove ones (their JSON encoding, https://docs.foxglove.dev/docs/sdk/schemas).
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
    "foxglove.Log": {
        "type": "object",
        "properties": {
            "timestamp": _TIME, "level": {"type": "integer"}, "message": {"type": "string"}, "name": {"type": "string"},
            "file": {"type": "string"}, "line": {"type": "integer"},
        },
    },
}  # fmt: skip
CHANNELS = {
    "/tree": "executive.Tree",
    "/tree/tick": "executive.TreeTick",
    "/blackboard": "executive.Blackboard",
    "/mission/state": "executive.MissionState",
    "/mission/events": "executive.MissionEvent",
    "/mission/route": "foxglove.GeoJSON",
    "/vehicle/location": "foxglove.LocationFix",
    "/log": "foxglove.Log",
}
#: Python's levels as foxglove.Log's (DEBUG 1, INFO 2, WARNING 3, ERROR 4, FATAL 5).
LOG_LEVELS = {logging.DEBUG: 1, logging.INFO: 2, logging.WARNING: 3, logging.ERROR: 4, logging.CRITICAL: 5}


def _ns(t: float) -> int:
    return max(0, round(t * 1e9))


def _stamp(t: float) -> dict[str, int]:
    ns = _ns(t)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


class _Stream:
    """The writer's output: whole writes through :class:`AppendFile` (a full disk is said once, as for the other recordings)."""

    def __init__(self, file: AppendFile) -> None:
        self._file = file
        self._at = 0

    def write(self, data: bytes) -> int:
        self._file.write(bytes(data))  # a chunk the disk refused is lost; the index still counts it (say so in the README)
        self._at += len(data)
        return len(data)

    def tell(self) -> int:
        return self._at

    def flush(self) -> None:
        pass


class _LogLines(logging.Handler):
    """Keeps the executive's log lines, in vehicle time, until the tick writes them (log calls may come from any thread)."""

    def __init__(self, clock: Clock | None) -> None:
        super().__init__(logging.DEBUG)
        self._clock = clock
        self.lines: collections.deque[tuple[float | None, logging.LogRecord]] = collections.deque(maxlen=1000)

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append((self._clock.now() if self._clock else None, record))


class McapFile:
    """A snapshot recording as one MCAP file (see the module's doc for its channels)."""

    def __init__(
        self, path: Path, max_bytes: int, storage: Storage | None, clock: Clock | None, values: Callable[[str], Any] = blackboard.value
    ) -> None:
        """``values``: where the vehicle and the mission are read after each tick (the blackboard; a recorded one for ``convert``)."""
        self.path, self.max_bytes, self.storage, self._clock, self._value = path, max_bytes, storage, clock, values
        self._nodes: list[dict[str, Any]] = []
        self._t = 0.0  # vehicle time of the last tick: what a line without a clock is timed by
        self._mission: tuple[Any, ...] | None = None
        self._fix_time: float | None = None
        self._logs = _LogLines(clock)
        self._tree_ns = 0
        self._start()
        logging.getLogger("executive").addHandler(self._logs)

    def write_tree(self, nodes: list[dict[str, Any]]) -> None:
        self._nodes = nodes
        self._tree_ns = self._put("/tree", self._now(), {"nodes": nodes})

    def write_tick(self, line: dict[str, Any]) -> bool:
        t = self._t = line["t"]
        self._write_logs()
        marks = {k: line[k] for k in ("key", "end") if k in line}
        ns = self._put("/tree/tick", t, {"tick": line["tick"], **marks, **{k: line[k] for k in ("s", "f") if k in line}})
        if line.get("key"):
            self._keyframes.append((line["tick"], ns, self._tree_ns))
        if "bb" in line:
            self._put("/blackboard", t, {"tick": line["tick"], **marks, "bb": line["bb"]})
        mission = tuple(self._value(k) for k in MISSION_KEYS)
        if mission != self._mission:
            self._mission = mission
            self._put("/mission/state", t, dict(zip(("state", "leg_index", "leg_count", "reason"), mission, strict=True)))
        self._write_fix()
        if self._stream.tell() > self.max_bytes:
            self._rotate()
            return False
        return True

    def write_event(self, before: str, after: str, reason: str) -> None:
        self._put("/mission/events", self._now(), {"before": before, "after": after, "reason": reason})

    def write_route(self, waypoints: list[tuple[float, float]]) -> None:
        line = [[lon, lat] for lat, lon in waypoints]  # GeoJSON: longitude first
        points = [
            {"type": "Feature", "geometry": {"type": "Point", "coordinates": p}, "properties": {"name": f"waypoint {i}"}}
            for i, p in enumerate(line, 1)
        ]
        route = {"type": "Feature", "geometry": {"type": "LineString", "coordinates": line}, "properties": {"name": "route"}}
        self._put("/mission/route", self._now(), {"geojson": json.dumps({"type": "FeatureCollection", "features": [route, *points]})})

    def close(self) -> None:
        logging.getLogger("executive").removeHandler(self._logs)
        self._write_logs()
        self._finish()

    def _start(self) -> None:
        self._file = AppendFile(self.path, "snapshots", "ticks are not recorded for replay", self.storage, append=False)
        self._stream = _Stream(self._file)
        self._writer = Writer(self._stream, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library="executive")
        schemas = {name: self._writer.register_schema(name, "jsonschema", json.dumps(body).encode()) for name, body in SCHEMAS.items()}
        self._channels = {topic: self._writer.register_channel(topic, "json", schemas[name]) for topic, name in CHANNELS.items()}
        self._sequence = 0
        self._keyframes: list[tuple[int, int, int]] = []

    def _finish(self) -> None:
        self._writer.add_metadata("executive.keyframes", {"ticks": json.dumps(self._keyframes, separators=(",", ":"))})
        self._writer.finish()
        self._file.close()

    def _rotate(self) -> None:
        self._finish()
        os.replace(self.path, self.path.with_name(self.path.name + ".1"))
        self._start()
        self._mission = None
        if self._nodes:
            self._tree_ns = self._put("/tree", self._t, {"nodes": self._nodes})

    def _now(self) -> float:
        return self._clock.now() if self._clock else self._t

    def _put(self, topic: str, t: float, message: dict[str, Any]) -> int:
        """Write ``message`` at time ``t``; its log time, ns."""
        self._sequence += 1
        ns = _ns(t)
        data = json.dumps(message, ensure_ascii=False, separators=(",", ":")).encode()
        self._writer.add_message(self._channels[topic], log_time=ns, data=data, publish_time=ns, sequence=self._sequence)
        return ns

    def _write_fix(self) -> None:
        fix = self._value("/vehicle/position")
        if fix is None or fix.time == self._fix_time:
            return
        self._fix_time = fix.time
        message = {
            "timestamp": _stamp(fix.time), "frame_id": "wgs84", "latitude": fix.lat, "longitude": fix.lon, "altitude": fix.alt_rel_m,
            "position_covariance": [0.0] * 9, "position_covariance_type": 0,
        }  # fmt: skip
        self._put("/vehicle/location", fix.time, message)

    def _write_logs(self) -> None:
        while self._logs.lines:
            t, record = self._logs.lines.popleft()
            t = self._t if t is None else t
            level = LOG_LEVELS.get(record.levelno, 3 if record.levelno < logging.ERROR else 4)
            message = {"timestamp": _stamp(t), "level": level, "message": record.getMessage(), "name": record.name,
                       "file": record.pathname, "line": record.lineno}  # fmt: skip
            self._put("/log", t, message)
