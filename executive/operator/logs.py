"""The log for a person: UTC timestamps, what an operator follows shown by default, and the live status line kept apart.

Each record reads ``2026-05-01T10:12:03.250Z t=12.345 executive WARNING intervention: ...``: the
timestamp is the computer's UTC wall clock, ``t=`` the run's clock (vehicle time, monotonic: the
live status line's ``[  12.3 s]`` and the journal's ``t``), which a wall clock's jump leaves alone.
By default the operator's events are shown at INFO - the mission's state changes and pauses, legs
done, samples, route edits, the autopilot found and its messages, the vehicle made safe - and every
other module's only from WARNING; ``-v`` shows every INFO, ``-vv`` DEBUG.

A record never lands on the end of the live status line: the line is cleared before the record
is written and drawn again after it (:class:`LiveLineHandler`). Under systemd, with stderr going
to the system journal (``$JOURNAL_STREAM``), each record carries its syslog priority instead of a
timestamp (``<4>intervention: ...``; the journal stamps it): ``journalctl -p warning`` finds it.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Callable
from typing import Protocol, TextIO

#: The loggers of what an operator follows, shown at INFO without -v.
OPERATOR_LOGGERS = (
    "executive.mission.lifecycle",  # state changes (pauses, resumes, aborts), legs done, samples, route edits
    "executive.runtime",  # the vehicle made safe
    "executive.io.mavlink.reader",  # the autopilot found, the link up, the autopilot's own messages
    "executive.autopilot_link.route_keeper",  # the route held by the autopilot
    "executive.energy",  # the energy estimate of each leg (what is left, what the route and the way home need)
    "executive.behaviours.rc_switches",  # what an RC switch did
    "executive.behaviours.flow",  # what a person does to end a wait (how to arm the vehicle)
    "executive.behaviours.zones",  # the zones and rally points on the autopilot, its fence parameters read and set
    "executive.io.can.reader",  # the AgileX base found on the CAN bus (with --can)
)


class LiveLine(Protocol):
    """A line rewritten in place on a terminal (the status line)."""

    def apart(self, write: Callable[[], object]) -> None:
        """Call ``write`` with the line erased before and drawn again after (and nothing else written meanwhile)."""


class UtcFormatter(logging.Formatter):
    """``2026-05-01T10:12:03.250Z t=12.345 executive LEVEL name: message``: UTC, and the run's clock beside it.

    The UTC wall clock may jump (a computer without a real-time clock boots in 1970, then NTP or GPS
    time arrives): ``t=`` is the run's own time line (the vehicle's, the journal's ``t``; monotonic),
    which orders the records whatever the wall clock did. Before a run names its clock (:func:`use_clock`),
    seconds since the log was set up.
    """

    converter = time.gmtime

    def __init__(self, clock: Callable[[], float] | None = None) -> None:
        super().__init__("%(asctime)s.%(msecs)03dZ t=%(t).3f executive %(levelname)s %(name)s: %(message)s", datefmt="%Y-%m-%dT%H:%M:%S")
        start = time.monotonic()
        self.clock = clock or (lambda: time.monotonic() - start)

    def format(self, record: logging.LogRecord) -> str:
        record = logging.makeLogRecord(record.__dict__)
        record.name = record.name.removeprefix("executive.")
        record.t = self.clock()
        return super().format(record)


class JournalFormatter(logging.Formatter):
    """``<4>intervention: ...``: the record's syslog priority (read by the journal, sd-daemon(3)), its module and message."""

    PRIORITIES = ((logging.CRITICAL, 2), (logging.ERROR, 3), (logging.WARNING, 4), (logging.INFO, 6))

    def format(self, record: logging.LogRecord) -> str:
        priority = next((p for level, p in self.PRIORITIES if record.levelno >= level), 7)
        text = f"{record.name.removeprefix('executive.')}: {record.getMessage()}"
        if record.exc_info:
            text += "\n" + self.formatException(record.exc_info)
        return f"<{priority}>" + text.replace("\n", f"\n<{priority}>")


def to_journal(stream: TextIO) -> bool:
    """Whether ``stream`` is the systemd journal's (``$JOURNAL_STREAM`` is its device:inode, systemd.exec(5))."""
    try:
        info = os.fstat(stream.fileno())
    except (OSError, ValueError, AttributeError):  # not a file (a test's StringIO)
        return False
    return os.environ.get("JOURNAL_STREAM") == f"{info.st_dev}:{info.st_ino}"


class LiveLineHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """Writes records to ``stream``, clearing the live line (when there is one) before and drawing it again after."""

    def __init__(self, stream: TextIO) -> None:
        super().__init__(stream)
        self.live: LiveLine | None = None

    def emit(self, record: logging.LogRecord) -> None:
        live = self.live
        if live is None:
            super().emit(record)
        else:
            live.apart(lambda: super(LiveLineHandler, self).emit(record))


def setup_logging(verbose: int = 0, stream: TextIO | None = None) -> LiveLineHandler:
    """Log to ``stream`` (stderr): the operator's events and every warning by default, all INFO with -v, DEBUG with -vv."""
    stream = stream or sys.stderr
    handler = LiveLineHandler(stream)
    handler.setFormatter(JournalFormatter() if to_journal(stream) else UtcFormatter())
    root = logging.getLogger()
    for old in list(root.handlers):
        root.removeHandler(old)
        old.close()
    root.addHandler(handler)
    root.setLevel((logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)])
    for name in OPERATOR_LOGGERS:
        logging.getLogger(name).setLevel(logging.DEBUG if verbose >= 2 else logging.INFO)
    return handler


def use_clock(now: Callable[[], float]) -> None:
    """The log's ``t=`` from now on: the run's clock (its ``now``)."""
    for handler in logging.getLogger().handlers:
        if isinstance(handler.formatter, UtcFormatter):
            handler.formatter.clock = now


def attach_live_line(live: LiveLine | None) -> None:
    """Keep the log's records off ``live`` (None: no live line any more)."""
    for handler in logging.getLogger().handlers:
        if isinstance(handler, LiveLineHandler):
            handler.live = live
