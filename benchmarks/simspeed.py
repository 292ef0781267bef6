"""Simulator speed: a 1 km rover mission on the built-in simulator and the runtime in one process, as fast as it still completes.

As ``executive run MISSION --speedup X`` does it: the simulated vehicle serves a loopback UDP link
from its thread on a ScaledClock shared with the runtime, which ticks at 10 Hz of vehicle time.
Speed-ups are tried from the highest down; the figure is the highest at which the mission
completes every time (``runs`` runs) as it would in real time: COMPLETED, the link never lost,
and the runtime keeping its tick rate (at least 90 % of 10 ticks per second of vehicle time).
It is reported as vehicle time over wall time (set-up included, so a little under the speed-up);
the target applies to the speed-up.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Sequence

from benchmarks.common import HOME, Row, offset, rover_mission
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.lifecycle import MissionStatus
from executive.runtime.assembly import build_runtime
from executive.runtime.pacing import keeping_time
from executive.sim import SimServer
from executive.world.clock import ScaledClock

MIN_SPEEDUP = 50.0
MIN_TICK_FRACTION = 0.9


class _LinkLosses(logging.Handler):
    """Counts the reader's "link lost" warnings."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        if record.getMessage().startswith("link lost"):
            self.count += 1


def route(length_m: float) -> list[tuple[float, float]]:
    """A survey pattern ``length_m`` long: four lanes north and south (0.2 of it each, two legs per lane), 0.05 of it east between them."""
    lane, shift = 0.2 * length_m, 0.05 * length_m
    points, north, east = [], 0.0, 0.0
    for i in range(4):
        sign = 1.0 if i % 2 == 0 else -1.0
        for _ in range(2):
            north += sign * lane / 2
            points.append(offset(HOME[0], HOME[1], north, east))
        east += shift
        points.append(offset(HOME[0], HOME[1], north, east))
    return points


def run_once(speedup: float, length_m: float, ekf_ready_after_s: float, timeout_s: float) -> tuple[bool, float, float, int, str]:
    """Completed?, vehicle seconds, wall seconds, ticks and how it ended, for one run of ``Runtime.run`` at ``speedup``."""
    mission = rover_mission(route(length_m), ekf_ready_after_s=ekf_ready_after_s, leg_timeout_s=300.0)
    wall0 = time.perf_counter()
    clock = ScaledClock(speedup)
    with SimServer("rover", clock=clock, home=HOME, ekf_ready_after_s=ekf_ready_after_s) as sim:
        link = PymavlinkLink(sim.url_for_client)
        try:
            runtime = build_runtime(mission, link, clock)
            if not runtime.link.connect(10.0 * speedup):
                return False, clock.now(), time.perf_counter() - wall0, 0, "no heartbeat"
            watchdog = threading.Timer(timeout_s, runtime.request_stop, ("benchmark time limit",))
            watchdog.start()
            try:
                with keeping_time(runtime.pacer.late_after_s / speedup):  # as executive run does
                    outcome = runtime.run()
            finally:
                watchdog.cancel()
            vehicle_s = clock.now()
        finally:
            link.close()
    wall_s = time.perf_counter() - wall0
    if outcome.status is not MissionStatus.COMPLETED:
        return False, vehicle_s, wall_s, outcome.ticks, f"{outcome.status}: {outcome.reason}"
    return True, vehicle_s, wall_s, outcome.ticks, "COMPLETED"


def judge(speedup: float, length_m: float, ekf_ready_after_s: float, timeout_s: float) -> tuple[bool, float, float, int, str]:
    """:func:`run_once`, failed also when the link was lost or the runtime fell behind its tick rate."""
    losses = _LinkLosses()
    logger = logging.getLogger("executive.io.mavlink.reader")
    logger.addHandler(losses)
    propagate, logger.propagate = logger.propagate, False
    try:
        ok, vehicle_s, wall_s, ticks, why = run_once(speedup, length_m, ekf_ready_after_s, timeout_s)
    finally:
        logger.removeHandler(losses)
        logger.propagate = propagate
    rate = ticks / vehicle_s if vehicle_s > 0 else 0.0
    if ok and losses.count:
        ok, why = False, f"link lost {losses.count}x"
    if ok and rate < MIN_TICK_FRACTION * 10.0:
        ok, why = False, f"{rate:.1f} ticks/s"
    return ok, vehicle_s, wall_s, ticks, why


def run(
    speedups: Sequence[float] = (400.0, 200.0, 100.0, 50.0, 20.0), length_m: float = 1000.0, runs: int = 2, ekf_ready_after_s: float = 40.0
) -> list[Row]:
    """The highest speed-up that completes ``runs`` times out of ``runs``, and its vehicle time / wall time."""
    tried = []
    best: tuple[float, float, float, int] | None = None
    for speedup in sorted(speedups, reverse=True):
        results = []
        for _ in range(runs):  # a failure settles it: no need for the other runs
            results.append(judge(speedup, length_m, ekf_ready_after_s, timeout_s=60.0))
            if not results[-1][0]:
                break
        tried.append(f"{speedup:g}x: " + ", ".join("ok" if ok else why for ok, _, _, _, why in results))
        if len(results) == runs and all(ok for ok, *_ in results):
            vehicle = sum(r[1] for r in results)
            wall = sum(r[2] for r in results)
            best = (speedup, vehicle / wall, vehicle / runs, sum(r[3] for r in results) // runs)
            break
    if best is None:
        return [Row("sim", f"simulator speed ({length_m / 1000:g} km mission)", 0.0, "x real time", f">= {MIN_SPEEDUP:g}x", False, "; ".join(tried))]
    speedup, ratio, vehicle_s, ticks = best
    return [
        Row(
            "sim",
            f"simulator speed ({length_m / 1000:g} km mission)",
            round(ratio, 1),
            "x real time",
            f">= {MIN_SPEEDUP:g}x (reliable --speedup)",
            speedup >= MIN_SPEEDUP,
            f"--speedup {speedup:g} completes {runs}/{runs}: {vehicle_s:.0f} s of vehicle time, {ticks} ticks "
            f"({ticks / vehicle_s:.1f}/s of vehicle time); tried {'; '.join(tried)}",
            {"speedup": speedup, "vehicle_s": vehicle_s, "ticks": ticks, "tried": tried},
        )
    ]
