"""``executive report DB``: what a run did - state changes, legs, samples, events - from the journal.

Waypoints are numbered from 1 here and in ``--json`` (``waypoint``), as on the status line, in its
JSON lines (``leg`` of ``legs``) and in ``executive ctl``: leg N is the way to waypoint N.
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from executive.cli import EXIT_BAD_INPUT, EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="what a recorded run did: state changes, legs, samples, events")
    p.add_argument(
        "journal", metavar="DB", help="the journal written by `executive run --journal DB` (or an MCAP recording, `--snapshots FILE.mcap`)"
    )
    p.add_argument("--run", type=int, help="which run (default: the last)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=main)


def _when(wall: float | None) -> str:
    return "-" if wall is None else datetime.fromtimestamp(wall, UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def _heading(row: dict[str, Any]) -> str:
    """``heading for waypoint 3 'inlet' of 8``, or ``every waypoint reached (8 of 8)`` once past the last (``no waypoint yet``: an empty route)."""
    if not row["waypoints"]:
        return "no waypoint yet (an empty route)"
    if row["waypoint"] is None:
        return f"every waypoint reached ({row['waypoints']} of {row['waypoints']})"
    name = f" {row['name']!r}" if row.get("name") else ""
    return f"heading for waypoint {row['waypoint']}{name} of {row['waypoints']}"


def render(report: dict[str, Any]) -> str:
    """The report for a person."""
    lines = [
        f"run {report['id']}: mission {report['mission']!r} ({report['vehicle']})"
        + (f", resuming run {report['resumed_from']}" if report["resumed_from"] else ""),
        f"  started {_when(report['started'])}, ended {_when(report['ended'])}: {report['outcome'] or 'UNFINISHED'} {report['reason'] or ''}".rstrip(),  # noqa: E501
        "state changes:",
        *(f"  [{t['t']:9.1f} s] {t['before']} -> {t['after']}: {t['reason']}" for t in report["transitions"]),
        "legs:",
        *(f"  [{leg['t']:9.1f} s] {_heading(leg)}" for leg in report["legs"]),
        f"samples ({len(report['samples'])}):",
    ]
    for sample in report["samples"]:
        reads: dict[str, list[float]] = {}
        for read in sample["reads"]:
            reads.setdefault(f"{read['sensor']} ({read['unit']})" if read["unit"] else read["sensor"], []).append(read["value"])
        summary = ", ".join(f"{name} {sum(v) / len(v):.2f}" for name, v in reads.items())
        missing = ", ".join(sample.get("missing") or ())
        lines.append(
            f"  waypoint {sample['waypoint']} at {sample['lat']:.7f}, {sample['lon']:.7f}: {len(sample['reads'])} reads, mean {summary}"
            + (f" ({sample['instrument']})" if sample.get("instrument") else "")
            + (f": PARTIAL, no reading of {missing}" if sample.get("partial") else f"; no reading of {missing}" if missing else "")
        )
    if report.get("routes"):
        lines.append(f"route edits ({len(report['routes'])}):")
        lines += [f"  [{r['t']:9.1f} s] {r['waypoints']} waypoints, {_heading(r)}: {r['reason']}" for r in report["routes"]]
    energy = [e for e in report["events"] if e["kind"] == "energy"]
    if energy:  # each leg's estimate (executive.sensing.energy): where the energy went, leg by leg
        lines.append(f"energy ({len(energy)} estimates):")
        lines += [f"  [{e['t']:9.1f} s] {e['text']}" for e in energy]
    lines.append(f"events ({len(report['events'])}):")
    lines += [f"  [{e['t']:9.1f} s] {e['kind']}: {e['text']}" for e in report["events"]]
    return "\n".join(lines)


def main(args: argparse.Namespace) -> int:
    from executive.observers.journal import Journal
    from executive.world.clock import ScaledClock

    # a database has no line and column to point at: the file and why, as the other commands say of what is not a text file
    if not Path(args.journal).is_file():
        print(f"executive: report: {args.journal}: no such journal", file=sys.stderr)
        return EXIT_BAD_INPUT
    with open(args.journal, "rb") as f:
        if f.read(8) == b"\x89MCAP0\r\n":
            return _from_mcap(args)
    try:
        journal = Journal(args.journal, ScaledClock())
        try:
            report = journal.report(args.run)
        finally:
            journal.close()
    except sqlite3.DatabaseError as exc:
        print(f"executive: report: {args.journal}: not a journal: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except LookupError as exc:  # its message names the journal
        print(f"executive: report: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(json.dumps(report, indent=2) if args.json else render(report))
    return EXIT_OK


def _from_mcap(args: argparse.Namespace) -> int:
    """The report of a run recorded with ``run --snapshots FILE.mcap`` (no samples nor route edits: the journal has them)."""
    from executive.observers.mcap.report import report

    try:
        found = report(Path(args.journal), args.run)
    except LookupError as exc:
        print(f"executive: report: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(json.dumps(found, indent=2) if args.json else render(found))
    return EXIT_OK
