"""Tick cost: the whole runtime tick (drain, blackboard, tree, heading filter, commands) against what it cannot do without, by mission length.

The baseline, measured side by side at every tick: the bare py_trees tick of the same tree (timed
inside the runtime's tick) plus bare filterpy ``predict()``/``update(z, R, H)`` calls, on a
``KalmanFilter`` of the same shape with filterpy's defaults, for the readings the heading filter took
in that tick (recorded during it, replayed after it, outside the full tick's timing).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from benchmarks.common import Row, SimLoop, median, percentile, rover_mission, serpentine
from executive.io.heading import HeadingFilter, wait_for_filterpy
from executive.mission.lifecycle import MissionStatus
from executive.vehicles import AutopilotName

#: The full tick may cost this much more than the bare tree tick plus the bare filterpy calls.
MAX_RATIO = 1.5
#: ... and its median at the longest mission this much more than at the shortest ("flat").
MAX_GROWTH = 1.25


class _BareKalman:
    """filterpy as a user calls it: ``predict()`` and ``update(z, R, H)`` on a 2-state ``KalmanFilter``, nothing of ours."""

    def __init__(self) -> None:
        from filterpy.common import Q_discrete_white_noise
        from filterpy.kalman import KalmanFilter

        self.kf = KalmanFilter(dim_x=2, dim_z=1)
        self.kf.F = np.array([[1.0, 0.1], [0.0, 1.0]])
        self.kf.Q = Q_discrete_white_noise(dim=2, dt=0.1, var=1.0)
        self.h = (np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]]))

    def replay(self, calls: list[tuple[float, ...]]) -> int:
        """Make the same predict/update calls (same measurements and variances); ns they took."""
        kf, h = self.kf, self.h
        t0 = time.perf_counter_ns()
        for call in calls:
            if len(call) == 2:
                kf.predict()
            else:
                kf.update(call[0], R=call[1], H=h[int(call[2])])
        return time.perf_counter_ns() - t0


def _record_filter_calls(heading_filter: HeadingFilter, calls: list[tuple[float, ...]]) -> None:
    """Note each predict/update the heading filter makes (its Kalman filter exists once filterpy is in)."""
    kalman = heading_filter._kf
    predict, update = kalman.predict, kalman.update

    def recorded_predict(dt: float, var: float) -> None:
        calls.append((dt, var))
        predict(dt, var)

    def recorded_update(z: float, r: float, i: int) -> None:
        calls.append((z, r, i))
        update(z, r, i)

    kalman.predict = recorded_predict  # type: ignore[method-assign]
    kalman.update = recorded_update  # type: ignore[method-assign]


def measure(waypoints: int, ticks: int, warmup_ticks: int = 50, autopilot: AutopilotName = "ardupilot") -> dict[str, float]:
    """Median and p99 (µs) of the full tick and of the tree tick inside it, driving a ``waypoints`` mission of 50 m legs on ``autopilot``.

    The legs are long enough that even the shortest mission is still on its route at the end: every
    size is measured in the same phase (a leg being driven, and now and then the next one starting).
    """
    wait_for_filterpy()  # the heading filter at work in every size (it loads in the background, ~0.7 s into a run)
    loop = SimLoop(rover_mission(serpentine(waypoints, 50.0, row_m=500.0), autopilot=autopilot))
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
    guided = rt.autopilot.capabilities.guided_mode  # GUIDED; OFFBOARD on PX4
    loop.run_until(lambda: rt.mission_state.leg_index >= 1 and rt._bb.get("/vehicle/mode") == guided, 120.0)
    for _ in range(warmup_ticks):
        loop.step()
        rt.tick()
    if heading_filter._kf is None:
        raise RuntimeError("the heading filter has no Kalman filter yet: filterpy not loaded")
    calls: list[tuple[float, ...]] = []
    _record_filter_calls(heading_filter, calls)
    bare = _BareKalman()
    inner.clear()
    heading.clear()
    full: list[int] = []
    bare_kf: list[int] = []
    kf_calls = 0
    messages = loop.messages
    for _ in range(ticks):
        loop.step()
        calls.clear()
        t0 = time.perf_counter_ns()
        rt.tick()
        full.append(time.perf_counter_ns() - t0)
        bare_kf.append(bare.replay(calls))
        kf_calls += len(calls)
    if rt.mission_state.status is not MissionStatus.RUNNING or rt.mission_state.leg_index >= waypoints:
        raise RuntimeError(f"the mission left its route during the benchmark: {rt.mission_state.status} {rt.mission_state.reason}")
    if len(inner) != len(full):
        raise RuntimeError("the tree was not ticked once per runtime tick")
    baseline = [t + k for t, k in zip(inner, bare_kf, strict=True)]
    return {
        "ratio": median([f / b for f, b in zip(full, baseline, strict=True)]),
        "ratio_to_tree": median([f / t for f, t in zip(full, inner, strict=True)]),
        "baseline_median_us": median(baseline) / 1e3,
        "bare_filterpy_median_us": median(bare_kf) / 1e3,
        "filterpy_calls_per_tick": kf_calls / ticks,
        "full_median_us": median(full) / 1e3,
        "full_p99_us": percentile(full, 99) / 1e3,
        "tree_median_us": median(inner) / 1e3,
        "tree_p99_us": percentile(inner, 99) / 1e3,
        "heading_median_us": median(heading) / 1e3,
        "ratio_without_heading": median([(f - h) / t for f, h, t in zip(full, heading, inner, strict=True)]),
        "messages_per_tick": (loop.messages - messages) / ticks,
        "legs_done": rt.mission_state.leg_index,
    }


def run(ticks: int = 1500, sizes: Sequence[int] = (10, 100, 1000), warmup_ticks: int = 50, autopilot: AutopilotName = "ardupilot") -> list[Row]:
    """One row per mission length (full tick vs tree tick), and the growth from the shortest to the longest, on ``autopilot``'s back end."""
    rows = []
    results = {n: measure(n, ticks, warmup_ticks, autopilot) for n in sizes}
    on = "" if autopilot == "ardupilot" else f", {autopilot}"  # ArduPilot's rows keep their names
    for n, r in results.items():
        ratio = r["ratio"]
        rows.append(
            Row(
                "tick",
                f"full tick, {n} waypoints{on}",
                round(r["full_median_us"], 1),
                "µs median",
                f"<= {MAX_RATIO:g}x (bare tree tick + bare filterpy)",
                ratio <= MAX_RATIO,
                f"{ratio:.2f}x (median of full/baseline per tick); p99 {r['full_p99_us']:.0f} µs; baseline {r['baseline_median_us']:.0f} µs: "
                f"tree tick {r['tree_median_us']:.0f} µs (p99 {r['tree_p99_us']:.0f}) + bare filterpy {r['bare_filterpy_median_us']:.0f} µs "
                f"({r['filterpy_calls_per_tick']:.1f} calls/tick); {r['ratio_to_tree']:.2f}x the tree alone; "
                f"{r['messages_per_tick']:.1f} msgs/tick; heading filter {r['heading_median_us']:.0f} µs of it",
                r,
            )
        )
    first, last = results[sizes[0]], results[sizes[-1]]
    growth = last["full_median_us"] / first["full_median_us"]
    rows.append(
        Row(
            "tick",
            f"growth {sizes[0]} -> {sizes[-1]} waypoints{on}",
            round(growth, 2),
            "x",
            f"<= {MAX_GROWTH:g}x (flat)",
            growth <= MAX_GROWTH,
            f"full tick median {first['full_median_us']:.0f} -> {last['full_median_us']:.0f} µs",
        )
    )
    return rows
