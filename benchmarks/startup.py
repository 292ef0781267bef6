"""Start-up and memory: ``executive run`` as a subprocess, from launch to its first tick, and its resident memory while it runs.

The first tick is the first status JSON line on stdout (the runtime writes one after every tick
when it is due, and the first at once). Memory is the process's VmRSS (sampled) and VmHWM (its
peak) from /proc while it drives the rover square on the built-in simulator, against the floor
the mandated libraries set, measured beside it: VmHWM of a bare interpreter that imports py_trees,
pymavlink's ardupilotmega dialect, can, yaml and filterpy's KalmanFilter as the executive loads it
(numpy and scipy.linalg with it; not the rest of filterpy, nor scipy.stats).
"""

from __future__ import annotations

import json
import os
import selectors
import signal
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.common import Row, median
from executive.world.vehicles import AutopilotName

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "rover_square.yaml"
MAX_FIRST_TICK_S = 1.0
#: A run may use this much more than the floor.
MAX_ABOVE_FLOOR_MB = 16.0
FLOOR_IMPORTS = (
    "import py_trees, can, yaml\nfrom pymavlink.dialects.v20 import ardupilotmega\n"
    "from executive.sensing.heading import kalman_filter_class\nkalman_filter_class()"
)


def _status_kb(pid: int) -> dict[str, int]:
    """VmRSS and VmHWM of a process, kB."""
    values = {}
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            name, _, rest = line.partition(":")
            if name in ("VmRSS", "VmHWM"):
                values[name] = int(rest.split()[0])
    return values


def floor_kb() -> int:
    """VmHWM (kB) of a bare interpreter once it has imported the mandated libraries."""
    code = f"{FLOOR_IMPORTS}\nprint(open('/proc/self/status').read())"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True, timeout=60).stdout
    return next(int(line.split()[1]) for line in out.splitlines() if line.startswith("VmHWM:"))


def run_once(sample_s: float, speedup: float = 20.0, autopilot: AutopilotName = "ardupilot") -> tuple[float, int, int]:
    """Seconds to the first tick, then the largest VmRSS sampled and VmHWM (kB) over ``sample_s`` of running on ``autopilot`` (built-in simulator)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, "-m", "executive", "run", str(MISSION), "--speedup", str(speedup), "--socket", "none", "--autopilot", autopilot]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    assert proc.stdout is not None
    try:
        first = proc.stdout.readline()
        first_tick_s = time.perf_counter() - t0
        if not first:
            raise RuntimeError(f"executive run exited ({proc.wait()}) before its first tick")
        json.loads(first)  # a status line, not something else
        rss = hwm = 0
        selector = selectors.DefaultSelector()
        selector.register(proc.stdout, selectors.EVENT_READ)
        end = time.perf_counter() + sample_s
        while time.perf_counter() < end and proc.poll() is None:
            try:
                kb = _status_kb(proc.pid)
            except FileNotFoundError:
                break
            rss, hwm = max(rss, kb.get("VmRSS", 0)), max(hwm, kb.get("VmHWM", 0))
            for key, _ in selector.select(timeout=0.05):  # keep the pipe drained
                key.fileobj.readline()  # type: ignore[union-attr]
        return first_tick_s, rss, hwm
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


def run(runs: int = 3, sample_s: float = 120.0, autopilot: AutopilotName = "ardupilot") -> list[Row]:
    """Median time to the first tick over ``runs`` launches; memory over the first run (to its end, at most ``sample_s`` s) against the floor.

    ``autopilot``: the back end and the built-in simulator's firmware (``--autopilot``).
    """
    floor_mb = floor_kb() / 1024.0
    results = [run_once(sample_s if i == 0 else 0.0, autopilot=autopilot) for i in range(runs)]
    on = "" if autopilot == "ardupilot" else f", {autopilot}"  # ArduPilot's rows keep their names
    first = [r[0] for r in results]
    rss_mb, hwm_mb = results[0][1] / 1024.0, results[0][2] / 1024.0
    return [
        Row(
            "startup",
            f"start-up: `executive run` to first tick{on}",
            round(median(first), 3),
            "s median",
            f"<= {MAX_FIRST_TICK_S:g} s",
            median(first) <= MAX_FIRST_TICK_S,
            f"{runs} launches: {', '.join(f'{x:.2f}' for x in first)} s (rover_square, built-in simulator)",
            {"first_tick_s": first},
        ),
        Row(
            "startup",
            f"memory during a run (VmHWM){on}",
            round(hwm_mb, 1),
            "MB peak",
            f"<= floor + {MAX_ABOVE_FLOOR_MB:g} MB",
            hwm_mb <= floor_mb + MAX_ABOVE_FLOOR_MB,
            f"floor {floor_mb:.1f} MB (a bare interpreter importing py_trees, pymavlink's ardupilotmega, can, yaml, filterpy's KalmanFilter); "
            f"{hwm_mb - floor_mb:+.1f} MB above it; VmRSS up to {rss_mb:.1f} MB (rover_square to its end at --speedup 20, at most {sample_s:g} s)",
            {"vmrss_mb": rss_mb, "vmhwm_mb": hwm_mb, "floor_mb": floor_mb},
        ),
    ]
