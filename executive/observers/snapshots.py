"""Per-tick snapshots of a running tree, and their replay: what the tree did, tick by tick.

A snapshot file is JSON lines. A ``tree`` line describes the nodes (pre-order: id, name, type,
parent). Each tick line holds only what changed since the tick before: node statuses (``s``),
feedback messages (``f``) and blackboard values (``bb``, as short text). Every ``keyframe_every``
ticks a keyframe holds everything, so a file can start anywhere. A run's end adds a line for its
last tick (``"end": true``): the blackboard as the end left it (COMPLETED, ABORTED and why, decided
after the tree's last tick), the statuses as that tick left them; a replay of that tick shows both.
When a file grows past
``max_bytes`` it is rotated to ``FILE.1`` (the one before is dropped): the disk use stays below
twice ``max_bytes`` however long the run.
"""

from __future__ import annotations

import ast
import bisect
import itertools
import json
import os
import re
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Protocol

import py_trees

from executive.io.storage import AppendFile, Storage
from executive.mission.events import Stage, Transition
from executive.tree.ticks import TickState, describe, render_tree, status_codes
from executive.world import blackboard
from executive.world.clock import Clock

if TYPE_CHECKING:
    from executive.mission.model import Mission
    from executive.runtime.assembly import Plug, Wiring
    from executive.world.dialect import MAVLinkMessage  # pymavlink: not imported to replay a file

MAX_VALUE_CHARS = 160


def show_value(value: Any) -> str:
    """A blackboard value as short text (its repr, cut to MAX_VALUE_CHARS)."""
    text = repr(value)
    return text if len(text) <= MAX_VALUE_CHARS else text[: MAX_VALUE_CHARS - 3] + "..."


def _immutable(kind: type) -> bool:
    """Values of ``kind`` are never changed in place (the blackboard's values are replaced whole): their text can be kept."""
    if kind in (str, int, float, bool, tuple, type(None)) or issubclass(kind, Enum):
        return True
    params = getattr(kind, "__dataclass_params__", None)
    if params is not None:
        return bool(params.frozen)
    config = getattr(kind, "model_config", None)  # a pydantic model: frozen (the mission's waypoints)
    return isinstance(config, dict) and bool(config.get("frozen"))


class ShownValues:
    """The blackboard as short text (:func:`show_value`), an immutable value's repr made again only once it is replaced.

    Most values stay the same object from tick to tick; their repr is most of what recording a tick costs.
    """

    def __init__(self) -> None:
        self._seen: dict[str, tuple[Any, str, bool]] = {}  # key -> the value, its text, whether it is kept while the same object
        self._kinds: dict[type, bool] = {}

    def read(self) -> dict[str, str]:
        shown: dict[str, str] = {}
        seen, kinds = self._seen, self._kinds
        for key, value in blackboard.documented_values():
            last = seen.get(key)
            if last is not None and last[2] and last[0] is value:
                shown[key] = last[1]
                continue
            kind = type(value)
            keep = kinds.get(kind)
            if keep is None:
                keep = kinds[kind] = _immutable(kind)
            text = shown[key] = show_value(value)
            seen[key] = (value, text, keep)
        return shown


_FIELD = re.compile(r"""(\w+)=('(?:[^'\\]|\\.)*'|"(?:[^"\\]|\\.)*"|[^,)]+)""")


def literal(text: str | None) -> Any:
    """A value shown as its repr, back (None when it is not a plain literal)."""
    try:
        return ast.literal_eval(text) if text is not None else None
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return None


def shown_fields(text: str | None) -> dict[str, Any]:
    """The fields of a value shown as ``Name(field=value, ...)`` (a dataclass's repr), each back as a literal; those cut off are missing."""
    return {name: literal(value) for name, value in _FIELD.findall(text or "") if not value.endswith("...")}


