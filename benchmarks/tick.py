"""Tick cost, in figures that mean what they say.

(a) CPU share: each seed mission (``missions/*.yaml``) run whole on the lock-step simulation at
10 Hz, as ``executive run --journal --snapshots`` runs it (status JSON lines, the journal, the
snapshots recorded): the CPU time the executive's ticks took (thread CPU inside each tick and its
status line; the simulator runs between ticks, outside) over the vehicle time of the run, as a share
of one core. Target: at most 1 %.

(b) Where a tick goes, on a rover driving a 100-waypoint route over a byte link (pymavlink parses
what arrives, as on a real port), each part beside an honest floor measured on the same tick:

- reading (the MAVLink link and reader): pymavlink's ``parse_buffer`` alone on the same bytes;
- the tree: py_trees ticking a tree of the same shape (the same composites and decorators, each
  leaf a trivial behaviour returning what the real one returned that tick);
- the heading filter: filterpy's ``predict()``/``update(z, R, H)`` alone, the same calls;
- status and JSON (the status line): ``json.dumps`` of the same status document;
- recording (journal and snapshots): ``json.dumps`` of the same snapshot record and its write.

Also the full tick's median by route length (10 and 1000 waypoints): the cost does not grow with the mission.
Everything is timed in the thread's CPU time (``time.thread_time_ns``): on a shared machine the wall clock
counts the other processes' turns too.
"""

from __future__ import annotations

import io
import json
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

from benchmarks.common import Row, SimLoop, median, percentile, rover_mission, serpentine
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.observers.journal import Journal, journal_recorder
from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
from executive.operator.progress import Progress
from executive.sensing.heading import HeadingFilter, kalman_filter_class, wait_for_filterpy
from executive.testing import Lockstep
from executive.world.dialect import mavlink
from executive.world.vehicles import AutopilotName

MISSIONS = Path(__file__).resolve().parent.parent / "missions"
#: The executive may take this share of one core at 10 Hz.
MAX_CPU_SHARE = 0.01
#: The full tick's median at the longest mission may be this much more than at the shortest ("flat").
MAX_GROWTH = 1.25
RATE_HZ = 10.0


# -- (a) the CPU share of whole runs -------------------------------------------------------------------


def cpu_share(path: Path, limit_s: float = 3600.0) -> dict[str, float]:
    """Run the mission at ``path`` to its end on the lock-step simulation, recording as ``executive run`` would; the executive's CPU."""
    mission = load_mission(path)
    with tempfile.TemporaryDirectory() as tmp:
        status_lines = io.StringIO()  # not a terminal: JSON lines, as in a log or a service journal

        def recorders(clock: Any) -> dict[str, Any]:
            journal = Journal(Path(tmp) / "journal.db", clock)
            snapshots = SnapshotRecorder(Path(tmp) / "snapshots.jsonl")
            made.extend([journal, snapshots])
            return {"progress": Progress(status_lines, clock), "plugs": [journal_recorder(journal), snapshot_recorder(snapshots)]}

        made: list[Any] = []
        ticks: list[int] = []
        with Lockstep(mission, mission_dir=path.parent, rate_hz=RATE_HZ, options_for_clock=recorders) as sim:
            runtime = sim.runtime
            tick_once = runtime._tick_once

            def timed_tick_once() -> Any:
                t0 = time.thread_time_ns()
                outcome = tick_once()
                ticks.append(time.thread_time_ns() - t0)
                return outcome

            runtime._tick_once = timed_tick_once  # type: ignore[method-assign]
            outcome = sim.run_to_end(limit_s)
        for recorder in made:
            recorder.close()
    vehicle_s = len(ticks) / RATE_HZ
    cpu_s = sum(ticks) / 1e9
    return {
        "share": cpu_s / vehicle_s,
        "cpu_s": cpu_s,
        "vehicle_s": vehicle_s,
        "ticks": len(ticks),
        "median_us": median(ticks) / 1e3,
        "p99_us": percentile(ticks, 99) / 1e3,
        "completed": float(outcome.status is MissionStatus.COMPLETED),
    }


def seed_missions() -> list[Path]:
    return sorted(MISSIONS.glob("*.yaml"))


def cpu_rows(paths: Sequence[Path]) -> list[Row]:
    rows = []
    for path in paths:
        r = cpu_share(path)
        share = r["share"]
        rows.append(
            Row(
                "tick",
                f"CPU share at 10 Hz, {path.stem}",
                round(share * 100, 3),
                "% of a core",
                f"<= {MAX_CPU_SHARE * 100:g} %",
                share <= MAX_CPU_SHARE and bool(r["completed"]),
                f"{r['cpu_s'] * 1000:.0f} ms of CPU over {r['vehicle_s']:.0f} s of vehicle time, the whole run ({r['ticks']:.0f} ticks: "
                f"median {r['median_us']:.0f} µs, p99 {r['p99_us']:.0f} µs; status JSON, journal, snapshots on)"
                + ("" if r["completed"] else "; the mission did not complete"),
                r,
            )
        )
    return rows


