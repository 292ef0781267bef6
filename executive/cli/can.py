"""``executive can decode FILE.log [--json]``, ``executive can monitor IFACE:CHANNEL [--duration S] [--json]``.

What the executive makes of a CAN bus: one line per frame (time since the first frame, id, bytes,
the decoded AgileX frame, and what is wrong with it), then a summary: frames per id, bad frames,
frames of other ids, and every stretch where the RC frame's (0x241) rolling counter froze, which
is how the executive notices a lost transmitter in CAN command mode. ``--json`` prints one JSON
object per frame and the summary as the last one (``{"summary": ...}``).

``decode`` reads any log python-can reads: candump ``-L`` ``.log`` files, ``.asc``, ``.blf``,
``.trc``, ``.csv``, as ``--format`` says, else by the file's extension, else by its first bytes
(a candump log named ``bus.txt``). A candump line python-can cannot read is skipped and counted
(``3 lines not understood: 6, 19, 40``), the frames after it decoded. ``monitor`` watches a live
bus until ``--duration`` or Ctrl-C. Exit codes: 0 done, 1 lines were skipped, 2 bad input (no
such file, unreadable log, bad IFACE:CHANNEL), 3 the bus cannot be opened.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can

from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_NO_VEHICLE, EXIT_OK, number
from executive.io.can.agilex import RC_STATE_ID, FrameStats, RcState, decode, is_agilex
from executive.io.can.bus import CanOpenError, CanSpecError, open_can


@dataclass
class Freeze:
    """A stretch of 0x241 frames repeating one rolling counter value."""

    counter: int
    from_t: float
    to_t: float
    repeats: int  # frames after the first that carried the same counter

    def as_dict(self) -> dict[str, Any]:
        return {"counter": self.counter, "from_t": round(self.from_t, 6), "to_t": round(self.to_t, 6), "repeats": self.repeats}


@dataclass
class Analysis:
    """Reads frames in order: what each is, and the summary of all of them."""

    stats: FrameStats = field(default_factory=FrameStats)
    freezes: list[Freeze] = field(default_factory=list)
    _start: float | None = None
    _counter: int | None = None
    _counter_t: float = 0.0
    _freeze: Freeze | None = None

    def feed(self, msg: can.Message) -> dict[str, Any]:
        """One frame: a JSON-ready record of what it is."""
        if self._start is None:
            self._start = msg.timestamp
        t = msg.timestamp - self._start
        frame = decode(msg)
        usable = self.stats.record(msg, frame)
        record: dict[str, Any] = {
            "t": round(t, 6),
            "timestamp": msg.timestamp,
            "id": f"0x{msg.arbitration_id:03X}",
            "extended": msg.is_extended_id,
            "data": bytes(msg.data).hex().upper() if not msg.is_remote_frame else None,
            "kind": frame.KIND if frame is not None else None,
            "valid": usable,
        }
        if msg.is_error_frame:
            record["problem"] = "error frame"
        elif msg.is_remote_frame:
            record["problem"] = "remote frame"
        elif frame is None and is_agilex(msg):
            record["problem"] = f"wrong length {len(msg.data)}"
        elif frame is None:
            record["problem"] = "id not read by the executive"
        elif not usable:
            record["problem"] = "values out of range"
        if frame is not None:
            record["fields"] = frame.fields()
            record["text"] = frame.describe()
        if usable and isinstance(frame, RcState):
            record["counter_frozen"] = self._on_counter(frame.counter, t)
        return record

    def _on_counter(self, counter: int, t: float) -> bool:
        if counter != self._counter:
            self._counter, self._counter_t, self._freeze = counter, t, None
            return False
        if self._freeze is None:
            self._freeze = Freeze(counter, self._counter_t, t, 0)
            self.freezes.append(self._freeze)
        self._freeze.to_t = t
        self._freeze.repeats += 1
        return True

    def summary(self) -> dict[str, Any]:
        return {
            "frames": self.stats.frames,
            "per_id": {f"0x{i:03X}": n for i, n in sorted(self.stats.per_id.items())},
            "bad": self.stats.bad,
            "other": self.stats.other,
            "rc_frames": self.stats.per_id.get(RC_STATE_ID, 0),
            "rc_counter_freezes": [f.as_dict() for f in self.freezes],
        }


def frame_line(record: dict[str, Any]) -> str:
    """The text line of one frame record."""
    data = record["data"]
    raw = " ".join(data[i : i + 2] for i in range(0, len(data), 2)) if data is not None else "(remote)"
    nbytes = len(data) // 2 if data is not None else 0
    text = record.get("text", "")
    notes = []
    if "problem" in record:
        notes.append(f"[{record['problem']}]")
    if record.get("counter_frozen"):
        notes.append("[RC counter frozen]")
    id_text = record["id"][2:] if not record["extended"] else record["id"][2:].rjust(8, "0")
    return " ".join(part for part in (f"{record['t']:12.6f}", f"{id_text:>3}", f"[{nbytes}]", f"{raw:<23}", text, *notes) if part).rstrip()


def summary_lines(summary: dict[str, Any]) -> list[str]:
    per_id = ", ".join(f"{i} x{n}" for i, n in summary["per_id"].items()) or "none"
    freezes = summary["rc_counter_freezes"]
    lines = [f"summary: {summary['frames']} frames ({per_id}); bad {summary['bad']}; other ids {summary['other']}; RC counter freezes {len(freezes)}"]
    for f in freezes:
        lines.append(
            f"  RC counter froze at {f['counter']} (0x{f['counter']:02X}): {f['repeats']} repeated frames, "
            f"t={f['from_t']:.6f}..{f['to_t']:.6f} ({f['to_t'] - f['from_t']:.3f} s)"
        )
    return lines


class _Printer:
    def __init__(self, as_json: bool) -> None:
        self.as_json = as_json

    def frame(self, record: dict[str, Any]) -> None:
        print(json.dumps(record) if self.as_json else frame_line(record), flush=True)

    def summary(self, summary: dict[str, Any]) -> None:
        if self.as_json:
            print(json.dumps({"summary": summary}), flush=True)
        else:
            print("\n".join(summary_lines(summary)), flush=True)


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``can`` subcommand and its ``decode`` and ``monitor`` actions."""
    parser = subparsers.add_parser(
        "can", help="what the executive makes of a CAN bus (a log, or live)", description="Decode the AgileX frames of a CAN log or a live bus."
    )
    actions = parser.add_subparsers(dest="can_action", required=True, metavar="ACTION")
    decode_parser = actions.add_parser("decode", help="decode a CAN log (candump -L .log, .asc, .blf, ...)")
    decode_parser.add_argument("file", metavar="FILE", help="the log (its format: --format, else its extension, else its first bytes)")
    decode_parser.add_argument("--format", choices=sorted(FORMATS), help="the log's format, whatever the file's name")
    decode_parser.add_argument("--json", action="store_true", help="one JSON object per frame, the summary last")
    decode_parser.set_defaults(func=run_decode)
    monitor = actions.add_parser("monitor", help="watch a live CAN bus")
    monitor.add_argument("bus", metavar="IFACE:CHANNEL", help="e.g. socketcan:can0, slcan:/dev/ttyACM0@115200, pcan:PCAN_USBBUS1, virtual:test")
    monitor.add_argument("--duration", metavar="S", type=number(above=0), help="stop after S seconds (default: at Ctrl-C)")
    bitrate = "CAN bit rate (default: %(default)s; socketcan: ip link sets it)"
    monitor.add_argument("--bitrate", metavar="BIT/S", type=int, default=500_000, help=bitrate)
    monitor.add_argument("--json", action="store_true", help="one JSON object per frame, the summary last")
    monitor.set_defaults(func=run_monitor)


