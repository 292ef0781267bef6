"""Run ``executive`` with its wall clock stepped under it, as NTP or GPS time arriving steps a Raspberry Pi's (no real-time clock).

``python stepped_wall_clock.py STEP_FILE OFFSET_S -- executive arguments...``: every reader of the
wall clock in the process (``time.time``, ``time.time_ns``: the logging, the journal, the tlog,
pymavlink) sees the real time plus ``OFFSET_S`` (``-1.7e9``: a computer that booted in 1970), until
``STEP_FILE`` appears: from then on, plus the offset it holds (``0``: the right time). The monotonic
clock is left alone, as a wall-clock step leaves it. (libfaketime, Debian's, cannot do this for
Python: with the monotonic clock unfaked its clock_nanosleep wrapper fails ``time.sleep`` with EINVAL.)
"""

from __future__ import annotations

import os
import sys
import time


def install(step_file: str, offset_s: float) -> None:
    real_time, real_monotonic = time.time, time.monotonic
    state = {"offset": offset_s, "stepped": False, "checked": 0.0}

    def wall() -> float:
        now = real_monotonic()
        if not state["stepped"] and now - state["checked"] > 0.02:
            state["checked"] = now
            if os.path.exists(step_file):
                with open(step_file, encoding="utf-8") as f:
                    state["offset"], state["stepped"] = float(f.read() or 0), True
        return real_time() + state["offset"]

    time.time = wall  # type: ignore[assignment]
    time.time_ns = lambda: int(wall() * 1e9)  # type: ignore[assignment]


if __name__ == "__main__":
    step_file, offset, separator, *arguments = sys.argv[1:]
    assert separator == "--"
    install(step_file, float(offset))
    from executive.cli import main

    sys.exit(main(arguments))