# -- (b) where a tick goes, beside the floors -----------------------------------------------------------


class _BareKalman:
    """filterpy as a user calls it: ``predict()`` and ``update(z, R, H)`` on a 2-state ``KalmanFilter``, nothing of ours."""

    def __init__(self) -> None:
        # filterpy's KalmanFilter as the heading filter loads it (not the whole of filterpy, whose import pulls scipy.stats in:
        # 0.85 CPU-s of this benchmark's smoke test), and Q_discrete_white_noise(dim=2, dt=0.1, var=1.0) written out as it does
        self.kf = kalman_filter_class()(dim_x=2, dim_z=1)
        self.kf.F = np.array([[1.0, 0.1], [0.0, 1.0]])
        dt = 0.1
        self.kf.Q = np.array([[dt**4 / 4.0, dt**3 / 2.0], [dt**3 / 2.0, dt**2]])
        self.h = (np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]]))

    def replay(self, calls: list[tuple[float, ...]]) -> int:
        """Make the same predict/update calls (same measurements and variances); ns they took."""
        kf, h = self.kf, self.h
        t0 = time.thread_time_ns()
        for call in calls:
            if len(call) == 2:
                kf.predict()
            else:
                kf.update(call[0], R=call[1], H=h[int(call[2])])
        return time.thread_time_ns() - t0


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


class _Echo(py_trees.behaviour.Behaviour):
    """A trivial leaf: returns what the real leaf returned at this tick (SUCCESS if it was not ticked)."""

    def __init__(self, real: py_trees.behaviour.Behaviour) -> None:
        super().__init__(real.name)
        self.real = real

    def update(self) -> Status:
        status = self.real.status
        return status if status in (Status.SUCCESS, Status.FAILURE, Status.RUNNING) else Status.SUCCESS


