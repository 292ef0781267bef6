"""``executive show MISSION``: the tree the mission would run, as text or a picture."""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import py_trees

import trees
from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK
from executive.cli.common import load_or_report

FORMATS = ("ascii", "unicode", "dot", "svg", "png")
GRAPHVIZ_HINT = (
    "Graphviz's 'dot' program is needed for svg/png and was not found on PATH; install it "
    "(Debian/Ubuntu: apt-get install graphviz, macOS: brew install graphviz) or use --format dot"
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("show", help="print or draw the behaviour tree a mission would run")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--format", choices=FORMATS, default="unicode", help="default unicode")
    p.add_argument("-o", "--output", metavar="FILE", help="write here instead of stdout (required for svg/png)")
    p.set_defaults(func=main)


def render(root: py_trees.behaviour.Behaviour, fmt: str) -> str | bytes:
    """The tree in a format; svg/png need Graphviz (raises FileNotFoundError with a hint)."""
    if fmt == "ascii":
        return py_trees.display.ascii_tree(root) + "\n"
    if fmt == "unicode":
        return py_trees.display.unicode_tree(root) + "\n"
    graph = py_trees.display.dot_tree(root, with_blackboard_variables=False)
    if fmt == "dot":
        return graph.to_string()
    if shutil.which("dot") is None:
        raise FileNotFoundError(GRAPHVIZ_HINT)
    return graph.create(format=fmt)


def main(args: argparse.Namespace) -> int:
    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    if args.format in ("svg", "png") and not args.output:
        print(f"executive: show: --format {args.format} needs -o FILE", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        out = render(trees.build(mission), args.format)
    except FileNotFoundError as exc:
        print(f"executive: show: {exc}", file=sys.stderr)
        return EXIT_FAILED
    if args.output:
        Path(args.output).write_bytes(out if isinstance(out, bytes) else out.encode())
    else:
        sys.stdout.write(out if isinstance(out, str) else out.decode())
    return EXIT_OK
