"""The loop's schedule on the injected clock, and what it says when it cannot keep up.

A tick is *late* when it starts more than ``late_after_s`` after it was due; when the loop falls
more than a period behind, the schedule restarts from now and the ticks that were due meanwhile
are *skipped* (never run in a burst). Every ``window_s`` of clock time the achieved rate is
compared with the rate asked for: below ``1 - rate_margin`` of it the loop is *behind*: a warning
(at most one every ``warn_every_s``), and each listener is told (the built-in simulator's speed
governor slows the simulated world down to what the executive can follow).

Two process-wide settings let the loop wake on time while other threads share the interpreter
(the built-in simulator's, the one importing filterpy): :func:`keeping_time`, which ``executive run``
runs its loop in.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import re
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from executive.world import blackboard
from executive.world.clock import Clock, ScaledClock

log = logging.getLogger("executive.pacing")  # the name the log and the journal show, kept since 0.1

#: The most ticks per second of wall time the loop is asked for with the built-in simulator (``--rate`` x ``--speedup``):
#: a tick and the simulator's step it answers cost about 1 ms of CPU together on a 2-core machine, so above this the
#: loop cannot follow even when nothing else runs (benchmarks: ``python -m benchmarks --only tick sim``).
MAX_TICKS_PER_WALL_S = 2000.0


#: The shortest GIL switch interval :func:`keeping_time` sets (CPython's default is 5 ms): below it the
#: hand-overs between two busy threads cost more than the promptness is worth.
MIN_SWITCH_INTERVAL_S = 0.0001


@contextlib.contextmanager
def keeping_time(late_after_wall_s: float) -> Iterator[float]:
    """While the loop runs: other threads hand it the interpreter promptly, and the collector leaves start-up's objects alone.

    A loop woken for its tick needs the GIL; while another thread runs Python (the built-in simulator's step,
    filterpy's import in the background), CPython asks that thread to let go only after ``sys.getswitchinterval()``,
    5 ms by default: twice the 2.5 ms a tick may be late at ``--speedup 20`` (half of 100 ms of vehicle time, 20 times
    faster). The interval is cut to a tenth of the loop's lateness margin (``late_after_wall_s``, wall seconds), never
    lengthened, and restored after. A full pass of the collector over start-up's objects (modules, the mission, the
    tree) held the interpreter 20-50 ms: they are collected once here and frozen out of later passes, until the loop
    ends. The collector is left as it was found: unfrozen if nothing was frozen before (a process that goes on can collect
    start-up's objects again); what was frozen before (filterpy's import, a test session's collected tests) stays frozen.
    Yields the switch interval set.
    """
    before = sys.getswitchinterval()
    interval = min(before, max(MIN_SWITCH_INTERVAL_S, late_after_wall_s / 10.0))
    frozen_before = gc.get_freeze_count()
    gc.collect()
    gc.freeze()
    sys.setswitchinterval(interval)
    try:
        yield interval
    finally:
        sys.setswitchinterval(before)
        if not frozen_before:  # CPython unfreezes all or nothing
            gc.unfreeze()


def caps_logged(text: str) -> list[float]:
    """The speed-ups a run's log says the governor capped to, in order (for tools reading ``executive run``'s stderr)."""
    return [float(x) for x in re.findall(r"speed-up capped at (\S+)x", text)]


@dataclass(frozen=True)
class Behind:
    """One window in which the loop missed its rate: ticks per second of clock time achieved and asked for."""

    achieved_hz: float
    rate_hz: float
    late: int
    skipped: int
    #: Windows behind in a row, this one included.
    in_a_row: int = 1


class TickPacer:
    """When the next tick is due; counts late and skipped ticks; reports a loop that misses its rate (``/runtime/*``)."""

    def __init__(
        self,
        clock: Clock,
        period_s: float,
        *,
        late_after_s: float | None = None,
        window_s: float = 5.0,
        rate_margin: float = 0.1,
        warn_every_s: float = 60.0,
    ) -> None:
        self._clock = clock
        self.period_s = period_s
        self.late_after_s = period_s / 2 if late_after_s is None else late_after_s
        self.window_s = window_s
        self.rate_margin = rate_margin
        self.warn_every_s = warn_every_s
        self.ticks = self.late = self.skipped = 0
        self.worst_late_s = 0.0
        #: Told of each window the loop was behind in.
        self.listeners: list[Callable[[Behind], object]] = []
        self._due: float | None = None  # when the next tick is due on the schedule
        self._slot: float | None = None  # ... and when it would have been had the schedule not restarted: its lateness is from here
        self._window_start = self._window_ticks = self._window_late = self._window_skipped = 0
        self._next_warning = float("-inf")
        self._suppressed = 0
        self._behind_in_a_row = 0
        self._bb = blackboard.writer("tick pacer", ["/runtime/late_ticks", "/runtime/skipped_ticks", "/runtime/rate_hz"])

    def restart(self) -> None:
        """A new run of the loop: its first tick is due when it starts."""
        self._due = self._slot = None

    def tick_started(self) -> None:
        """A tick starts now: was it late?"""
        now = self._clock.now()
        if self._due is None or self._slot is None:
            self._due = self._slot = self._window_start = now
            self._window_ticks = self._window_late = self._window_skipped = 0
        lateness = now - self._slot
        if lateness > self.late_after_s:
            self.late += 1
            self._window_late += 1
            self._bb.set("/runtime/late_ticks", self.late)
        self.worst_late_s = max(self.worst_late_s, lateness)
        self.ticks += 1
        self._window_ticks += 1
        if now - self._window_start >= self.window_s:
            self._close_window(now)

    def next_due(self) -> float:
        """When the next tick is due (after a tick ends): a period after the last, or now when more than a period behind."""
        now = self._clock.now()
        due = self._slot = (now if self._due is None else self._due) + self.period_s
        if due < now - self.period_s:  # fell behind by more than a tick: do not try to catch up
            missed = int((now - due) / self.period_s)
            self.skipped += missed
            self._window_skipped += missed
            self._bb.set("/runtime/skipped_ticks", self.skipped)
            due = now
        self._due = due
        return due

    def summary(self) -> str:
        """``12 late ticks of 3000 (worst 0.42 s late), 3 skipped``"""
        return f"{self.late} late tick{'' if self.late == 1 else 's'} of {self.ticks} (worst {self.worst_late_s:.2f} s late), {self.skipped} skipped"

    def _close_window(self, now: float) -> None:
        span = now - self._window_start
        # the ticks started in the window, the one that closes it excepted: a full rate gives span / period of them
        achieved = (self._window_ticks - 1) / span
        rate = 1.0 / self.period_s
        self._bb.set("/runtime/rate_hz", round(achieved, 2))
        if achieved < (1.0 - self.rate_margin) * rate:
            self._behind_in_a_row += 1
            behind = Behind(achieved, rate, self._window_late, self._window_skipped, self._behind_in_a_row)
            self._warn(now, behind)
            for listener in self.listeners:
                listener(behind)
        else:
            self._behind_in_a_row = 0
        self._window_start, self._window_ticks, self._window_late, self._window_skipped = now, 1, 0, 0

    def _warn(self, now: float, behind: Behind) -> None:
        if now < self._next_warning:
            self._suppressed += 1
            return
        also = f" ({self._suppressed} more such window(s) since the last warning)" if self._suppressed else ""
        log.warning(
            "the loop cannot keep up: %.1f of its %g ticks per second of clock time; %d late, %d skipped in the last %g s%s",
            behind.achieved_hz,
            behind.rate_hz,
            behind.late,
            behind.skipped,
            self.window_s,
            also,
        )
        self._next_warning = now + self.warn_every_s
        self._suppressed = 0


class SpeedGovernor:
    """Slows the built-in simulator's clock to what the loop achieves when it is behind: the speed-up is capped, never raised.

    It acts when the loop has been behind ``patience`` windows in a row (a start-up hiccup is not
    a machine too slow); ``headroom`` keeps the new speed-up a little under what was achieved, so
    the next window has time to spare. Attach it with ``pacer.listeners.append(governor)``.
    """

    def __init__(self, clock: ScaledClock, *, patience: int = 2, headroom: float = 0.9, floor: float = 1.0) -> None:
        self._clock = clock
        self.patience = patience
        self.headroom = headroom
        self.floor = floor
        self.asked = clock.speedup
        self.caps: list[float] = []

    def __call__(self, behind: Behind) -> None:
        if behind.in_a_row < self.patience:
            return
        current = self._clock.speedup
        capped = max(self.floor, current * behind.achieved_hz / behind.rate_hz * self.headroom)
        if capped >= current:
            return
        self._clock.set_speedup(capped)
        self.caps.append(capped)
        log.warning(
            "speed-up capped at %.1fx (was %.0fx, asked %gx): the executive kept %.1f of its %g ticks per second; "
            "the simulated vehicle is slowed with it",
            capped,
            current,
            self.asked,
            behind.achieved_hz,
            behind.rate_hz,
        )