class TickFile(Protocol):
    """Where a :class:`SnapshotRecorder` writes: one back end per file format, chosen by the file's suffix."""

    def write_tree(self, nodes: list[dict[str, Any]]) -> None:
        """A (new) tree's description: its nodes in pre-order."""

    def write_tick(self, line: dict[str, Any]) -> bool:
        """One tick's line (what changed); False when what follows must be a keyframe (the line was lost, or a new file began)."""

    def write_event(self, before: str, after: str, reason: str) -> None:
        """A mission transition, as it happened."""

    def write_run(self, run: dict[str, Any]) -> None:
        """A run begins: ``mission``, ``vehicle``, ``resumed_from``, ``started`` (wall time) and its ``waypoints`` (lat, lon, name)."""

    def close(self) -> None: ...


class JsonLinesFile:
    """The snapshot file as JSON lines: rotated to ``FILE.1`` past ``max_bytes``, each new file starting with the tree line."""

    def __init__(self, path: Path, max_bytes: int, storage: Storage | None) -> None:
        self.path, self.max_bytes, self.storage = path, max_bytes, storage
        self._tree_line = ""
        self._file = self._open()

    def write_tree(self, nodes: list[dict[str, Any]]) -> None:
        self._tree_line = json.dumps({"tree": nodes})
        self._write(self._tree_line)

    def write_tick(self, line: dict[str, Any]) -> bool:
        return self._write(json.dumps(line, ensure_ascii=False))

    def write_event(self, before: str, after: str, reason: str) -> None:
        """Nothing to add: the transition is in the tick's blackboard (/mission/state, /mission/reason)."""

    def write_run(self, run: dict[str, Any]) -> None:
        """Nothing to add: the mission file holds the route (and the journal the run)."""

    def close(self) -> None:
        self._file.close()

    def _open(self) -> AppendFile:
        return AppendFile(self.path, "snapshots", "ticks are not recorded for replay", self.storage, append=False)

    def _write(self, line: str) -> bool:
        if not self._file.write((line + "\n").encode()):
            return False  # the disk took nothing: what follows is a keyframe, readable alone
        if self._file.size > self.max_bytes:
            self._file.close()
            os.replace(self.path, self.path.with_name(self.path.name + ".1"))
            self._file = self._open()
            self._file.write((self._tree_line + "\n").encode())
            return False  # the new file starts with a keyframe
        return True


def open_tick_file(path: Path | None, max_bytes: int, storage: Storage | None, clock: Clock | None, live: Any = None) -> TickFile:
    """The back end for ``path``: MCAP for ``.mcap`` (Foxglove and the MCAP tools read it), JSON lines otherwise.

    ``live`` (a :class:`~executive.observers.foxglove.live.FoxgloveSink`) is given the MCAP file's messages too; with no ``path``, only it.
    """
    if path is None or path.suffix.lower() == ".mcap":
        from executive.observers.mcap.recording import ChannelFeed, McapSink

        sinks = [McapSink(path, max_bytes, storage)] if path is not None else []
        return ChannelFeed([*sinks, *([live] if live is not None else [])], clock, storage=storage)
    return JsonLinesFile(path, max_bytes, storage)


