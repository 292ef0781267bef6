"""``executive import FILE -o MISSION.yaml`` and ``executive export MISSION --format plan|waypoints|btcpp``: other tools' files.

Both subcommands live here (``register`` adds the two): QGroundControl ``.plan`` and Mission Planner
``.waypoints`` files in and out, through :mod:`executive.mission.formats.plan_files`; a mission's tree as
BehaviorTree.CPP v4 XML (Groot2) in and out, through :mod:`executive.tree.formats.btcpp`.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.cli.common import load_or_report, print_errors
from executive.cli.examples import mission_file
from executive.mission.errors import MissionError, format_path
from executive.mission.errors import Path as MissionPath

if TYPE_CHECKING:
    import yaml

    from executive.mission.formats.plan_files import Exported

KINDS = ("rover", "boat", "sub", "vtol")


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``import`` and ``export`` subcommands."""
    imp = subparsers.add_parser(
        "import",
        help="make a mission file from a QGroundControl .plan or Mission Planner .waypoints file",
        description="Make a mission file from a QGroundControl .plan or a Mission Planner QGC WPL 110 (.waypoints) file, or a mission's "
        "tree from a BehaviorTree.CPP v4 XML file (Groot2). What a mission file cannot hold is reported on stderr, located, and listed "
        "at the top of the mission; errors go to stderr as FILE:LINE:COL: FIELD: message (exit 2).",
    )
    imp.add_argument("file", metavar="FILE", help="FILE.plan, FILE.waypoints, or FILE.xml (a BehaviorTree.CPP v4 / Groot2 tree)")
    imp.add_argument("-o", "--output", metavar="MISSION.yaml", help="write the mission here (default: stdout)")
    imp.add_argument(
        "--zones",
        metavar="FILE",
        action="append",
        default=[],
        help="a Mission Planner fence or rally file whose zones and rally points join the mission (.fen, .poly, .rally, or a QGC WPL 110 "
        "fence/rally plan); repeatable",
    )
    imp.add_argument("--vehicle", choices=KINDS, help="the vehicle kind (needed for .waypoints; a .plan's vehicleType otherwise)")
    imp.add_argument("--name", help="the mission's name (default: the file's name)")
    imp.add_argument("--auto-arm", action="store_true", help="arm the vehicle in pre-flight (auto_arm: true)")
    imp.add_argument(
        "--mission", metavar="MISSION.yaml", help="FILE.xml: the mission whose tree it replaces (default: write the tree: section alone)"
    )
    imp.set_defaults(func=run_import)
    exp = subparsers.add_parser(
        "export",
        help="write a mission as a QGroundControl .plan or Mission Planner .waypoints file, or its tree as BehaviorTree.CPP XML",
        description="Write a mission's route, home and geofence as a QGroundControl .plan or a Mission Planner QGC WPL 110 file "
        "(what the format cannot carry is reported on stderr), or its tree (written in the file) as BehaviorTree.CPP v4 XML with "
        "the node catalogue as its TreeNodesModel, for Groot2.",
    )
    exp.add_argument("mission", metavar="MISSION", type=mission_file, help="mission file (YAML), or an example's name")
    exp.add_argument("--format", choices=("plan", "waypoints", "btcpp"), help="output format (default: from the -o file's suffix)")
    exp.add_argument("-o", "--output", metavar="FILE", help="write here (default: stdout)")
    exp.set_defaults(func=run_export)


def run_import(args: argparse.Namespace) -> int:
    """Import, report what was not imported, write the mission; 2 on bad input."""
    from executive.mission.formats.plan_files import WAITS_FOR_ARMING, import_file

    if args.file.lower().endswith(".xml"):
        return _import_btcpp(args)
    try:
        imported = import_file(args.file, vehicle=args.vehicle, name=args.name, auto_arm=args.auto_arm, zone_files=args.zones)
    except MissionError as exc:
        print_errors(exc)
        return EXIT_BAD_INPUT
    for warning in imported.warnings:
        print(f"{warning} (warning)", file=sys.stderr)
    if not imported.mission.auto_arm:
        print(f"{args.file}: {WAITS_FOR_ARMING} (note)", file=sys.stderr)
    if not _write(args.output, imported.yaml_text, "import"):
        return EXIT_BAD_INPUT
    if args.output is not None:
        print(f"{args.output}: {len(imported.mission.waypoints)} waypoints, vehicle {imported.mission.vehicle}", file=sys.stderr)
    return EXIT_OK


def run_export(args: argparse.Namespace) -> int:
    """Export a mission; 2 if it is invalid or the format cannot be told."""
    from executive.mission.formats.plan_files import export_plan, export_waypoints
    from executive.tree.formats import recompose

    fmt = args.format or _format_from_suffix(args.output)
    if fmt is None:
        print("executive: export: --format plan|waypoints|btcpp is needed (or an -o file ending in .plan, .waypoints or .xml)", file=sys.stderr)
        return EXIT_BAD_INPUT
    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    if fmt == "btcpp":
        text, warnings = recompose.export_tree(args.mission, mission, _catalogue())
        for where, why in warnings:
            print(f"{args.mission}: tree {mission.tree}: {where}: {why} (warning)", file=sys.stderr)
        return EXIT_OK if _write(args.output, text, "export") else EXIT_BAD_INPUT
    exported = export_plan(mission) if fmt == "plan" else export_waypoints(mission)
    _report(args.mission, exported)
    return EXIT_OK if _write(args.output, exported.text, "export") else EXIT_BAD_INPUT


