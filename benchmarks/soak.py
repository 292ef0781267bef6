"""Soak: long missions, memory and tick time must not grow.

In process: simulator and runtime on a manual clock, as fast as they go.

A rover drives a serpentine of ``legs`` 200 m legs (40 km, about 5 hours of vehicle time with the defaults).
The run is cut in quarters: the last quarter's median tick time, Python heap (the interpreter's
allocated blocks) and resident memory against the first quarter's, after the pre-flight, show
whether anything accumulates as a run goes on. The records are preallocated, so the benchmark's own
bookkeeping does not grow with the run (tracemalloc's did: ~10 MB of RSS over the same run).

Over real sockets: ``executive run --speedup 50`` as a subprocess (the built-in simulator over
loopback UDP, with a journal and a tlog being written, and a link or EKF loss every few minutes), its VmRSS sampled from /proc while it
drives ``process_legs`` legs; the last quarter of the route against the first.
"""

from __future__ import annotations

import gc
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from array import array
from pathlib import Path

import yaml

from benchmarks.common import Row, SimLoop, median, rover_mission, serpentine
from benchmarks.startup import ROOT, _status_kb
from executive.mission.lifecycle import MissionStatus
from executive.runtime.pacing import caps_logged
from executive.sensing.heading import wait_for_filterpy

#: The last quarter's tick may cost this much more than the first's: "no growth", with noise.
MAX_GROWTH = 1.2
#: ... the interpreter may hold this many more allocated blocks (one object leaked every 30 ticks would show) ...
MAX_BLOCK_GROWTH = 1000
#: ... and the resident memory this much more (a page here and there; a leak of a few bytes a tick shows over the run).
MAX_RSS_GROWTH_MB = 1.0
#: Memory is sampled every this many ticks.
SAMPLE_EVERY = 500
LEG_TIMEOUT_S = 600.0


