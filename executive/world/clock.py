"""Injected clocks: the same tree runs in real time on the vehicle and faster in tests.

Every component that needs time takes a :class:`Clock`. Times are seconds on a monotonic
time line; only differences are meaningful.
"""

from __future__ import annotations

import threading
import time
from typing import Protocol


class Clock(Protocol):
    """A source of monotonic time that can also wait."""

    def now(self) -> float:
        """Seconds on this clock's time line."""
        ...

    def sleep_until(self, t: float) -> None:
        """Block the caller (never a behaviour) until ``now() >= t``."""
        ...


class ScaledClock:
    """Wall-clock time run ``speedup`` times faster (1.0 = real time).

    The runtime and the simulated vehicle share one instance, so a 10 Hz tick stays 10 Hz of
    vehicle time whatever the speed-up. The speed-up can be lowered while running
    (:meth:`set_speedup`): the time line goes on from where it is, only slower.
    """

    def __init__(self, speedup: float = 1.0) -> None:
        if speedup <= 0:
            raise ValueError(f"speed-up must be > 0, got {speedup}")
        # (wall time, clock time then, speed-up since): one tuple, replaced whole, so another thread never sees half a change
        self._base = (time.monotonic(), 0.0, float(speedup))

    @property
    def speedup(self) -> float:
        return self._base[2]

    def set_speedup(self, speedup: float) -> None:
        """Run at ``speedup`` from now on; ``now()`` goes on from its current value."""
        if speedup <= 0:
            raise ValueError(f"speed-up must be > 0, got {speedup}")
        wall = time.monotonic()
        wall0, t0, current = self._base
        self._base = (wall, t0 + (wall - wall0) * current, float(speedup))

    def now(self) -> float:
        wall0, t0, speedup = self._base
        return t0 + (time.monotonic() - wall0) * speedup

    def sleep_until(self, t: float) -> None:
        while (delay := (t - self.now()) / self.speedup) > 0:  # again if the speed-up was lowered meanwhile
            time.sleep(delay)


class TickClock:
    """The time of the tick being run: every behaviour of one tick sees one time.

    On a clock that runs by itself (:class:`ScaledClock`) two reads in one tick differ; a guard
    judged by the tree and again by its failsafe in the same tick could then give two verdicts
    (fails, then holds a moment later) and the failsafe would find nothing to wait for.
    """

    def __init__(self, clock: Clock) -> None:
        self._clock = clock
        self._t = clock.now()

    def latch(self) -> float:
        """Start a tick: from now until the next latch, :meth:`now` is this time."""
        self._t = self._clock.now()
        return self._t

    def now(self) -> float:
        return self._t

    def sleep_until(self, t: float) -> None:
        self._clock.sleep_until(t)
        self.latch()


class ManualClock:
    """A clock that moves only when told to: for tick-by-tick tests."""

    def __init__(self, start: float = 0.0) -> None:
        self._t = start
        self._lock = threading.Lock()

    def now(self) -> float:
        return self._t

    def advance(self, dt: float) -> float:
        with self._lock:
            self._t += dt
            return self._t

    def sleep_until(self, t: float) -> None:
        with self._lock:
            self._t = max(self._t, t)
