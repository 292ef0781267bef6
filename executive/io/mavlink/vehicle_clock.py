"""The autopilot's clock against ours: a simulator at another speed-up than the executive's is said, with both rates and the flag to use.

The executive counts its ticks and every timeout in its own clock: real time, or ``--speedup X``
times it. A SITL (or ``executive sim``) at ``--speedup 20`` driven by an executive without
``--speedup`` gets a tick every 2 s of its time and timeouts 20 times too long: a mission that
"completes" at 0.5 Hz (issue 28). The autopilot says how fast its time runs: ``time_boot_ms`` in
SYSTEM_TIME and in every message that carries it (ArduPilot's ``AP_HAL::millis()``, SITL's
simulated time: GCS_Common.cpp ``send_system_time``, ``send_global_position_int``...).

Each window of at least :data:`WINDOW_S` on both clocks (and :data:`MIN_SAMPLES` readings), the
rate of the autopilot's clock against ours is the least-squares slope of its boot time over our
clock time at each reading: a reading late on the link (jitter, a burst after a stall) moves the
slope by its lateness over the window, averaged with the others. A rate beyond :data:`FAR` (or
under its inverse) is warned about once, and again only when it moves :data:`FAR` times from the
one warned about (a SITL that cannot keep its speed-up drifts a little: not news).
"""

from __future__ import annotations

import logging
import math

from executive.world.clock import Clock

log = logging.getLogger(__name__)

#: A window spans at least this much of each clock (seconds)...
WINDOW_S = 2.0
#: ... and this many readings of the autopilot's clock.
MIN_SAMPLES = 5
#: The autopilot's clock at this many times ours (or fewer than 1/FAR) is far from it.
FAR = 1.5


def speedup_flag(rate: float) -> str:
    """The flag for a measured rate: a round speed-up within 5 % of it (a multiple of 5, else a whole number), else the rate itself.

    A simulator asked for 20 on a busy machine measures 19.3: ``--speedup 20``.
    """
    for step in (5, 1):
        near = step * round(rate / step)
        if near >= 1 and abs(rate - near) <= 0.05 * rate:
            return f"--speedup {near:d}"
    return f"--speedup {rate:.2g}"


class VehicleClockWatch:
    """Fed the autopilot's boot time at our clock's time (:meth:`sample`), it judges each window and warns when the clocks run apart.

    ``clock`` is the executive's: its ``speedup`` (a :class:`~executive.world.clock.ScaledClock`'s; 1 for
    another) turns the measured ratio into rates against real time.
    """

    def __init__(self, clock: Clock) -> None:
        self._clock = clock
        #: The latest window's rate of the autopilot's clock against ours (None until a window is complete).
        self.ratio: float | None = None
        self._warned: float | None = None  # the ratio last warned about
        self._last_boot_s: float | None = None
        self._start()

    def _start(self, origin: tuple[float, float] | None = None) -> None:
        """A new window, from ``origin`` (our time, its boot time) when given."""
        self._origin = origin
        self._n = 0
        self._sx = self._sy = self._sxx = self._sxy = 0.0
        self._span = (0.0, 0.0)
        if origin is not None:
            self._add(*origin)

    def _add(self, now: float, boot_s: float) -> None:
        assert self._origin is not None
        x, y = now - self._origin[0], boot_s - self._origin[1]
        self._n += 1
        self._sx += x
        self._sy += y
        self._sxx += x * x
        self._sxy += x * y
        self._span = (x, y)

    def sample(self, boot_s: float, now: float) -> None:
        """The autopilot's clock read ``boot_s`` (its time_boot_ms / 1000) in a message handled at our ``now``."""
        if boot_s == self._last_boot_s:
            return  # nothing new since the last reading
        if self._last_boot_s is not None and boot_s < self._last_boot_s:  # a reboot: its clock starts again
            self._start()
        self._last_boot_s = boot_s
        if self._origin is None:
            self._start((now, boot_s))
            return
        self._add(now, boot_s)
        ours, theirs = self._span
        if ours < WINDOW_S or theirs < WINDOW_S or self._n < MIN_SAMPLES:
            return
        n = self._n
        variance = self._sxx - self._sx * self._sx / n
        if variance > 0.0:
            self._judge((self._sxy - self._sx * self._sy / n) / variance)
        self._start((now, boot_s))

    def _judge(self, ratio: float) -> None:
        self.ratio = ratio
        log.debug("the autopilot's clock ran %.4g s per second of ours over the last %.3g s of ours", ratio, self._span[0])
        if not math.isfinite(ratio) or ratio <= 0.0:
            return
        far = ratio > FAR or ratio < 1.0 / FAR
        if not far:
            if self._warned is not None:
                log.warning("the autopilot's clock keeps to the executive's again (%.2fx ours)", ratio)
                self._warned = None
            return
        if self._warned is not None and 1.0 / FAR <= ratio / self._warned <= FAR:
            return  # said already, and not much changed
        self._warned = ratio
        ours = float(getattr(self._clock, "speedup", 1.0))
        theirs = ratio * ours
        flag = speedup_flag(theirs)
        why = "a real vehicle: no --speedup" if flag == "--speedup 1" else "the simulator's speed-up"
        log.warning(
            "the autopilot's clock runs %.3gx real time and the executive's %.3gx (%.3g s of the vehicle's time per second of ours): "
            "the executive ticks and times out in its own clock; run it with %s (%s)",
            theirs, ours, ratio, flag, why,
        )  # fmt: skip
