"""Run ``executive`` with its clock held from the moment its loop acts on a first SIGINT or SIGTERM (it logs ``mission aborted:
stopped: SIGINT``) until another one arrives: a test's second Ctrl-C, sent when it reads that line, lands while the vehicle is
being made safe, at any speed-up and however busy the machine (the vehicle time of making it safe is not a window for the test
to hit in wall time).

``python held_after_stop.py -- executive arguments...``. Held, the clock stands still: no tick runs, no vehicle time passes.
"""

from __future__ import annotations

import logging
import sys
import time

from executive.cli import main, run
from executive.world.clock import ScaledClock

_held = {"from_stop": False, "signals": 0}


class _HeldAfterStop(ScaledClock):
    """``executive run``'s clock, standing still while :data:`_held` says so (then going on from where it stood)."""

    def sleep_until(self, t: float) -> None:
        if _held["from_stop"] and _held["signals"] < 2:
            stood = self.now()
            while _held["signals"] < 2:
                time.sleep(0.01)  # a signal ends it early: the handler runs, then the loop looks again
            *_, speedup = self._base
            self._base = (time.monotonic(), stood, speedup)
        super().sleep_until(t)


class _OnStop(logging.Handler):
    def emit(self, record: logging.LogRecord) -> None:
        if record.getMessage().startswith("mission aborted: stopped: SIG"):
            _held["from_stop"] = True


def _counting(on_signal):  # type: ignore[no-untyped-def]
    def counted(self, signum: int, frame: object) -> None:  # type: ignore[no-untyped-def]
        _held["signals"] += 1
        on_signal(self, signum, frame)

    return counted


if __name__ == "__main__":
    separator, *arguments = sys.argv[1:]
    assert separator == "--"
    run.ScaledClock = _HeldAfterStop  # type: ignore[misc]
    run.StopSignals._on_signal = _counting(run.StopSignals._on_signal)  # type: ignore[method-assign]
    logging.getLogger("executive.runtime").addHandler(_OnStop())
    sys.exit(main(arguments))
