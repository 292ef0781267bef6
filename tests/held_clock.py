"""Run ``executive`` with its clock held from a moment of the run until a signal comes: a test acting on what it reads of
the run (a line, a status) acts at that moment, at any speed-up and however busy the machine, not in a window of wall time.

``python held_clock.py WHEN -- executive arguments...``, ``WHEN`` one of:

- ``stopped``: from the moment the loop acts on a first SIGINT or SIGTERM (it logs ``mission aborted: stopped: SIGINT``)
  until the next one: a second Ctrl-C sent on that line lands while the vehicle is being made safe;
- ``sampled``: from the first status line (JSON, on stdout) that shows a sample taken until a signal: a SIGKILL sent on that
  line kills the run with one sample taken, never after the run went on.

Held, the clock stands still: no tick runs, no vehicle time passes; let go, it goes on from where it stood.
"""

from __future__ import annotations

import json
import logging
import sys
import time

from executive.cli import main, run
from executive.operator.progress import Progress
from executive.world.clock import ScaledClock

_held = {"from": False, "let_go": False}


class _HeldClock(ScaledClock):
    """``executive run``'s clock, standing still while :data:`_held` says so."""

    def sleep_until(self, t: float) -> None:
        if _held["from"] and not _held["let_go"]:
            stood = self.now()
            while not _held["let_go"]:
                time.sleep(0.01)  # a signal ends it early: the handler runs, then the loop looks again
            *_, speedup = self._base
            self._base = (time.monotonic(), stood, speedup)
        super().sleep_until(t)


class _OnStop(logging.Handler):
    def emit(self, record: logging.LogRecord) -> None:
        if record.getMessage().startswith("mission aborted: stopped: SIG"):
            _held["from"] = True


def _hold_after_a_sample(emit):  # type: ignore[no-untyped-def]
    def emitted(self, text: str) -> None:  # type: ignore[no-untyped-def]
        emit(self, text)
        if text.startswith("{") and json.loads(text)["samples"]:
            _held["from"] = True

    return emitted


def _let_go_on(on_signal):  # type: ignore[no-untyped-def]
    def counted(self, signum: int, frame: object) -> None:  # type: ignore[no-untyped-def]
        _held["let_go"] = _held["let_go"] or _held["from"]
        on_signal(self, signum, frame)

    return counted


if __name__ == "__main__":
    when, separator, *arguments = sys.argv[1:]
    assert separator == "--" and when in ("stopped", "sampled"), sys.argv
    run.ScaledClock = _HeldClock  # type: ignore[misc]
    run.StopSignals._on_signal = _let_go_on(run.StopSignals._on_signal)  # type: ignore[method-assign]
    if when == "stopped":
        logging.getLogger("executive.runtime").addHandler(_OnStop())
    else:
        Progress._emit = _hold_after_a_sample(Progress._emit)  # type: ignore[method-assign]
    sys.exit(main(arguments))
