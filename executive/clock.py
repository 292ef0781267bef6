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
    vehicle time whatever the speed-up.
    """

    def __init__(self, speedup: float = 1.0) -> None:
        if speedup <= 0:
            raise ValueError(f"speed-up must be > 0, got {speedup}")
        self.speedup = speedup
        self._origin = time.monotonic()

    def now(self) -> float:
        return (time.monotonic() - self._origin) * self.speedup

    def sleep_until(self, t: float) -> None:
        delay = (t - self.now()) / self.speedup
        if delay > 0:
            time.sleep(delay)


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
