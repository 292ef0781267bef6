"""``executive validate MISSION...``: check mission files without running them; a directory stands for its ``*.yaml`` files.

A file is refused as ``executive run`` would refuse it, in the same words: the file itself and
its tree, instrument and plugins (:func:`executive.admission.checks.load_mission`), then what run refuses
of the mission on the built-in simulator (``--real-vehicle``: as with ``run --mavlink``) and, with
``--autopilot``, that firmware (:func:`executive.cli.run_checks.check_mission`). The installed
plugins (trees, behaviours, instruments) are checked too: one that cannot be loaded is named with
its error (at the ``tree:`` line of a mission that uses it), and the exit is 2.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from executive.cli import EXIT_BAD_INPUT, EXIT_OK, BadInput
from executive.cli.examples import mission_file
from executive.mission.errors import FieldError, MissionError


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``validate`` subcommand."""
    parser = subparsers.add_parser(
        "validate", help="check mission files", description="Check mission files; errors go to stderr as FILE:LINE:COL: FIELD: message."
    )
    parser.add_argument(
        "missions",
        nargs="+",
        metavar="MISSION",
        type=mission_file,
        help="mission file (YAML), a directory (every *.yaml in it, by name), or an example's name",
    )
    parser.add_argument("--json", action="store_true", help="print a JSON list of results on stdout instead")
    parser.add_argument(
        "--autopilot", choices=("ardupilot", "px4"), help="check the missions against this autopilot firmware, as `run --autopilot` does"
    )
    parser.add_argument(
        "--real-vehicle",
        action="store_true",
        help="check the missions as `run --mavlink` does (a real vehicle: samples from a real instrument), not on the built-in simulator",
    )
    parser.set_defaults(func=run)


def mission_files(path: str) -> list[str]:
    """``path`` itself, or for a directory (a mission list) every ``*.yaml`` file in it, sorted by name; not its subdirectories."""
    if not os.path.isdir(path):
        return [path]
    return sorted(str(p) for p in Path(path).glob("*.yaml") if p.is_file())


def run(args: argparse.Namespace) -> int:
    """Validate every file named, and every mission file of every directory named; exit 0 if all are good, 2 if any is not."""
    from executive.admission.checks import plugin_problems

    results: list[dict[str, Any]] = []
    for named in args.missions:
        files = mission_files(named)
        if not files:
            empty = FieldError(named, 1, 1, "(directory)", "no mission files (*.yaml) in this directory")
            results.append({"file": named, "ok": False, "errors": [asdict(empty)]})
            if not args.json:
                print(empty, file=sys.stderr)
        for path in files:
            _validate(path, args, results)
    said = " ".join(e["message"] for r in results for e in r.get("errors", ()))
    for broken in plugin_problems():
        if broken.plugin not in said:  # not already named at a mission's tree: line
            results.append({"plugin": broken.plugin, "ok": False, "error": str(broken)})
            if not args.json:
                print(f"executive: validate: {broken}", file=sys.stderr)
    if args.json:
        print(json.dumps(results, indent=2))
    return EXIT_OK if all(r["ok"] for r in results) else EXIT_BAD_INPUT


def _validate(path: str, args: argparse.Namespace, results: list[dict[str, Any]]) -> None:
    from executive.admission.checks import load_mission
    from executive.cli.run_checks import check_mission
    from executive.mission.model import tree_name
    from executive.mission.rules import waits_for_the_vehicle
    from executive.sensing.energy import planned

    try:
        mission = load_mission(path)
        check_mission(path, mission, autopilot=args.autopilot, simulator=not args.real_vehicle)
    except MissionError as exc:
        results.append({"file": path, "ok": False, "errors": [asdict(e) for e in exc.errors]})
        if not args.json:
            print("\n".join(map(str, exc.errors)), file=sys.stderr)
        return
    except BadInput as exc:  # run's refusal, in its words
        results.append({"file": path, "ok": False, "refused": str(exc)})
        if not args.json:
            print(f"{path}: {exc}", file=sys.stderr)
        return
    tree = tree_name(mission) or "(composed in the file)"
    result: dict[str, object] = {"file": path, "ok": True, "waypoints": len(mission.waypoints), "vehicle": mission.vehicle, "tree": tree}
    energy = planned(mission)
    said = None if energy is None else energy if isinstance(energy, str) else f"{energy.figures()} on a full pack, the kind's seeds"
    if said is not None:
        result["energy"] = said
    waits = waits_for_the_vehicle(mission)
    if waits:
        result["warnings"] = [f"no home: checked only at start, against the vehicle's position: {'; '.join(waits)}"]
    results.append(result)
    if not args.json:
        count = len(mission.waypoints)
        print(
            f"{path}: ok ({count} waypoint{'' if count == 1 else 's'}, vehicle {mission.vehicle}, tree {tree})"
            + (f"; energy: {said}" if said else "")
        )
        for warning in result.get("warnings", ()):
            print(f"{path}: warning: {warning}", file=sys.stderr)