def _rss_bytes() -> int:
    """Resident memory now (Linux: /proc/self/statm; 0 where that is not available)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize()
    except OSError:
        return 0


def measure(legs: int, leg_m: float = 200.0, rate_hz: float = 10.0, sample_every: int = SAMPLE_EVERY) -> dict[str, float]:
    """Drive the whole mission; tick times (µs), allocated blocks and RSS (bytes) along it."""
    wait_for_filterpy()  # loaded in the background: its imports must not count as growth
    # no battery floor: an hour of driving drains the simulated battery, and the battery failsafe would (rightly) end it
    mission = rover_mission(serpentine(legs, leg_m, row_m=20.0), leg_timeout_s=LEG_TIMEOUT_S, battery_min_pct=None)
    loop = SimLoop(mission, rate_hz=rate_hz)
    rt = loop.runtime
    loop.connect()
    rt.mission_state.start()
    loop.run_until(lambda: rt.mission_state.legs.leg_index >= 1, LEG_TIMEOUT_S)
    capacity = int(legs * LEG_TIMEOUT_S * rate_hz) + 1  # the leg timeout ends the mission before this
    ticks = array("d", bytes(8 * capacity))
    blocks = array("q", bytes(8 * (capacity // sample_every + 1)))
    rss = array("q", bytes(8 * (capacity // sample_every + 1)))
    n = samples = 0
    gc.collect()
    vehicle_s = loop.clock.now()
    started = time.perf_counter()
    while rt.mission_state.status is MissionStatus.RUNNING:
        loop.step()
        t0 = time.perf_counter_ns()
        rt._tick_once()
        ticks[n] = (time.perf_counter_ns() - t0) / 1000.0
        n += 1
        if n % sample_every == 0:
            blocks[samples], rss[samples] = sys.getallocatedblocks(), _rss_bytes()
            samples += 1
    wall_s = time.perf_counter() - started
    tq, sq = n // 4, max(1, samples // 4)
    return {
        "ticks": n,
        "vehicle_h": (loop.clock.now() - vehicle_s) / 3600.0,
        "wall_s": wall_s,
        "completed": rt.mission_state.status is MissionStatus.COMPLETED,
        "tick_first_us": median(ticks[:tq]),
        "tick_last_us": median(ticks[n - tq : n]),
        "blocks_first": median(blocks[:sq]),
        "blocks_last": median(blocks[samples - sq : samples]),
        "rss_first_mb": median(rss[:sq]) / 1e6,
        "rss_last_mb": median(rss[samples - sq : samples]) / 1e6,
        "rss_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def recurring_faults(first_s: float, every_s: float, until_s: float, for_s: float = 6.0) -> list[dict[str, object]]:
    """A link loss and an EKF position loss by turns, every ``every_s`` from ``first_s``: each a failsafe hold, then the leg resumed."""
    faults: list[dict[str, object]] = []
    at = first_s
    while at < until_s:
        if len(faults) % 2 == 0:
            faults.append({"kind": "link_loss", "at_s": at, "for_s": for_s, "direction": "both"})
        else:
            faults.append({"kind": "ekf_degradation", "at_s": at, "for_s": for_s, "variance": 1.2, "lose_position": True})
        at += every_s
    return faults


def measure_process(legs: int, speedup: float = 50.0, leg_m: float = 200.0, faults_every_s: float = 240.0) -> dict[str, float]:
    """Run ``executive run`` on a ``legs``-leg mission with recurring faults; VmRSS (kB) sampled along the route."""
    mission = rover_mission(serpentine(legs, leg_m, row_m=20.0), name="soak", leg_timeout_s=LEG_TIMEOUT_S, battery_min_pct=None)
    leg_s = leg_m * 0.45  # 200 m legs take ~90 s
    scale = leg_m / 200.0  # shorter legs, the faults as often per leg
    faults = recurring_faults(120.0 * scale, faults_every_s * scale, legs * leg_s)
    with tempfile.TemporaryDirectory(prefix="executive-soak-") as tmp:
        path, faults_path, log_path = Path(tmp) / "soak.yaml", Path(tmp) / "faults.yaml", Path(tmp) / "run.log"
        path.write_text(yaml.safe_dump(mission.model_dump(mode="json", exclude_defaults=True), sort_keys=False), encoding="utf-8")
        faults_path.write_text(yaml.safe_dump({"version": 1, "faults": faults}, sort_keys=False), encoding="utf-8")
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        cmd = [sys.executable, "-m", "executive", "run", str(path), "--speedup", f"{speedup:g}", "--socket", "none"]
        cmd += ["--journal", str(Path(tmp) / "journal.db"), "--tlog", str(Path(tmp) / "link.tlog"), "--faults", str(faults_path)]
        started = time.perf_counter()
        with open(log_path, "w", encoding="utf-8") as log:
            proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=log, text=True)
            assert proc.stdout is not None
            samples: list[tuple[int, int]] = []  # (leg, VmRSS kB), one per status line once on the route
            state, status = "", {}
            for line in proc.stdout:  # a status line every 0.5 s of vehicle time
                status = json.loads(line)
                state = status.get("state", state)
                if state == "RUNNING" and status.get("leg", 0) >= 2:  # past the pre-flight and the first leg
                    try:
                        samples.append((status["leg"], _status_kb(proc.pid)["VmRSS"]))
                    except (FileNotFoundError, KeyError):
                        break
            code = proc.wait()
        wall_s = time.perf_counter() - started
        tlog_mb = (Path(tmp) / "link.tlog").stat().st_size / 1e6 if (Path(tmp) / "link.tlog").exists() else 0.0
        text = log_path.read_text(encoding="utf-8")
        injected = sum(1 for f in faults if float(f["at_s"]) < status.get("t", 0.0))  # type: ignore[arg-type]
    quarter = max(1, len(samples) // 4)
    rss = [kb for _, kb in samples]
    return {
        "completed": code == 0 and state == "COMPLETED",
        "exit_code": code,
        "vehicle_h": status.get("t", 0.0) / 3600.0,
        "wall_s": wall_s,
        "samples": len(samples),
        "rss_first_mb": median(rss[:quarter]) * 1024 / 1e6,
        "rss_last_mb": median(rss[-quarter:]) * 1024 / 1e6,
        "tlog_mb": tlog_mb,
        "faults_injected": injected,
        "failsafes": text.count("failsafe ") - text.count("recovered after"),
        "recoveries": text.count("recovered after"),
        "capped_to": (caps_logged(text) or [speedup])[-1],
    }


def _capped(p: dict[str, float]) -> str:
    """How far the executive capped the speed-up on this machine, if it did."""
    return f" (capped to {p['capped_to']:g}x: the machine could not follow)" if p["capped_to"] < 50.0 else ""


def run(legs: int = 200, sample_every: int = SAMPLE_EVERY, process_legs: int = 30, leg_m: float = 200.0) -> list[Row]:
    """``legs`` legs of ``leg_m`` in process, ``process_legs`` of them over UDP; growth from the first quarter to the last."""
    p = measure_process(process_legs, leg_m=leg_m)
    process_growth = p["rss_last_mb"] - p["rss_first_mb"]
    m = measure(legs, leg_m=leg_m, sample_every=sample_every)
    tick_growth = m["tick_last_us"] / m["tick_first_us"]
    block_growth = m["blocks_last"] - m["blocks_first"]
    rss_growth = m["rss_last_mb"] - m["rss_first_mb"]
    where = f"{legs} legs of {leg_m:g} m, {m['vehicle_h']:.1f} h of vehicle time in {m['wall_s']:.0f} s, {m['ticks']} ticks"
    where += f", completed: {m['completed']}"
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
            block_growth,
            "blocks",
            f"<= {MAX_BLOCK_GROWTH}",
            block_growth <= MAX_BLOCK_GROWTH,
            f"{m['blocks_first']:.0f} -> {m['blocks_last']:.0f} allocated blocks (sys.getallocatedblocks)",
            m,
        ),
        Row(
            "soak",
            "soak: resident memory, last - first quarter",
            rss_growth,
            "MB",
            f"<= {MAX_RSS_GROWTH_MB} MB",
            rss_growth <= MAX_RSS_GROWTH_MB,
            f"{m['rss_first_mb']:.2f} -> {m['rss_last_mb']:.2f} MB (VmRSS); peak {m['rss_peak_mb']:.0f} MiB",
            m,
        ),
        Row(
            "soak",
            "soak over UDP (executive run): resident memory, last - first quarter",
            process_growth,
            "MB",
            f"<= {MAX_RSS_GROWTH_MB} MB",
            p["completed"] and process_growth <= MAX_RSS_GROWTH_MB,
            f"{p['rss_first_mb']:.2f} -> {p['rss_last_mb']:.2f} MB (VmRSS, {p['samples']} samples); {process_legs} legs, "
            f"{p['vehicle_h']:.1f} h of vehicle time at 50x{_capped(p)} in {p['wall_s']:.0f} s, journal and {p['tlog_mb']:.0f} MB tlog written; "
            f"{p['faults_injected']} faults injected (link loss, EKF loss by turns): {p['failsafes']} failsafes, {p['recoveries']} resumed; "
            f"completed: {p['completed']}",
            p,
        ),
    ]
