"""``executive validate MISSION...``: check mission files without running them."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from typing import Any

from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.mission.errors import MissionError
from executive.mission.loader import load_mission


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``validate`` subcommand."""
    parser = subparsers.add_parser(
        "validate", help="check mission files", description="Check mission files; errors go to stderr as FILE:LINE:COL: FIELD: message."
    )
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file (YAML)")
    parser.add_argument("--json", action="store_true", help="print a JSON list of results on stdout instead")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Validate every file named; exit 0 if all are good, 2 if any is not."""
    results: list[dict[str, Any]] = []
    for path in args.missions:
        try:
            mission = load_mission(path)
        except MissionError as exc:
            results.append({"file": path, "ok": False, "errors": [asdict(e) for e in exc.errors]})
            if not args.json:
                print("\n".join(map(str, exc.errors)), file=sys.stderr)
            continue
        results.append({"file": path, "ok": True, "waypoints": len(mission.waypoints), "vehicle": mission.vehicle, "tree": mission.tree})
        if not args.json:
            print(f"{path}: ok ({len(mission.waypoints)} waypoints, vehicle {mission.vehicle}, tree {mission.tree})")
    if args.json:
        print(json.dumps(results, indent=2))
    return EXIT_OK if all(r["ok"] for r in results) else EXIT_BAD_INPUT
