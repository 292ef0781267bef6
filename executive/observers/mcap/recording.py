"""The snapshot recorder's Foxglove back end: a run as MCAP (``run --snapshots FILE.mcap``) and live (``run --foxglove PORT``).

:class:`ChannelFeed` turns each tick (and what happened between two) into messages on the channels
of :mod:`executive.observers.mcap.messages`, timed in vehicle time (the injected clock, nanoseconds), so a run
recorded at ``--speedup 20`` draws true speeds; its sinks take them: :class:`McapSink` (a file,
through the ``mcap`` library: pure Python, chunked, compressed, indexed) and the live server. The
channels:

- ``/tree`` (``executive.Tree``): the tree's nodes in pre-order (id, name, type, parent id), when a
  run's tree starts (and again at the top of each rotated file);
- ``/tree/tick`` (``executive.TreeTick``): every tick: ``tick``, ``key`` (a keyframe: everything),
  ``end`` (the run's end), ``s`` (node id -> status S/F/R/-, changed ones) and ``f`` (node id ->
  feedback, changed ones), as the JSON-lines snapshot file holds them;
- ``/blackboard`` (``executive.Blackboard``): ``tick``, ``key``, ``bb`` (key -> value as short text), the changed keys;
- ``/mission/run`` (``executive.Run``): each run's mission, vehicle, run it resumes, wall-clock start, waypoints (lat, lon, name);
- ``/mission/state`` (``executive.MissionState``): state, leg_index, leg_count, reason, when one changes;
- ``/mission/events`` (``executive.MissionEvent``): each mission transition: before, after, reason;
- ``/mission/route`` (``foxglove.GeoJSON``): the route each run starts on, a line through its waypoints (edits are not);
- ``/vehicle/location`` (``foxglove.LocationFix``): each new GLOBAL_POSITION_INT: the Map panel draws the track from them;
- ``/vehicle/pose`` (``foxglove.PoseInFrame``) and ``/tf`` (``foxglove.FrameTransforms``, home -> vehicle): attitude and
  position in the frame ``home`` (east, north, up from HOME_POSITION), at each new fix or attitude once home is known;
- ``/mavlink/in/KIND``, ``/mavlink/out/KIND``: every MAVLink message the autopilot link received (of the kinds the
  reader decodes) and sent, its fields as JSON;
- ``/log`` (``foxglove.Log``): the executive's log lines (what its logger lets through), for the Log panel.

The tick only queues what it saw (its line as the snapshot recorder built it, the mission's changes, the log lines) and
notes the vehicle's frozen values; an encoder thread woken every :data:`ENCODE_EVERY` ticks encodes and writes them all,
in order, with the MAVLink messages (as heard, with their source ids as heard) and the vehicle's fixes and poses, so
they reach a file or a live client up to that many ticks late, each at its own time. What is written in a round is cut at
the tick that woke it, not at the moment the thread runs: the same run makes the same file byte for byte (a lock-step
run's, with the same wall-clock start: ``SnapshotRecorder(wall=...)``). When a file is rotated the thread writes the
next tick line as a keyframe (the tree and blackboard so far): each file is readable alone.

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
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

from executive.io.storage import AppendFile, Storage
from executive.observers.mcap.messages import CHANNELS, MavlinkJson, location_fix, log_line, mavlink_schema, ns, pose, route_geojson, schema_bytes
from executive.observers.mcap.writer import ChunkedWriter
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage

#: Small enough that a crash loses little (a chunk is written whole, when full), large enough that zstd compresses well.
CHUNK_BYTES = 256 << 10
#: Ticks between two rounds of the encoder thread: a round's cost is mostly waking the thread and taking the lock.
ENCODE_EVERY = 10
MISSION_KEYS = ("/mission/state", "/mission/leg_index", "/mission/leg_count", "/mission/reason")
#: What a file (or a client joining late) needs whatever the time: written again at the top of each rotated file.
LATCHED = frozenset(("/tree", "/mission/run", "/mission/route", "/mission/state"))
_DUMPS = json.JSONEncoder(ensure_ascii=False, separators=(",", ":")).encode


class Sink(Protocol):
    """Where a :class:`ChannelFeed`'s messages go."""

    def put(self, topic: str, schema: tuple[str, bytes], log_ns: int, data: bytes) -> None:
        """One message on ``topic`` (its channel made on the first, with ``schema``: its name and JSON schema)."""

    def keyframe(self, tick: int, log_ns: int) -> None:
        """The message at ``log_ns`` was a keyframe of tick ``tick``."""

    def ticked(self) -> bool:
        """The messages so far are in and a tick line comes next; False when a new file began (that line must be a keyframe)."""

    def close(self) -> None: ...