def _format_from_suffix(output: str | None) -> str | None:
    from executive.mission.formats.plan_files import WPL_SUFFIXES

    if output is None:
        return None
    suffix = os.path.splitext(output)[1].lower()
    return {".plan": "plan", ".xml": "btcpp"}.get(suffix) or ("waypoints" if suffix in WPL_SUFFIXES else None)


def _catalogue() -> Any:
    """The node catalogue (imported only for a tree: it imports every behaviour)."""
    from executive.tree.catalogue import catalogue

    return catalogue()


def _import_btcpp(args: argparse.Namespace) -> int:
    """A BehaviorTree.CPP file's tree as a mission's ``tree:``, alone or in place of ``--mission``'s; 2 on bad input."""
    import yaml

    from executive.admission.checks import load_mission_text
    from executive.tree.formats import btcpp

    try:
        tree = btcpp.import_tree(args.file, _catalogue())
    except MissionError as exc:
        print_errors(exc)
        return EXIT_BAD_INPUT
    if args.mission is None:
        return EXIT_OK if _write(args.output, yaml.safe_dump({"tree": tree}, sort_keys=False, allow_unicode=True), "import") else EXIT_BAD_INPUT
    if load_or_report(args.mission) is None:
        return EXIT_BAD_INPUT
    data = yaml.safe_load(Path(args.mission).read_text(encoding="utf-8")) | {"tree": tree}
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    try:
        load_mission_text(text, args.output or "(stdout)")
    except MissionError as exc:
        print_errors(exc)
        return EXIT_BAD_INPUT
    return EXIT_OK if _write(args.output, text, "import") else EXIT_BAD_INPUT


def _report(mission_file: str, exported: Exported) -> None:
    """What the format could not carry, located in the mission file: said once for every waypoint it concerns (at the first)."""
    if not exported.warnings:
        return
    locate = _locator(mission_file)
    alike: dict[tuple[MissionPath, str], list[MissionPath]] = {}  # the same loss in every waypoint: (its path, its index left out; why)
    for path, why in exported.warnings:
        index = next((i for i, p in enumerate(path) if isinstance(p, int)), None)
        alike.setdefault(((*path[:index], "*", *path[index + 1 :]) if index is not None else path, why), []).append(path)
    for (line, column), path, why, more in sorted((locate(paths[0]), paths[0], why, paths[1:]) for (_, why), paths in alike.items()):
        also = f"; the same for {len(more)} more ({_indexed(more)})" if more else ""
        print(f"{mission_file}:{line}:{column}: {format_path(path)}: {why}{also} (warning)", file=sys.stderr)


def _indexed(paths: list[MissionPath]) -> str:
    """``waypoints[1-7].name`` for paths alike but for one index (runs of consecutive indices as ranges)."""
    index = next(i for i, p in enumerate(paths[0]) if isinstance(p, int))
    numbers = sorted(int(p[index]) for p in paths)
    runs: list[list[int]] = []
    for n in numbers:
        if runs and n == runs[-1][-1] + 1:
            runs[-1].append(n)
        else:
            runs.append([n])
    spans = ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 1 else str(r[0]) for r in runs)
    head, tail = format_path(paths[0][:index]), format_path(paths[0][index + 1 :])
    return f"{head}[{spans}]" + (f".{tail}" if tail else "")


def _locator(mission_file: str) -> Callable[[MissionPath], tuple[int, int]]:
    """``locate(path) -> (line, column)`` in a (valid) mission file: of the value at ``path`` or of its nearest enclosing value."""
    import yaml

    marks: dict[MissionPath, tuple[int, int]] = {}

    def index(node: yaml.Node, path: MissionPath) -> None:
        marks[path] = (node.start_mark.line + 1, node.start_mark.column + 1)
        if isinstance(node, yaml.SequenceNode):
            for i, child in enumerate(node.value):
                index(child, (*path, i))
        elif isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                if isinstance(key, yaml.ScalarNode):
                    index(value, (*path, key.value))

    try:
        root = yaml.compose(Path(mission_file).read_text(encoding="utf-8"), Loader=yaml.SafeLoader)
        if root is not None:
            index(root, ())
    except (OSError, yaml.YAMLError):
        pass
    return lambda path: next((marks[path[:n]] for n in range(len(path), -1, -1) if path[:n] in marks), (1, 1))


def _write(output: str | None, text: str, command: str) -> bool:
    """Write ``text`` to ``output`` (stdout if None); False after saying why it could not."""
    if output is None:
        sys.stdout.write(text)
        return True
    try:
        Path(output).write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"executive: {command}: cannot write {output}: {exc.strerror or exc}", file=sys.stderr)
        return False
    return True