class SnapshotRecorder:
    """Writes one line per tick of ``tree`` to ``path``; call :meth:`record` after each tick.

    ``FILE.mcap`` is written as MCAP (:mod:`executive.observers.mcap.recording`), anything else as JSON lines;
    ``clock`` times what happens between ticks (mission transitions, log lines) in an MCAP file.
    ``live``: a Foxglove server given what an MCAP file is (``path`` None: the server alone).
    ``wall``: the wall-clock time (Unix seconds) a run starts at, in an MCAP file's ``/mission/run``: ``time.time``; a
    lock-step test gives its own, and the same run then makes the same MCAP file byte for byte.
    """

    def __init__(
        self,
        path: str | Path | None,
        *,
        max_bytes: int = 50 << 20,
        keyframe_every: int = 100,
        storage: Storage | None = None,
        clock: Clock | None = None,
        live: Any = None,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.path = Path(path) if path is not None else None
        self.keyframe_every = keyframe_every
        self._wall = wall
        self._file = open_tick_file(self.path, max_bytes, storage, clock, live)
        self._nodes: list[py_trees.behaviour.Behaviour] = []
        self._status: list[str] = []
        self._feedback: list[str] = []
        self._values: dict[str, str] = {}
        self._shown = ShownValues()
        self._since_keyframe = 0
        self._last: tuple[int, float] | None = None  # the last tick recorded of this tree, and its time

    def attach(self, root: py_trees.behaviour.Behaviour) -> None:
        """Start recording a (new) tree: describes it and forces a keyframe."""
        self._nodes, nodes = describe(root)
        self._file.write_tree(nodes)
        self._status, self._feedback, self._values = [], [], {}
        self._since_keyframe = self.keyframe_every
        self._last = None

    def run_started(self, mission: Any, resumed_from: int | None) -> None:
        """A run of ``mission`` (a :class:`~executive.mission.model.Mission`) begins: what it is, and the route it starts on."""
        waypoints = [{"lat": w.lat, "lon": w.lon, "name": w.name} for w in mission.waypoints]
        info = {"mission": mission.name, "vehicle": str(mission.vehicle), "resumed_from": resumed_from, "started": self._wall()}
        self._file.write_run({**info, "waypoints": waypoints})

    @property
    def mavlink(self) -> Callable[[str, MAVLinkMessage], object] | None:
        """What hears each MAVLink message received (``in``) or sent (``out``) on the autopilot's link; None: the file takes none.

        Only the Foxglove back end records them (one channel per kind); ``run --tlog`` records the link's bytes.
        """
        return getattr(self._file, "mavlink", None)

    def event(self, before: object, after: object, reason: str) -> None:
        """A mission transition (a MissionState listener)."""
        self._file.write_event(str(before), str(after), reason)

    def record(self, tick: int, t: float) -> None:
        """Write what changed during tick ``tick`` (clock time ``t``)."""
        keyframe = self._since_keyframe >= self.keyframe_every
        self._since_keyframe = 0 if keyframe else self._since_keyframe + 1
        status = status_codes(self._nodes)
        feedback = [n.feedback_message or "" for n in self._nodes]
        values = self._shown.read()
        line: dict[str, Any] = {"tick": tick, "t": round(t, 3)}
        if keyframe:
            line["key"] = True
        changed = {i: s for i, s in enumerate(status) if keyframe or i >= len(self._status) or self._status[i] != s}
        notes = {i: m for i, m in enumerate(feedback) if keyframe or i >= len(self._feedback) or self._feedback[i] != m}
        keys = {k: v for k, v in values.items() if keyframe or self._values.get(k) != v}
        if changed:
            line["s"] = changed
        if notes:
            line["f"] = notes
        if keys:
            line["bb"] = keys
        self._status, self._feedback, self._values = status, feedback, values
        self._last = (tick, t)
        self._write(line)

    def record_end(self) -> None:
        """The run has ended: its last tick again, with the blackboard as the end left it (the statuses as the tick left them)."""
        if self._last is None:
            return  # no tick of this tree was recorded (a mission refused before its tree ran)
        tick, t = self._last
        values = self._shown.read()
        line: dict[str, Any] = {"tick": tick, "t": t, "end": True}
        keys = {k: v for k, v in values.items() if self._values.get(k) != v}
        if keys:
            line["bb"] = keys
        self._values = values
        self._last = None
        self._write(line)

    def close(self) -> None:
        self._file.close()

    def _write(self, line: dict[str, Any]) -> None:
        if not self._file.write_tick(line):
            self._since_keyframe = self.keyframe_every


SQLITE_HEADER = b"SQLite format 3\x00"
MCAP_MAGIC = b"\x89MCAP0\r\n"


class NotSnapshots(ValueError):
    """A file that is not a snapshot file (a journal, something else): says what it is and what reads it."""


def _check_kind(part: Path) -> None:
    """NotSnapshots unless ``part`` starts as a snapshot file does: with its ``tree`` line."""
    with part.open("rb") as f:
        head = f.read(64)
    if head.startswith(SQLITE_HEADER):
        raise NotSnapshots(
            f"{part}:1:1: (snapshot): this is a journal (SQLite), not a snapshot file: `executive report {part}` shows what its runs did; "
            "`executive run --snapshots FILE` records the ticks that `executive replay` shows"
        )
    if head and not head.startswith((b'{"tree"', MCAP_MAGIC)):
        raise NotSnapshots(f"{part}:1:1: (snapshot): not a snapshot file (one is written by `executive run --snapshots FILE`)")


def _is_mcap(part: Path) -> bool:
    with part.open("rb") as f:
        return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC


def read_lines(path: Path, near: int | None = None) -> Iterator[dict[str, Any]]:
    """The recording's lines, oldest first; with ``near``, an MCAP file's from its last keyframe before that tick."""
    for part in (path.with_name(path.name + ".1"), path):
        if part.exists():
            _check_kind(part)
            if _is_mcap(part):
                from executive.observers.mcap.reading import tick_lines

                yield from tick_lines(part, near)
                continue
            with part.open(encoding="utf-8") as f:
                for number, line in enumerate(f, 1):
                    try:
                        yield json.loads(line)
                    except json.JSONDecodeError as exc:
                        raise ValueError(f"{part}:{number}:{exc.colno}: (snapshot): {exc.msg}") from exc
                    except UnicodeDecodeError as exc:
                        raise NotSnapshots(f"{part}:{number}:1: (snapshot): not UTF-8 text, so not a snapshot file: {exc.reason}") from exc


def recorded_ticks(path: str | Path) -> list[tuple[int, int]]:
    """The ticks a recording holds, as (first, last) runs of consecutive ticks."""
    spans: list[tuple[int, int]] = []
    for line in read_lines(Path(path)):
        if "tick" not in line:
            continue
        tick = line["tick"]
        if spans and spans[-1][1] + 1 == tick:
            spans[-1] = (spans[-1][0], tick)
        elif not spans or tick > spans[-1][1]:
            spans.append((tick, tick))
    return spans


def _parts(path: Path) -> list[Path]:
    """The files of a recording, oldest first (``FILE.1`` before ``FILE``); FileNotFoundError if there is none."""
    parts = [part for part in (path.with_name(path.name + ".1"), path) if part.exists()]
    if not parts:
        raise FileNotFoundError(path)
    return parts


def _apply(state: TickState | None, nodes: list[dict[str, Any]], line: dict[str, Any]) -> TickState:
    """The state after tick line ``line`` (a keyframe starts afresh)."""
    previous = dict(state.blackboard) if state else {}
    same_tick = state is not None and line.get("end") and state.tick == line["tick"]  # the run's end, after its last tick
    if state is None or line.get("key"):
        state = TickState(line["tick"], line["t"], nodes)
    state.tick, state.t = line["tick"], line["t"]
    state.status.update({int(i): s for i, s in line.get("s", {}).items()})
    state.feedback.update({int(i): m for i, m in line.get("f", {}).items()})
    values = line.get("bb", {})
    state.blackboard.update(values)
    changed = {k for k, v in values.items() if previous.get(k) != v}  # a keyframe repeats what did not change
    state.changed = state.changed | changed if same_tick else changed
    return state


def replay(path: str | Path, tick: int | None = None) -> TickState:
    """The state at ``tick`` (the last recorded tick when None); LookupError if it was not recorded."""
    path = Path(path)
    _parts(path)
    state: TickState | None = None
    nodes: list[dict[str, Any]] = []
    for line in read_lines(path, tick):
        if "tree" in line:
            nodes = line["tree"]
            state = None
            continue
        if tick is not None and line["tick"] > tick:
            break
        state = _apply(state, nodes, line)
    if state is None or (tick is not None and state.tick != tick):
        spans = recorded_ticks(path)
        held = ", ".join(f"{first}-{last}" if last > first else str(first) for first, last in spans) or "none: no tick was recorded"
        raise LookupError(f"{path}: tick {tick} is not in the recording; it holds ticks {held}")
    return state


class _RecordedBoard:
    """A recorded blackboard (values as text) read back as :mod:`executive.observers.mcap.recording` reads the live one."""

    def __init__(self) -> None:
        self.text: dict[str, str] = {}
        self._t = 0.0
        self._fix: tuple[str | None, Any] = (None, None)

    def update(self, line: dict[str, Any]) -> None:
        self.text.update(line.get("bb", {}))
        self._t = line["t"]

    def value(self, key: str) -> Any:
        text = self.text.get(key)
        if key != "/vehicle/position":
            return literal(text)
        if text != self._fix[0]:  # a new fix: timed by the tick that saw it when its time was cut off the text
            fields = shown_fields(text)
            whole = "lat" in fields and "lon" in fields
            self._fix = (text, SimpleNamespace(**{"alt_rel_m": 0.0, **fields, "time": fields.get("time", self._t)}) if whole else None)
        return self._fix[1]


def convert(old: Path, new: Path) -> int:
    """The JSON-lines recording ``old`` (and ``old.1``) written as the MCAP recording ``new``; how many tick lines."""
    from executive.observers.mcap.recording import ChannelFeed, McapSink

    for part in _parts(old):
        if _is_mcap(part):
            raise NotSnapshots(f"{part}:1:1: (snapshot): already an MCAP recording")
    board = _RecordedBoard()
    out = ChannelFeed([McapSink(new, 1 << 62, None)], None, values=board.value)  # one file, however long: nothing is rotated away
    ticks = 0
    try:
        for line in read_lines(old):
            if "tree" in line:
                out.write_tree(line["tree"])
                continue
            before = board.value("/mission/state")
            board.update(line)
            after = board.value("/mission/state")
            if before is not None and after != before:
                out.write_event(str(before), str(after), str(board.value("/mission/reason") or ""))
            out.write_tick(line)
            ticks += 1
    finally:
        out.close()
    return ticks


@dataclass(frozen=True)
class _Entry:
    """Where a tick's line is: its file, its byte offset (MCAP: its log time, ns), the tree it belongs to, whether it is a keyframe."""

    tick: int
    part: Path
    offset: int
    tree: int
    key: bool


class Recording:
    """A snapshot file indexed once, for the state at any recorded tick without reading it all again (``replay --web``'s slider).

    ``watch`` is called with each tick line as the file is indexed (to gather what the whole run shows, a track).
    """

    def __init__(self, path: str | Path, watch: Callable[[dict[str, Any]], object] | None = None) -> None:
        self.path = Path(path)
        #: The trees recorded (a new one for each run), as their ``tree`` lines describe them.
        self.trees: list[list[dict[str, Any]]] = []
        self._entries: list[_Entry] = []
        for part in _parts(self.path):
            _check_kind(part)
            for offset, line in _offset_lines(part):
                if "tree" in line:
                    self.trees.append(line["tree"])
                elif self.trees:
                    self._entries.append(_Entry(line["tick"], part, offset, len(self.trees) - 1, bool(line.get("key"))))
                    if watch is not None:
                        watch(line)
        if not self._entries:
            raise LookupError(f"{self.path}: no tick recorded")
        self._ticks = [entry.tick for entry in self._entries]

    @property
    def ticks(self) -> list[int]:
        """Every recorded tick, in order (a run's end repeats its last tick)."""
        return list(self._ticks)

    @property
    def first(self) -> int:
        return self._ticks[0]

    @property
    def last(self) -> int:
        return self._ticks[-1]

    def nearest(self, tick: int) -> int:
        """The recorded tick at or before ``tick`` (the first one before the recording starts)."""
        return self._ticks[max(0, bisect.bisect_right(self._ticks, tick) - 1)]

    def tree_of(self, tick: int) -> int:
        """The index (in :attr:`trees`) of the tree ticking at recorded tick ``tick``."""
        return self._entries[self._index(tick)].tree

    def state_at(self, tick: int) -> TickState:
        """The state at recorded tick ``tick``; LookupError (naming the range) if it was not recorded."""
        i = self._index(tick)
        k = i
        while not self._entries[k].key:  # each file of a recording starts each tree with a keyframe
            k -= 1
        start = self._entries[k]
        lines = _offset_lines(start.part, start.offset)
        for _, line in lines:
            if line.get("tick") == start.tick and line.get("key"):
                break  # an MCAP file's seek may start a message early: at its keyframe's tree
        else:
            raise ValueError(f"{start.part}: the keyframe of tick {start.tick} is no longer there")
        state = _apply(None, self.trees[start.tree], line)
        for _, line in itertools.islice((entry for entry in lines if "tree" not in entry[1]), i - k):
            state = _apply(state, self.trees[start.tree], line)
        return state

    def _index(self, tick: int) -> int:
        """The entry of recorded tick ``tick``: its last line (a run's end follows its last tick's line, with the same tick)."""
        i = bisect.bisect_right(self._ticks, tick) - 1
        if i < 0 or self._ticks[i] != tick:
            raise LookupError(f"{self.path}: tick {tick} is not in the recording (ticks {self.first} to {self.last})")
        return i


def _offset_lines(part: Path, offset: int = 0) -> Iterator[tuple[int, dict[str, Any]]]:
    """Each line of one file with where it is: a JSON-lines file's byte offset, an MCAP file's log time (ns, found through its index)."""
    if _is_mcap(part):
        from executive.observers.mcap.reading import timed_lines

        yield from timed_lines(part, offset)
        return
    with part.open("rb") as f:
        f.seek(offset)
        for number, raw in enumerate(f, 1):
            yield offset, _parse(raw, part, number)
            offset += len(raw)


def _parse(raw: bytes, part: Path, number: int) -> dict[str, Any]:
    try:
        return json.loads(raw)
    except UnicodeDecodeError as exc:
        raise NotSnapshots(f"{part}:{number}:1: (snapshot): not UTF-8 text, so not a snapshot file: {exc.reason}") from exc
    except json.JSONDecodeError as exc:
        raise ValueError(f"{part}:{number}:{exc.colno}: (snapshot): {exc.msg}") from exc


def render(state: TickState, *, all_keys: bool = False) -> Iterable[str]:
    """The tree at that tick, like ``py_trees.display.unicode_tree`` with statuses, then the blackboard."""
    yield from render_tree(state)
    yield "blackboard" + (":" if all_keys else " (changed at this tick):")
    for key in sorted(state.blackboard if all_keys else state.changed):
        yield f"  {key}: {state.blackboard[key]}"


class _SnapshotRuns:
    """The recorder's part in a run: attached to each run's tree, a line per tick, the end recorded."""

    def __init__(self, recorder: SnapshotRecorder) -> None:
        self._recorder = recorder

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self._recorder.attach(root)
        self._recorder.run_started(mission, resumed_from)

    def ticked(self, tick: int, now: float) -> None:
        self._recorder.record(tick, now)

    def end(self, status: str, reason: str) -> None:
        self._recorder.record_end()  # the last tick as the run ended; the file goes on with the next run's tree


def snapshot_recorder(recorder: SnapshotRecorder) -> Plug:
    """Record every tick of the tree (node statuses, blackboard changes) and the mission's transitions for ``executive replay``."""

    def plug(w: Wiring) -> None:
        w.mission_state.events.subscribe(Transition, recorder.event, Stage.RECORDING)
        w.observers.append(_SnapshotRuns(recorder))
        if recorder.mavlink is not None:
            w.link.watch.listeners.append(recorder.mavlink)

    return plug