class _LogLines(logging.Handler):
    """Keeps the executive's log lines, in vehicle time, until the tick writes them (log calls may come from any thread)."""

    def __init__(self, clock: Clock | None) -> None:
        super().__init__(logging.DEBUG)
        self._clock = clock
        self.lines: collections.deque[tuple[float | None, logging.LogRecord]] = collections.deque(maxlen=1000)

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append((self._clock.now() if self._clock else None, record))


class _Batch:
    """What the ticks between two rounds of the encoder thread queued: written whole, in this order, whenever the thread runs."""

    __slots__ = ("lines", "mavlink", "vehicle")

    def __init__(self) -> None:
        #: The tick lines and the channels written in order with them (topic, t, message).
        self.lines: collections.deque[dict[str, Any] | tuple[str, float, dict[str, Any]]] = collections.deque()
        self.mavlink: collections.deque[tuple[float, str, MAVLinkMessage, tuple[int, int]]] = collections.deque(maxlen=10_000)
        self.vehicle: collections.deque[tuple[float, Any, Any, Any, bool]] = collections.deque()  # t, fix, home, attitude, new fix


class ChannelFeed:
    """A snapshot recorder's :class:`~executive.observers.snapshots.TickFile` as Foxglove channels, into ``sinks``.

    ``values``: where the vehicle and the mission are read after each tick (the blackboard; a recorded one for ``convert``).
    """

    def __init__(
        self, sinks: Sequence[Sink], clock: Clock | None, values: Callable[[str], Any] = blackboard.value, storage: Storage | None = None
    ) -> None:
        """``storage``: where the sinks' disk losses are said; the encoder thread's are told at the next tick (Storage.deliver)."""
        self.sinks, self._clock, self._value, self._storage = list(sinks), clock, values, storage
        self._t = 0.0  # vehicle time of the last tick: what a line without a clock is timed by
        self._mission: tuple[Any, ...] | None = None
        self._fix_time: float | None = None
        self._pose_times: tuple[float | None, float | None] = (None, None)
        self._logs = _LogLines(clock)
        self._mavlink_schemas: dict[str, tuple[str, bytes]] = {}
        self._mavlink_channels: dict[tuple[str, str], tuple[str, tuple[str, bytes]]] = {}  # topic, schema
        self._mavlink_json = MavlinkJson()
        self._schemas = {topic: (name, schema_bytes(name)) for topic, name in CHANNELS.items()}
        #: What the ticks since the last round queued, and the rounds' batches the encoder thread has yet to write. A batch is cut
        #: at a tick, not when the thread happens to run, so the file's bytes are the same however late the thread is.
        self._batch = _Batch()
        self._ready: collections.deque[_Batch] = collections.deque()
        self._state: dict[str, dict[Any, Any]] = {"s": {}, "f": {}, "bb": {}}  # the tree and blackboard so far: a keyframe's
        self._new_file = False  # a sink began a new file: the next tick line is written as a keyframe
        self._sinks_lock = threading.Lock()  # the sinks are written by the encoder thread, and by close after it
        self._work = threading.Event()
        self._closing = False
        #: CPU the encoder thread has spent (ns): the benchmark adds it to the tick's recording cost.
        self.encoder_ns = 0
        self._encoder = threading.Thread(target=self._encode_forever, name="mcap-encoder", daemon=True)
        self._encoder.start()
        logging.getLogger("executive").addHandler(self._logs)

    def write_tree(self, nodes: list[dict[str, Any]]) -> None:
        self._put("/tree", self._now(), {"nodes": nodes})

    def write_tick(self, line: dict[str, Any]) -> bool:
        t = self._t = line["t"]
        if self._storage is not None:
            self._storage.deliver()
        self._write_logs()
        batch = self._batch
        batch.lines.append(line)  # the tick's /tree/tick and /blackboard: built from the line by the encoder thread
        mission = tuple(self._value(k) for k in MISSION_KEYS)
        if mission != self._mission:
            self._mission = mission
            batch.lines.append(("/mission/state", t, dict(zip(("state", "leg_index", "leg_count", "reason"), mission, strict=True))))
        self._note_vehicle(t)
        if line["tick"] % ENCODE_EVERY == 0:
            self._ready.append(batch)
            self._batch = _Batch()
            self._work.set()  # the tick's channels, the MAVLink messages and the vehicle's: encoded and written by the encoder thread
        return True  # a new file begins with a keyframe made by the encoder thread (:meth:`_write_line`)

    def write_event(self, before: str, after: str, reason: str) -> None:
        self._put("/mission/events", self._now(), {"before": before, "after": after, "reason": reason})

    def write_run(self, run: dict[str, Any]) -> None:
        t = self._now()
        self._put("/mission/run", t, run)
        self._put("/mission/route", t, route_geojson([(w["lat"], w["lon"]) for w in run["waypoints"]]))

    def mavlink(self, direction: str, msg: MAVLinkMessage) -> None:
        """A MAVLink message received (``in``) or sent (``out``) on the autopilot's link: kept until the tick writes it."""
        # its source now: a message we send gets its header when packed, after this (the encoder thread may run later)
        self._batch.mavlink.append((self._now(), direction, msg, (msg.get_srcSystem(), msg.get_srcComponent())))

    def close(self) -> None:
        logging.getLogger("executive").removeHandler(self._logs)
        self._closing = True
        self._work.set()
        self._encoder.join()
        self._write_logs()
        self._ready.append(self._batch)
        self._batch = _Batch()
        start = time.thread_time_ns()
        self._encode()  # what came after the thread's last round
        self.encoder_ns += time.thread_time_ns() - start
        for sink in self.sinks:
            sink.close()

    def _now(self) -> float:
        return self._clock.now() if self._clock else self._t

    def _put(self, topic: str, t: float, message: dict[str, Any]) -> None:
        """``message`` on ``topic`` at time ``t``: written by the encoder thread, in order with the tick lines."""
        self._batch.lines.append((topic, t, message))

    def _write(self, topic: str, t: float, message: dict[str, Any]) -> int:
        """Write ``message`` at time ``t`` to every sink; its log time, ns."""
        log_ns, data = ns(t), _DUMPS(message).encode()
        with self._sinks_lock:
            for sink in self.sinks:
                sink.put(topic, self._schemas[topic], log_ns, data)
        return log_ns

    def _write_line(self, line: dict[str, Any]) -> None:
        """A tick line as /tree/tick and /blackboard; the first after a new file began made a keyframe (the state so far)."""
        with self._sinks_lock:  # a full file is rotated as the next tick comes, not after the last: a run never ends on a file without one
            self._new_file = not all([sink.ticked() for sink in self.sinks])  # every sink told, whichever began a new file
        state = self._state
        if line.get("key"):
            self._state = state = {"s": dict(line.get("s", {})), "f": dict(line.get("f", {})), "bb": dict(line.get("bb", {}))}
        else:
            for part in ("s", "f", "bb"):
                if part in line:
                    state[part].update(line[part])
            if self._new_file:
                line = {**line, "key": True, **{part: dict(values) for part, values in state.items()}}
        self._new_file = False
        t, marks = line["t"], {k: line[k] for k in ("key", "end") if k in line}
        log_ns = self._write("/tree/tick", t, {"tick": line["tick"], **marks, **{k: line[k] for k in ("s", "f") if k in line}})
        with self._sinks_lock:
            if line.get("key"):
                for sink in self.sinks:
                    sink.keyframe(line["tick"], log_ns)
        if "bb" in line:
            self._write("/blackboard", t, {"tick": line["tick"], **marks, "bb": line["bb"]})

    def _note_vehicle(self, t: float) -> None:
        """The vehicle's values after the tick, when a fix or the attitude is new (frozen values: the encoder reads them later)."""
        fix = self._value("/vehicle/position")
        if fix is None:
            return
        new_fix = fix.time != self._fix_time
        self._fix_time = fix.time
        home, attitude = self._value("/vehicle/home"), self._value("/vehicle/attitude")
        times = (fix.time, attitude.time if attitude is not None else None)
        new_pose = home is not None and times != self._pose_times
        if new_pose:
            self._pose_times = times
        if new_fix or new_pose:
            self._batch.vehicle.append((t, fix, home if new_pose else None, attitude, new_fix))

    def _encode_forever(self) -> None:
        """The encoder thread: each tick's MAVLink messages and vehicle channels, off the tick (its CPU in ``encoder_ns``)."""
        while not self._closing:
            self._work.wait()
            self._work.clear()
            start = time.thread_time_ns()
            self._encode()
            self.encoder_ns += time.thread_time_ns() - start

    def _encode(self) -> None:
        """Every batch ready, oldest first: its lines, then its MAVLink messages, then the vehicle's channels."""
        while self._ready:
            batch = self._ready.popleft()
            for item in batch.lines:
                if isinstance(item, dict):
                    self._write_line(item)
                else:
                    self._write(*item)
            self._write_mavlink(batch.mavlink)
            self._write_vehicle(batch.vehicle)

    def _write_vehicle(self, vehicle: collections.deque[tuple[float, Any, Any, Any, bool]]) -> None:
        while vehicle:
            t, fix, home, attitude, new_fix = vehicle.popleft()
            if new_fix:
                self._write("/vehicle/location", fix.time, location_fix(fix))
            if home is not None:
                in_frame, transforms = pose(home, fix, attitude, t)
                self._write("/vehicle/pose", t, in_frame)
                self._write("/tf", t, transforms)

    def _write_mavlink(self, mavlink: collections.deque[tuple[float, str, MAVLinkMessage, tuple[int, int]]]) -> None:
        channels, sinks, encode = self._mavlink_channels, self.sinks, self._mavlink_json.encode
        while mavlink:
            t, direction, msg, source = mavlink.popleft()
            if not msg.fieldnames:
                continue  # a kind the reader skims (header only, never decoded): the tlog has its bytes
            kind = msg.get_type()
            channel = channels.get((direction, kind))
            if channel is None:
                schema = self._mavlink_schemas.get(kind)
                if schema is None:
                    schema = self._mavlink_schemas[kind] = mavlink_schema(msg)
                channel = channels[direction, kind] = (f"/mavlink/{direction}/{kind}", schema)
            log_ns, data = ns(t), encode(msg, source)
            with self._sinks_lock:
                for sink in sinks:
                    sink.put(channel[0], channel[1], log_ns, data)

    def _write_logs(self) -> None:
        while self._logs.lines:
            t, record = self._logs.lines.popleft()
            t = self._t if t is None else t
            self._put("/log", t, log_line(record, t))


