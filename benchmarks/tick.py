"""Tick cost: the whole runtime tick (drain, blackboard, tree, commands) against the tree's own py_trees tick, by mission length."""

from __future__ import annotations

import time
from collections.abc import Sequence

from benchmarks.common import Row, SimLoop, median, percentile, rover_mission, serpentine
from executive.io.heading import HeadingFilter, wait_for_filterpy
from executive.mission.lifecycle import MissionStatus

#: The full tick may cost this much more than the bare tree tick.
MAX_RATIO = 1.5
#: ... and its median at the longest mission this much more than at the shortest ("flat").
MAX_GROWTH = 1.25


def measure(waypoints: int, ticks: int, warmup_ticks: int = 50) -> dict[str, float]:
    """Median and p99 (µs) of the full tick and of the tree tick inside it, driving a ``waypoints`` mission of 50 m legs.

    The legs are long enough that even the shortest mission is still on its route at the end: every
    size is measured in the same phase (a leg being driven, and now and then the next one starting).
    """
    wait_for_filterpy()  # the heading filter at work in every size (it loads in the background, ~0.7 s into a run)
    loop = SimLoop(rover_mission(serpentine(waypoints, 50.0, row_m=500.0)))
    rt = loop.runtime
    loop.connect()
    rt.mission_state.start()
    assert rt.tree is not None
    tree = rt.tree
    inner: list[int] = []
    tree_tick = tree.tick

    def timed_tree_tick() -> None:
        t0 = time.perf_counter_ns()
        tree_tick()
        inner.append(time.perf_counter_ns() - t0)

    tree.tick = timed_tree_tick  # type: ignore[method-assign]
    heading: list[int] = []  # the heading filter's share (filterpy): where the full tick's time goes
    heading_filter = next(s for s in rt.readers if isinstance(s, HeadingFilter))
    heading_service = heading_filter.service

    def timed_heading_service() -> None:
        t0 = time.perf_counter_ns()
        heading_service()
        heading.append(time.perf_counter_ns() - t0)

    heading_filter.service = timed_heading_service  # type: ignore[method-assign]
    # pre-flight (EKF, arming), then the route: the steady state of a mission is a leg being driven
    loop.run_until(lambda: rt.mission_state.leg_index >= 1 and rt._bb.get("/vehicle/mode") == "GUIDED", 120.0)
    for _ in range(warmup_ticks):
        loop.step()
        rt.tick()
    inner.clear()
    heading.clear()
    full: list[int] = []
    messages = loop.messages
    for _ in range(ticks):
        loop.step()
        t0 = time.perf_counter_ns()
        rt.tick()
        full.append(time.perf_counter_ns() - t0)
    if rt.mission_state.status is not MissionStatus.RUNNING or rt.mission_state.leg_index >= waypoints:
        raise RuntimeError(f"the mission left its route during the benchmark: {rt.mission_state.status} {rt.mission_state.reason}")
    if len(inner) != len(full):
        raise RuntimeError("the tree was not ticked once per runtime tick")
    return {
        "ratio": median([f / t for f, t in zip(full, inner, strict=True)]),
        "full_median_us": median(full) / 1e3,
        "full_p99_us": percentile(full, 99) / 1e3,
        "tree_median_us": median(inner) / 1e3,
        "tree_p99_us": percentile(inner, 99) / 1e3,
        "heading_median_us": median(heading) / 1e3,
        "ratio_without_heading": median([(f - h) / t for f, h, t in zip(full, heading, inner, strict=True)]),
        "messages_per_tick": (loop.messages - messages) / ticks,
        "legs_done": rt.mission_state.leg_index,
    }


def run(ticks: int = 1500, sizes: Sequence[int] = (10, 100, 1000), warmup_ticks: int = 50) -> list[Row]:
    """One row per mission length (full tick vs tree tick), and the growth from the shortest to the longest."""
    rows = []
    results = {n: measure(n, ticks, warmup_ticks) for n in sizes}
    for n, r in results.items():
        ratio = r["ratio"]
        rows.append(
            Row(
                "tick",
                f"full tick, {n} waypoints",
                round(r["full_median_us"], 1),
                "µs median",
                f"<= {MAX_RATIO:g}x tree tick",
                ratio <= MAX_RATIO,
                f"p99 {r['full_p99_us']:.0f} µs; tree tick {r['tree_median_us']:.0f} µs (p99 {r['tree_p99_us']:.0f}); "
                f"{ratio:.2f}x (median of full/tree per tick); {r['messages_per_tick']:.1f} msgs/tick; "
                f"heading filter {r['heading_median_us']:.0f} µs of it ({r['ratio_without_heading']:.2f}x without)",
                r,
            )
        )
    first, last = results[sizes[0]], results[sizes[-1]]
    growth = last["full_median_us"] / first["full_median_us"]
    rows.append(
        Row(
            "tick",
            f"growth {sizes[0]} -> {sizes[-1]} waypoints",
            round(growth, 2),
            "x",
            f"<= {MAX_GROWTH:g}x (flat)",
            growth <= MAX_GROWTH,
            f"full tick median {first['full_median_us']:.0f} -> {last['full_median_us']:.0f} µs",
        )
    )
    return rows