def same_shape(node: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """A tree of the shape of ``node``'s: py_trees' own composites (same kind and memory) and pass-through decorators, echoing leaves."""
    if isinstance(node, py_trees.composites.Parallel):
        return py_trees.composites.Parallel(node.name, node.policy, [same_shape(c) for c in node.children])
    if isinstance(node, py_trees.composites.Sequence):
        return py_trees.composites.Sequence(node.name, node.memory, [same_shape(c) for c in node.children])
    if isinstance(node, py_trees.composites.Selector):
        return py_trees.composites.Selector(node.name, node.memory, [same_shape(c) for c in node.children])
    if isinstance(node, py_trees.decorators.Decorator):
        return py_trees.decorators.PassThrough(node.name, same_shape(node.decorated))
    return _Echo(node)


def _timed(target: Any, attribute: str, into: list[int]) -> None:
    """Replace ``target.attribute`` (a method) by one adding the ns each call takes to ``into[-1]``."""
    original = getattr(target, attribute)

    def timed(*args: Any, **kwargs: Any) -> Any:
        t0 = time.thread_time_ns()
        try:
            return original(*args, **kwargs)
        finally:
            into[-1] += time.thread_time_ns() - t0

    setattr(target, attribute, timed)


class _JsonCapture:
    """Stands in for a module's ``json``: ``dumps`` notes each object it writes (for the floor's own ``json.dumps``)."""

    def __init__(self) -> None:
        self.objects: list[Any] = []

    def dumps(self, obj: Any, **kwargs: Any) -> str:
        self.objects.append((obj, kwargs))
        return json.dumps(obj, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(json, name)


PARTS = ("reading", "tree", "heading filter", "status and JSON", "recording")


def breakdown(
    waypoints: int, ticks: int, warmup_ticks: int = 50, autopilot: AutopilotName = "ardupilot", snapshots_file: str = "snapshots.jsonl"
) -> dict[str, Any]:
    """Per tick, on a ``waypoints`` rover route of 50 m legs: each part's ns and its floor's; the full tick's.

    ``snapshots_file``'s suffix chooses the recorder's back end (``.mcap``: MCAP; its floor stays the JSON lines').
    """
    import executive.observers.snapshots as snapshots_module
    import executive.operator.progress as progress_module

    wait_for_filterpy()
    with tempfile.TemporaryDirectory() as tmp:
        journal_snapshots: list[Any] = []

        def plugs_for(clock: Any) -> list[Any]:
            journal = Journal(Path(tmp) / "journal.db", clock)
            snapshots = SnapshotRecorder(Path(tmp) / snapshots_file, clock=clock)
            journal_snapshots.extend([journal, snapshots])
            return [journal_recorder(journal), snapshot_recorder(snapshots)]

        loop = SimLoop(rover_mission(serpentine(waypoints, 50.0, row_m=500.0), autopilot=autopilot), byte_link=True, plugs_for=plugs_for)
        rt = loop.runtime
        status_stream = io.StringIO()
        progress = Progress(status_stream, loop.clock)
        loop.connect()
        rt.mission_state.start()
        assert rt.tree is not None
        guided = rt.link.autopilot.capabilities.guided_mode

        def tick() -> None:
            rt.tick()
            progress.update()

        loop.run_until(lambda: rt.mission_state.legs.leg_index >= 1 and rt.link.get("/vehicle/mode") == guided, 120.0, tick=tick)
        for _ in range(warmup_ticks):
            loop.step()
            tick()
        heading_filter = next(s for s in rt.readers if isinstance(s, HeadingFilter))
        if heading_filter._kf is None:
            raise RuntimeError("the heading filter has no Kalman filter yet: filterpy not loaded")
        parts: dict[str, list[int]] = {name: [] for name in PARTS}
        _timed(rt.link.reader, "drain", parts["reading"])
        _timed(rt.tree, "tick", parts["tree"])
        _timed(heading_filter, "service", parts["heading filter"])
        _timed(progress, "update", parts["status and JSON"])
        for observer in rt.observers:
            if type(observer).__name__ in ("_JournalRuns", "_SnapshotRuns"):
                _timed(observer, "ticked", parts["recording"])
        calls: list[tuple[float, ...]] = []
        _record_filter_calls(heading_filter, calls)
        bare = _BareKalman()
        mirror = py_trees.trees.BehaviourTree(same_shape(rt.tree.root))
        status_json, snapshot_json = _JsonCapture(), _JsonCapture()
        progress_module.json = status_json  # type: ignore[assignment]
        snapshots_module.json = snapshot_json  # type: ignore[assignment]
        floors: dict[str, list[int]] = {name: [] for name in PARTS}
        full: list[int] = []
        floor_file = open(Path(tmp) / "floor.jsonl", "w", encoding="utf-8")  # noqa: SIM115
        parser = mavlink.MAVLink(None)
        parser.robust_parsing = True
        messages = loop.messages
        feeds = [getattr(r, "_file", None) for r in journal_snapshots]
        feeds = [f for f in feeds if hasattr(f, "encoder_ns")]  # MCAP: its encoder thread's CPU, off the tick
        encoder_ns = sum(f.encoder_ns for f in feeds)
        try:
            for _ in range(ticks):
                datagrams = loop.step_bytes()
                for name in PARTS:
                    parts[name].append(0)
                calls.clear()
                status_json.objects.clear()
                snapshot_json.objects.clear()
                t0 = time.thread_time_ns()
                tick()
                full.append(time.thread_time_ns() - t0)
                # the floors, on the same tick's material, outside the tick's timing
                t0 = time.thread_time_ns()
                for datagram in datagrams:
                    parser.parse_buffer(datagram)
                floors["reading"].append(time.thread_time_ns() - t0)
                t0 = time.thread_time_ns()
                mirror.tick()
                floors["tree"].append(time.thread_time_ns() - t0)
                floors["heading filter"].append(bare.replay(calls))
                t0 = time.thread_time_ns()
                for obj, kwargs in status_json.objects:
                    json.dumps(obj, **kwargs)
                floors["status and JSON"].append(time.thread_time_ns() - t0)
                t0 = time.thread_time_ns()
                for obj, kwargs in snapshot_json.objects:
                    floor_file.write(json.dumps(obj, **kwargs) + "\n")
                floors["recording"].append(time.thread_time_ns() - t0)
        finally:
            progress_module.json = json  # type: ignore[assignment]
            snapshots_module.json = json  # type: ignore[assignment]
            floor_file.close()
            for recorder in journal_snapshots:
                recorder.close()
        encoder_ns = sum(f.encoder_ns for f in feeds) - encoder_ns
        if rt.mission_state.status is not MissionStatus.RUNNING or rt.mission_state.legs.leg_index >= waypoints:
            raise RuntimeError(f"the mission left its route during the benchmark: {rt.mission_state.status} {rt.mission_state.reason}")
        return {
            "parts": parts, "floors": floors, "full": full, "messages_per_tick": (loop.messages - messages) / ticks,
            "encoder_per_tick_ns": encoder_ns / ticks,
        }  # fmt: skip


FLOORS = {
    "reading": "pymavlink parse_buffer of the same bytes",
    "tree": "py_trees, a same-shape tree of trivial leaves",
    "heading filter": "filterpy predict/update alone",
    "status and JSON": "json.dumps of the same status",
    "recording": "json.dumps and write of the same record",
}


def breakdown_rows(waypoints: int, result: dict[str, Any], on: str) -> list[Row]:
    rows = []
    full = result["full"]
    rows.append(
        Row(
            "tick",
            f"full tick, {waypoints} waypoints{on}",
            round(median(full) / 1e3, 1),
            "µs median",
            "",
            None,
            f"p99 {percentile(full, 99) / 1e3:.0f} µs; {result['messages_per_tick']:.1f} msgs/tick over a byte link; "
            f"{median(full) / 1e3 * RATE_HZ / 1e4:.2f} % of a core at 10 Hz",
            {"full_median_us": median(full) / 1e3, "full_p99_us": percentile(full, 99) / 1e3},
        )
    )
    for name in PARTS:
        spent, floor = result["parts"][name], result["floors"][name]
        ratio = median([s / f for s, f in zip(spent, floor, strict=True) if f > 0]) if any(floor) else float("nan")
        rows.append(
            Row(
                "tick",
                f"tick part: {name}, {waypoints} waypoints{on}",
                round(median(spent) / 1e3, 1),
                "µs median",
                "",
                None,
                f"floor {median(floor) / 1e3:.1f} µs ({FLOORS[name]}): {ratio:.2f}x per tick (median); p99 {percentile(spent, 99) / 1e3:.0f} µs",
                {"median_us": median(spent) / 1e3, "floor_median_us": median(floor) / 1e3, "ratio": ratio},
            )
        )
    return rows


def mcap_row(waypoints: int, lines: dict[str, Any], ticks: int, warmup_ticks: int) -> Row:
    """The recording part with ``--snapshots FILE.mcap`` (issue 35: no slower than JSON lines), on the same mission and ticks.

    The tick's own CPU is judged (what delays the next tick); the encoder thread's, which turns the MAVLink messages and
    the vehicle's values into the file's messages between ticks, is reported beside it, and in the row's total.
    """
    mcap = breakdown(waypoints, ticks, warmup_ticks, snapshots_file="snapshots.mcap")
    spent, floor = median(mcap["parts"]["recording"]) / 1e3, median(lines["parts"]["recording"]) / 1e3
    encoder = mcap["encoder_per_tick_ns"] / 1e3
    mean_lines, mean_mcap = (sum(r["parts"]["recording"]) / len(r["parts"]["recording"]) / 1e3 for r in (lines, mcap))
    return Row(
        "tick",
        f"tick part: recording as MCAP, {waypoints} waypoints",
        round(spent, 1),
        "µs median",
        "<= JSON lines'",
        spent <= floor,
        f"JSON lines {floor:.1f} µs; p99 {percentile(mcap['parts']['recording'], 99) / 1e3:.0f} µs; the encoder thread {encoder:.0f} µs "
        f"a tick (mean; tick lines, MAVLink, fixes, poses): tick + encoder {mean_mcap + encoder:.0f} µs vs JSON lines {mean_lines:.0f} (means)",
        {"median_us": spent, "json_lines_median_us": floor, "encoder_mean_us": encoder, "total_mean_us": mean_mcap + encoder},
    )


def run(
    ticks: int = 1500, sizes: Sequence[int] = (10, 100, 1000), warmup_ticks: int = 50, autopilot: AutopilotName = "ardupilot",
    missions: Sequence[Path] | None = None,
) -> list[Row]:  # fmt: skip
    """(a) the CPU share of each seed mission (ArduPilot only: the seeds' firmware); (b) the breakdown at the middle size; growth."""
    on = "" if autopilot == "ardupilot" else f", {autopilot}"  # ArduPilot's rows keep their names
    rows = cpu_rows(seed_missions() if missions is None else missions) if autopilot == "ardupilot" else []
    results = {n: breakdown(n, ticks if n == sizes[len(sizes) // 2] else max(ticks // 3, 1), warmup_ticks, autopilot) for n in sizes}
    middle = sizes[len(sizes) // 2]
    rows += breakdown_rows(middle, results[middle], on)
    if autopilot == "ardupilot":
        rows.append(mcap_row(middle, results[middle], ticks, warmup_ticks))
    first, last = median(results[sizes[0]]["full"]) / 1e3, median(results[sizes[-1]]["full"]) / 1e3
    growth = last / first
    rows.append(
        Row(
            "tick",
            f"growth {sizes[0]} -> {sizes[-1]} waypoints{on}",
            round(growth, 2),
            "x",
            f"<= {MAX_GROWTH:g}x (flat)",
            growth <= MAX_GROWTH,
            f"full tick median {first:.0f} -> {last:.0f} µs",
        )
    )
    return rows
