"""``python -m benchmarks [--json FILE] [--only NAME ...]``: run the benchmarks, print the table (and write JSON)."""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial

from benchmarks import can_decode, efficiency, ingest, reaction, route_check, simspeed, soak, startup, tick
from benchmarks.common import Row

#: name -> the benchmark (each returns its rows); in the order they run.
BENCHMARKS: dict[str, Callable[[], list[Row]]] = {
    "tick": tick.run,
    "tick-px4": partial(tick.run, autopilot="px4"),  # issue 12: the rows hold for both back ends
    "ingest": ingest.run,
    "can": can_decode.run,
    "route": route_check.run,
    "reaction": reaction.run,
    "sim": simspeed.run,
    "startup": startup.run,
    "startup-px4": partial(startup.run, autopilot="px4"),
    "soak": soak.run,
    "efficiency": efficiency.run,
}


def _value(row: Row) -> str:
    return f"{row.value:,.0f}" if abs(row.value) >= 1000 else f"{row.value:g}"


def _load(row: Row) -> str:
    return "" if row.load is None else f"{row.load[0]:.1f}-{row.load[1]:.1f}"


def table(rows: Sequence[Row]) -> str:
    """The rows as an aligned text table: figure, target, PASS/FAIL, the load average while it ran, details."""
    header = ("benchmark", "figure", "target", "result", "load", "detail")
    lines = [
        (r.name, f"{_value(r)} {r.unit}", r.target, "" if r.passed is None else "PASS" if r.passed else "FAIL", _load(r), r.detail) for r in rows
    ]
    widths = [max(len(h), *(len(line[i]) for line in lines)) for i, h in enumerate(header[:-1])]
    out = ["  ".join(h.ljust(w) for h, w in zip(header[:-1], widths, strict=True)) + "  " + header[-1]]
    out.append("  ".join("-" * w for w in widths) + "  " + "-" * 6)
    out += ["  ".join(c.ljust(w) for c, w in zip(line[:-1], widths, strict=True)) + "  " + line[-1] for line in lines]
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument("--json", metavar="FILE", help="also write the rows (and the machine) as JSON")
    parser.add_argument("--only", nargs="+", choices=list(BENCHMARKS), metavar="NAME", help=f"run only these: {', '.join(BENCHMARKS)}")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)  # the simulated autopilot's pre-arm chatter is not a result
    rows: list[Row] = []
    started = time.perf_counter()
    for name in args.only or BENCHMARKS:
        t0 = time.perf_counter()
        print(f"running {name} ...", file=sys.stderr, flush=True)
        before = os.getloadavg()[0]
        produced = BENCHMARKS[name]()
        after = os.getloadavg()[0]
        for row in produced:
            row.load = (before, after)  # the 1-minute load average as the benchmark began and ended
        rows += produced
        print(f"  {name}: {time.perf_counter() - t0:.1f} s, load average {before:.1f} -> {after:.1f}", file=sys.stderr, flush=True)
    print(table(rows))
    total = time.perf_counter() - started
    failed = sum(r.passed is False for r in rows)
    print(f"\n{len(rows) - failed}/{len(rows)} rows meet their target ({total:.0f} s)")
    if args.json:
        machine = {
            "python": platform.python_version(),
            "machine": platform.machine(),
            "processor": platform.processor(),
            "system": platform.platform(),
            "cpus": os.cpu_count(),
        }
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"machine": machine, "seconds": round(total, 1), "rows": [r.to_dict() for r in rows]}, f, indent=2)
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
