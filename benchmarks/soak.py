"""Soak: a long mission at full speed (simulator and runtime on a manual clock); memory and tick time must not grow.

A rover drives a serpentine of ``legs`` 200 m legs (about 3 hours of vehicle time with the defaults).
The run is cut in quarters: the last quarter's median tick time and Python heap (tracemalloc) against
the first quarter's, after the pre-flight, show whether anything accumulates as a run goes on.
"""

from __future__ import annotations

import gc
import resource
import time
import tracemalloc

from benchmarks.common import Row, SimLoop, median, rover_mission, serpentine
from executive.io.heading import wait_for_filterpy
from executive.mission.lifecycle import MissionStatus

#: The last quarter's tick may cost this much more than the first's: "no growth", with noise.
MAX_GROWTH = 1.2
#: ... and the heap may hold this much more (a leak of even a few hundred bytes a tick shows over hours).
MAX_HEAP_GROWTH_MB = 1.0


def measure(legs: int, leg_m: float = 200.0, samples: int = 40) -> dict[str, float]:
    """Drive the whole mission; tick times (µs) and heap size (bytes) sampled ``samples`` times along it."""
    wait_for_filterpy()  # loaded in the background: its imports must not count as growth
    # no battery floor: an hour of driving drains the simulated battery, and the battery failsafe would (rightly) end it
    loop = SimLoop(rover_mission(serpentine(legs, leg_m, row_m=20.0), leg_timeout_s=600.0, battery_min_pct=None))
    rt = loop.runtime
    loop.connect()
    rt.mission_state.start()
    loop.run_until(lambda: rt.mission_state.leg_index >= 1, 600.0)
    gc.collect()
    tracemalloc.start()
    ticks: list[float] = []
    heap: list[int] = []
    vehicle_s = loop.clock.now()
    started = time.perf_counter()
    while rt.mission_state.status is MissionStatus.RUNNING:
        loop.step()
        t0 = time.perf_counter_ns()
        rt._tick_once()
        ticks.append((time.perf_counter_ns() - t0) / 1000.0)
        if len(ticks) % 500 == 0:
            heap.append(tracemalloc.get_traced_memory()[0])
    wall_s = time.perf_counter() - started
    tracemalloc.stop()
    quarter, hq = len(ticks) // 4, max(1, len(heap) // 4)
    return {
        "ticks": len(ticks),
        "vehicle_h": (loop.clock.now() - vehicle_s) / 3600.0,
        "wall_s": wall_s,
        "completed": rt.mission_state.status is MissionStatus.COMPLETED,
        "tick_first_us": median(ticks[:quarter]),
        "tick_last_us": median(ticks[-quarter:]),
        "heap_first_mb": median(heap[:hq]) / 1e6,
        "heap_last_mb": median(heap[-hq:]) / 1e6,
        "rss_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def run(legs: int = 50) -> list[Row]:
    m = measure(legs)
    tick_growth = m["tick_last_us"] / m["tick_first_us"]
    heap_growth = m["heap_last_mb"] - m["heap_first_mb"]
    where = f"{legs} legs, {m['vehicle_h']:.1f} h of vehicle time in {m['wall_s']:.0f} s, {m['ticks']} ticks, completed: {m['completed']}"
    return [
        Row(
            "soak",
            "soak: tick time, last / first quarter",
            tick_growth,
            "x",
            f"<= {MAX_GROWTH}x",
            m["completed"] and tick_growth <= MAX_GROWTH,
            f"{m['tick_first_us']:.0f} -> {m['tick_last_us']:.0f} µs median; {where}",
            m,
        ),
        Row(
            "soak",
            "soak: Python heap, last - first quarter",
            heap_growth,
            "MB",
            f"<= {MAX_HEAP_GROWTH_MB} MB",
            heap_growth <= MAX_HEAP_GROWTH_MB,
            f"{m['heap_first_mb']:.1f} -> {m['heap_last_mb']:.1f} MB (tracemalloc); peak RSS {m['rss_peak_mb']:.0f} MB",
            m,
        ),
    ]