def _error(text: str) -> None:
    print(f"executive: can: {text}", file=sys.stderr)


#: ``--format`` -> python-can's reader of it.
FORMATS: dict[str, type[can.io.generic.MessageReader]] = {
    "candump": can.CanutilsLogReader, "asc": can.ASCReader, "blf": can.BLFReader, "trc": can.TRCReader, "csv": can.CSVReader,
}  # fmt: skip
_SUFFIXES = {".log": "candump", ".asc": "asc", ".blf": "blf", ".trc": "trc", ".csv": "csv"}


def log_format(path: Path, asked: str | None = None) -> str | None:
    """The log's format: ``asked``, else by its extension, else by its first bytes (None: not one python-can reads)."""
    if asked is not None:
        return asked
    if path.suffix.lower() in _SUFFIXES:
        return _SUFFIXES[path.suffix.lower()]
    try:
        with path.open("rb") as f:
            head = f.read(512)
    except OSError:
        return None
    if head.startswith(b"LOGG"):
        return "blf"
    text = head.decode("utf-8", "replace").lstrip()
    if text.startswith("("):  # candump -L: (1699999999.123456) can0 241#...
        return "candump"
    if text.startswith(";$FILEVERSION"):
        return "trc"
    if text.lower().startswith(("date ", "base ")):
        return "asc"
    if text.startswith("timestamp,"):
        return "csv"
    return None


