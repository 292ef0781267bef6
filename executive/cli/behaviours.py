"""``executive behaviours [--json] [NAME...]``: the node catalogue (guards, actions, decorators, composites, subtrees) and their parameters."""

from __future__ import annotations

import argparse
import difflib
import json
import sys

from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.registry import PluginError
from executive.tree.catalogue import KINDS, Catalogue, NodeSpec, ParamSpec, load_behaviours


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``behaviours`` subcommand."""
    parser = subparsers.add_parser(
        "behaviours",
        help="list the nodes a tree can be made of, with their parameters",
        description="List every guard, action, decorator, composite and built-in subtree (ours and installed plugins').",
    )
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these nodes")
    parser.add_argument("--kind", choices=KINDS, help="only nodes of this kind")
    parser.add_argument("--json", action="store_true", help="a JSON list of nodes on stdout")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the catalogue (or the nodes named); exit 2 naming a node that does not exist, or a plugin that cannot be loaded."""
    broken: list[PluginError] = []
    found = Catalogue.build(load_behaviours(broken))  # a broken plugin is said, the others listed all the same
    for exc in broken:
        print(f"executive: behaviours: {exc}", file=sys.stderr)
    unknown = [n for n in args.names if found.get(n) is None]
    if unknown:
        said = ", ".join(f"no node {name!r}{_did_you_mean(name, found.names())}" for name in unknown)
        print(f"executive: behaviours: {said}; executive behaviours lists them", file=sys.stderr)
        return EXIT_BAD_INPUT
    specs = [s for s in found.nodes(args.kind) if not args.names or s.name in args.names]
    if args.json:
        json.dump([s.to_json() for s in specs], sys.stdout, indent=2, ensure_ascii=False)
        sys.stdout.write("\n")
        return EXIT_BAD_INPUT if broken else EXIT_OK
    sys.stdout.write("".join(describe(s) for s in specs))
    return EXIT_BAD_INPUT if broken else EXIT_OK


def _did_you_mean(name: str, names: list[str]) -> str:
    """`` (did you mean go_to?)`` for a name close to a node's, as ``validate`` says it of a tree's node; else nothing."""
    close = difflib.get_close_matches(name, names, n=1)
    return f" (did you mean {close[0]}?)" if close else ""


def describe(spec: NodeSpec) -> str:
    """A node as text: ``name (kind): doc``, then a line per parameter."""
    lines = [f"{spec.name} ({spec.kind}): {spec.doc}"]
    if spec.kind == "guard":
        lines.append(f"    unknown or stale: {spec.unknown_or_stale or '(not stated by the guard)'}")
    lines += [f"    {_param(p)}" for p in spec.params]
    return "\n".join(lines) + "\n"


def _param(p: ParamSpec) -> str:
    kind = f"one of {'|'.join(p.choices)}" if p.choices else p.type
    kind += " or null" if p.nullable and p.type != "node name" else ""
    unit = f" [{p.unit}]" if p.unit else ""
    if p.required:
        default = "required"
    elif p.from_mission is not None:
        default = f"default: the mission's {p.from_mission}"
    else:
        default = f"default: {json.dumps(p.default, ensure_ascii=False)}"
    return f"{p.name}: {kind}{unit}, {default}: {p.doc}"