class _Stream:
    """The writer's output: whole writes through :class:`AppendFile` (a full disk is said once, as for the other recordings)."""

    def __init__(self, file: AppendFile) -> None:
        self._file = file
        self._at = 0

    def write(self, data: bytes) -> int:
        self._file.write(bytes(data))  # a chunk the disk refused is lost; the index still counts it (docs/live-view.md says so)
        self._at += len(data)
        return len(data)

    def tell(self) -> int:
        return self._at

    def flush(self) -> None:
        pass


class McapSink:
    """One MCAP file, chunked and zstd-compressed, rotated to ``FILE.1`` past ``max_bytes``; each file seekable alone."""

    def __init__(self, path: Path, max_bytes: int, storage: Storage | None) -> None:
        self.path, self.max_bytes, self.storage = path, max_bytes, storage
        self._latched: dict[str, tuple[tuple[str, bytes], int, bytes]] = {}
        self._start()

    def put(self, topic: str, schema: tuple[str, bytes], log_ns: int, data: bytes) -> None:
        channel = self._channels.get(topic)
        if channel is None:
            schema_id = self._schema_ids.get(schema[0])
            if schema_id is None:
                schema_id = self._schema_ids[schema[0]] = self._writer.register_schema(schema[0], "jsonschema", schema[1])
            channel = self._channels[topic] = self._writer.register_channel(topic, "json", schema_id)
        self._sequence += 1
        self._writer.add_message(channel, log_ns, data, self._sequence)
        if topic in LATCHED:
            self._latched[topic] = (schema, log_ns, data)
            if topic == "/tree":
                self._tree_ns = log_ns

    def keyframe(self, tick: int, log_ns: int) -> None:
        self._keyframes.append((tick, log_ns, self._tree_ns))

    def ticked(self) -> bool:
        if self._stream.tell() <= self.max_bytes:
            return True
        self._finish()
        os.replace(self.path, self.path.with_name(self.path.name + ".1"))
        self._start()
        for topic, (schema, log_ns, data) in list(self._latched.items()):
            self.put(topic, schema, log_ns, data)
        return False

    def close(self) -> None:
        self._finish()

    def _start(self) -> None:
        self._file = AppendFile(self.path, "snapshots", "ticks are not recorded for replay", self.storage, append=False)
        self._stream = _Stream(self._file)
        chunk = min(CHUNK_BYTES, max(4096, self.max_bytes))  # a file rotated at less than a chunk would be one chunk, over its size
        self._writer = ChunkedWriter(self._stream, chunk)
        self._schema_ids: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence = 0
        self._tree_ns = 0
        self._keyframes: list[tuple[int, int, int]] = []

    def _finish(self) -> None:
        self._writer.add_metadata("executive.keyframes", {"ticks": json.dumps(self._keyframes, separators=(",", ":"))})
        self._writer.finish()
        self._file.close()
