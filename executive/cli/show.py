"""``executive show MISSION``: the tree the mission would run, as text or a picture."""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.cli.common import load_or_report
from executive.cli.examples import mission_file

if TYPE_CHECKING:
    import py_trees

FORMATS = ("ascii", "unicode", "dot", "svg", "png")
#: The format an output file's suffix names (without --format).
SUFFIX_FORMATS = {".txt": "unicode", ".dot": "dot", ".gv": "dot", ".svg": "svg", ".png": "png"}
GRAPHVIZ_HINT = (
    "Graphviz's 'dot' program is needed for svg/png and was not found on PATH; install it "
    "(Debian/Ubuntu: apt-get install graphviz, macOS: brew install graphviz) or use --format dot"
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("show", help="print or draw the behaviour tree a mission would run")
    p.add_argument("mission", type=mission_file, help="mission YAML file, or an example's name (executive examples)")
    p.add_argument("--format", choices=FORMATS, help="default: the output file's suffix (.txt .dot .gv .svg .png), else unicode")
    p.add_argument("-o", "--output", metavar="FILE", help="write here instead of stdout (required for svg/png)")
    p.set_defaults(func=main)


def render(root: py_trees.behaviour.Behaviour, fmt: str, name: str) -> str | bytes:
    """The tree in a format (a graph is named ``name``); svg/png need Graphviz (raises FileNotFoundError with a hint)."""
    import py_trees

    from executive.tree.drawing import dot_graph, unicode_tree

    if fmt == "ascii":
        return py_trees.display.ascii_tree(root) + "\n"
    if fmt == "unicode":
        return unicode_tree(root) + "\n"
    graph = dot_graph(root, name)
    if fmt == "dot":
        return graph
    dot = shutil.which("dot")
    if dot is None:
        raise FileNotFoundError(GRAPHVIZ_HINT)
    return subprocess.run([dot, f"-T{fmt}"], input=graph.encode(), capture_output=True, check=True).stdout


def output_format(fmt: str | None, output: str | None) -> str:
    """The format asked for, else the one the output file's suffix names (BadInput-worthy ValueError when it names none)."""
    if fmt is not None:
        return fmt
    if output is None:
        return "unicode"
    suffix = Path(output).suffix.lower()
    if suffix not in SUFFIX_FORMATS:
        known = " ".join(SUFFIX_FORMATS)
        raise ValueError(f"-o {output}: cannot tell the format from {suffix or 'no suffix'!r} (known: {known}); give --format")
    return SUFFIX_FORMATS[suffix]


def main(args: argparse.Namespace) -> int:
    from executive.tree import select as mission_tree

    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    try:
        fmt = output_format(args.format, args.output)
    except ValueError as exc:
        print(f"executive: show: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if fmt in ("svg", "png") and not args.output:
        print(f"executive: show: --format {fmt} needs -o FILE", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        out = render(mission_tree.build(mission), fmt, mission.name)
    except FileNotFoundError as exc:  # a picture this machine cannot draw: a usage to change (exit 2), not a mission that failed (1)
        asked = f"--format {fmt}" if args.format else f"-o {args.output} ({fmt}, from its suffix)"
        print(f"executive: show: {asked}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.output:
        Path(args.output).write_bytes(out if isinstance(out, bytes) else out.encode())
    else:
        sys.stdout.write(out if isinstance(out, str) else out.decode())
    return EXIT_OK