def _candump_frames(path: Path, skipped: list[tuple[int, str]]) -> Iterable[can.Message]:
    """Each line of a candump log that python-can reads, as a frame; the others added to ``skipped`` (line, why)."""
    with path.open(encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                yield from can.CanutilsLogReader(io.StringIO(line))
            except Exception as exc:  # python-can's reader raises ValueError, IndexError... on a damaged line
                skipped.append((number, str(exc) or type(exc).__name__))


def run_decode(args: argparse.Namespace) -> int:
    """Decode every frame of a log file; 1 when lines of it could not be read (the rest decoded)."""
    path = Path(args.file)
    printer = _Printer(args.json)
    analysis = Analysis()
    kind = log_format(path, args.format)
    if not path.is_file():
        _error(f"{path}: cannot read: No such file or directory")
        return EXIT_BAD_INPUT
    if kind is None:
        _error(f"{path}: not a CAN log python-can reads by its name or first bytes: give --format {'|'.join(sorted(FORMATS))}")
        return EXIT_BAD_INPUT
    skipped: list[tuple[int, str]] = []
    try:
        frames = _candump_frames(path, skipped) if kind == "candump" else FORMATS[kind](path)
    except (OSError, ValueError) as exc:
        _error(f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}")
        return EXIT_BAD_INPUT
    try:
        for msg in frames:
            printer.frame(analysis.feed(msg))
    except Exception as exc:  # a binary or structured log damaged past reading: what came before it stands
        printer.summary(analysis.summary())
        _error(f"{path} (after frame {analysis.stats.frames}): not a {kind} log python-can can read: {exc}")
        return EXIT_BAD_INPUT
    printer.summary(analysis.summary() | ({"not_understood": [n for n, _ in skipped]} if skipped else {}))
    if skipped:
        lines = ", ".join(str(n) for n, _ in skipped)
        _error(f"{path}: {len(skipped)} line{'s' if len(skipped) > 1 else ''} not understood: {lines} (line {skipped[0][0]}: {skipped[0][1]})")
        return EXIT_FAILED
    return EXIT_OK


def run_monitor(args: argparse.Namespace) -> int:
    """Watch a live bus and print what each frame is."""
    try:
        bus = open_can(args.bus, bitrate=args.bitrate)
    except CanSpecError as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    except CanOpenError as exc:
        _error(str(exc))
        return EXIT_NO_VEHICLE
    if args.bus.lower().startswith("virtual:"):
        _error(
            f"{args.bus}: python-can's virtual bus lives inside one process: this monitor hears frames sent in it only, never another "
            "process's (an executive's or a simulator's); to watch a bus between processes use a vcan: socketcan:vcan0 (note)"
        )
    printer = _Printer(args.json)
    analysis = Analysis()
    try:
        for msg in _receive(bus, args.duration):
            printer.frame(analysis.feed(msg))
    except KeyboardInterrupt:
        pass
    except can.CanError as exc:
        printer.summary(analysis.summary())
        _error(f"{args.bus}: the bus failed: {exc}")
        return EXIT_NO_VEHICLE
    finally:
        bus.shutdown()
    printer.summary(analysis.summary())
    return EXIT_OK


def _receive(bus: can.BusABC, duration: float | None) -> Iterable[can.Message]:
    """Frames as they arrive, until ``duration`` seconds of wall time have passed (forever without one)."""
    deadline = None if duration is None else time.monotonic() + duration
    while True:
        remaining = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
        if remaining <= 0:
            return
        msg = bus.recv(remaining)
        if msg is not None:
            yield msg
