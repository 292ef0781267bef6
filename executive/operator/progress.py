"""The status at 2 Hz for a person: a live line on a terminal, JSON lines otherwise."""

from __future__ import annotations

import json
import logging
import os
import threading
from collections.abc import Callable
from typing import Any, TextIO

from executive.operator.status import StatusSource, status_line
from executive.world.clock import Clock

log = logging.getLogger("executive.progress")  # the name the log and the journal show, kept since 0.1


class Progress:
    """Writes the status every ``period_s`` of clock time (2 Hz by default).

    On a terminal it is one line rewritten in place; elsewhere (a log file, a pipe, a service
    journal) one JSON object per line, with the clock time, for tools: every ``period_s`` and at
    once on a change of state, leg, mode or armed, so a tool sees even a mode held for less than a
    period. ``quiet`` keeps the JSON lines to those changes (and one every ``quiet_period_s``).
    The terminal's line is fitted to its width, read at each write (a window resized): the least
    important fields are left out (:func:`~executive.operator.status.status_fields`), as erasing the line
    (CR, ESC [K) clears one row only: a wrapped line would leave a stale row at each redraw. The log
    writes its records :meth:`apart` from the terminal's line (erased before, drawn again after, from
    any thread), so a warning never lands on its end. A reader that goes away (``run | head``)
    ends the status output, never the mission.
    """

    def __init__(self, stream: TextIO, clock: Clock, *, period_s: float = 0.5, quiet: bool = False, quiet_period_s: float = 10.0) -> None:
        self._stream = stream
        self._clock = clock
        self._tty = stream.isatty()
        self._quiet = quiet and not self._tty
        self._period_s = quiet_period_s if self._quiet else period_s
        self._source = StatusSource("progress", clock)
        self._next = float("-inf")
        self._last_key: tuple[object, ...] = ()
        self._shown: str | None = None  # the line on the terminal now, if one is
        self._closed = False  # the reader went away
        self._closed_by: OSError | None = None  # why, not logged yet
        self._lock = threading.RLock()  # a log record from another thread waits for the line being written, and the other way round

    def line(self) -> str:
        """The current status line."""
        return self._fitted(self._clock.now(), self._source.snapshot())

    def _fitted(self, now: float, status: dict[str, Any]) -> str:
        """The terminal's line: time and status, within the terminal's width (one column spare: some terminals wrap on the last)."""
        stamp = f"[{now:8.1f} s] "
        return stamp + status_line(status, terminal_columns(self._stream) - len(stamp) - 1)

    def update(self, force: bool = False) -> None:
        """Write the status if it is due (or ``force``)."""
        now = self._clock.now()
        key = self._source.headline()  # every tick: the whole status (a geodesic to the target) only when it is written
        changed = key != self._last_key
        if not (force or now >= self._next or (changed and not self._tty)):
            return
        status = self._source.snapshot()
        self._next = now + self._period_s
        self._last_key = key
        with self._lock:
            if self._tty:
                self._shown = self._fitted(now, status)
                self._emit(f"\r\x1b[K{self._shown}")
            else:
                self._emit(json.dumps({"t": round(now, 2), **status}) + "\n")
        self._say_if_closed()

    def apart(self, write: Callable[[], object]) -> None:
        """Call ``write`` (a log record to the terminal) with the line erased before and drawn again after; safe from any thread."""
        with self._lock:
            self.clear()
            try:
                write()
            finally:
                self.redraw()
        self._say_if_closed()

    def clear(self) -> None:
        """Erase the terminal's line (before a log record is written)."""
        if self._shown is not None:
            self._emit("\r\x1b[K")

    def redraw(self) -> None:
        """Draw the terminal's line again, as it was (after a log record)."""
        if self._shown is not None:
            self._emit(self._shown)

    def close(self) -> None:
        """End the in-place line so later output starts on its own line."""
        with self._lock:
            if self._tty:
                self._emit("\n")
            self._shown = None
        self._say_if_closed()

    def _emit(self, text: str) -> None:
        if self._closed:
            return
        try:
            self._stream.write(text)
            self._stream.flush()
        except (BrokenPipeError, ConnectionResetError) as exc:
            self._closed, self._shown, self._closed_by = True, None, exc

    def _say_if_closed(self) -> None:
        """Log that the reader went away, once, outside the lock (a record takes the log handler's lock, then ours)."""
        exc, self._closed_by = self._closed_by, None
        if exc is not None:
            log.warning("the status output was closed (%s): the mission goes on without it; `executive ctl status` still answers", exc)


def terminal_columns(stream: TextIO, default: int = 80) -> int:
    """The width of the terminal ``stream`` writes to: ``$COLUMNS`` if set (as shutil reads it), else the terminal's, else ``default``."""
    try:
        columns = int(os.environ.get("COLUMNS", ""))
    except ValueError:
        columns = 0
    if columns > 0:
        return columns
    try:
        return os.get_terminal_size(stream.fileno()).columns or default
    except (AttributeError, ValueError, OSError):  # no file descriptor (a test's StringIO), or not a terminal
        return default
