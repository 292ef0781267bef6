"""``executive validate MISSION...``: check mission files without running them; a directory stands for its ``*.yaml`` files.

The installed plugins (trees and behaviours) are checked too: one that cannot be loaded is named
with its error (at the ``tree:`` line of a mission that uses it), and the exit is 2.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from executive import plugins
from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.mission.errors import FieldError, MissionError
from executive.mission.loader import load_mission
from executive.mission.model import tree_name


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``validate`` subcommand."""
    parser = subparsers.add_parser(
        "validate", help="check mission files", description="Check mission files; errors go to stderr as FILE:LINE:COL: FIELD: message."
    )
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file (YAML), or a directory: every *.yaml in it, by name")
    parser.add_argument("--json", action="store_true", help="print a JSON list of results on stdout instead")
    parser.set_defaults(func=run)


def mission_files(path: str) -> list[str]:
    """``path`` itself, or for a directory (a mission list) every ``*.yaml`` file in it, sorted by name; not its subdirectories."""
    if not os.path.isdir(path):
        return [path]
    return sorted(str(p) for p in Path(path).glob("*.yaml") if p.is_file())


def run(args: argparse.Namespace) -> int:
    """Validate every file named, and every mission file of every directory named; exit 0 if all are good, 2 if any is not."""
    results: list[dict[str, Any]] = []
    for named in args.missions:
        files = mission_files(named)
        if not files:
            empty = FieldError(named, 1, 1, "(directory)", "no mission files (*.yaml) in this directory")
            results.append({"file": named, "ok": False, "errors": [asdict(empty)]})
            if not args.json:
                print(empty, file=sys.stderr)
        for path in files:
            _validate(path, args.json, results)
    said = " ".join(e["message"] for r in results for e in r.get("errors", ()))
    for broken in plugins.problems():
        if broken.plugin not in said:  # not already named at a mission's tree: line
            results.append({"plugin": broken.plugin, "ok": False, "error": str(broken)})
            if not args.json:
                print(f"executive: validate: {broken}", file=sys.stderr)
    if args.json:
        print(json.dumps(results, indent=2))
    return EXIT_OK if all(r["ok"] for r in results) else EXIT_BAD_INPUT


def _validate(path: str, as_json: bool, results: list[dict[str, Any]]) -> None:
    try:
        mission = load_mission(path)
    except MissionError as exc:
        results.append({"file": path, "ok": False, "errors": [asdict(e) for e in exc.errors]})
        if not as_json:
            print("\n".join(map(str, exc.errors)), file=sys.stderr)
        return
    tree = tree_name(mission) or "(composed in the file)"
    results.append({"file": path, "ok": True, "waypoints": len(mission.waypoints), "vehicle": mission.vehicle, "tree": tree})
    if not as_json:
        print(f"{path}: ok ({len(mission.waypoints)} waypoints, vehicle {mission.vehicle}, tree {tree})")
