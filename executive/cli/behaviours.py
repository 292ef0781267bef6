"""``executive behaviours [--json] [NAME...]``: the node catalogue (guards, actions, decorators, composites, subtrees) and their parameters."""

from __future__ import annotations

import argparse
import difflib
import json
import sys

from executive import registry
from executive.cli import EXIT_BAD_INPUT, EXIT_OK
from executive.mission.declaration import FIRMWARE_NAMES, TreeDeclaration, declaration_of
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
    parser.add_argument("--json", action="store_true", help="a JSON list of nodes (with --trees: of trees) on stdout")
    parser.add_argument("--trees", action="store_true", help="list the named trees (ours and plugins') and what each declares instead")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the catalogue (or the nodes named); exit 2 naming a node that does not exist, or a plugin that cannot be loaded."""
    if args.trees:
        return _trees(args)
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


def _trees(args: argparse.Namespace) -> int:
    """Print each named tree's declaration (or the trees named); exit 2 naming a tree that does not exist or cannot be loaded."""
    known = registry.names(registry.TREES)
    unknown = [n for n in args.names if n not in known]
    if unknown:
        said = ", ".join(f"no tree {name!r}{_did_you_mean(name, known)}" for name in unknown)
        print(f"executive: behaviours: {said}; executive behaviours --trees lists them", file=sys.stderr)
        return EXIT_BAD_INPUT
    found: dict[str, TreeDeclaration] = {}
    broken = False
    for name in args.names or known:
        try:
            found[name] = declaration_of(name)
        except PluginError as exc:  # said, the others listed all the same
            print(f"executive: behaviours: {exc}", file=sys.stderr)
            broken = True
    if args.json:
        json.dump([{"name": name, "kind": "tree", **d.to_json()} for name, d in found.items()], sys.stdout, indent=2, ensure_ascii=False)
        sys.stdout.write("\n")
    else:
        sys.stdout.write("".join(describe_tree(name, d) for name, d in found.items()))
    return EXIT_BAD_INPUT if broken else EXIT_OK


def describe_tree(name: str, d: TreeDeclaration) -> str:
    """A tree's declaration as text: ``name (tree): doc``, then a line per thing it declares."""
    lines = [f"{name} (tree): {d.doc or '(declares nothing: any vehicle, any autopilot, guided only)'}"]
    lines.append(f"    vehicles: {', '.join(sorted(d.vehicles)) if d.vehicles is not None else 'any'}")
    if d.needs is not None:
        lines.append(f"    needs: {FIRMWARE_NAMES.get(d.needs[0], d.needs[0])}: {d.needs[1]}")
    if d.auto_refused is not None:
        lines.append(f"    drive: auto: refused: {d.auto_refused}")
    elif d.auto_drive:
        lines.append(f"    drive: auto: {', '.join(f'{kind} ({firmware})' for kind, firmware in sorted(d.auto_drive.items()))}")
    if d.section is not None:
        lines.append(f"    reads: {d.section}:{' (its own: ' + ', '.join(d.options.model_fields) + ')' if d.options is not None else ''}")
    if d.rc_switches is not None or d.rc_defaults:
        defaults = ", ".join(f"rc.{key}: {value}" for key, value in d.rc_defaults.items())
        lines.append(f"    rc: {'its own switches' if d.rc_switches is not None else 'the take-over switch'}{f'; {defaults}' if defaults else ''}")
    lines += [f"    failsafe {condition}: {reaction}, {recovery}" for condition, (reaction, recovery) in d.failsafes.items()]
    lines += [f"    refuses failsafe reaction {reaction}: {why}" for reaction, why in d.refused_reactions.items()]
    said = [("its route may start empty", d.empty_route), ("takes samples", d.samples), ("legs timed", d.timed_legs)]
    if any(on for _, on in said):
        lines.append(f"    {'; '.join(what for what, on in said if on)}")
    for k in d.vehicle_kinds:
        simulated = f", simulated as a {k.simulator}" if k.simulator is not None else ", no simulated vehicle (--mavlink only)"
        lines.append(f"    vehicle kind {k.kind}: {', '.join(sorted(k.autopilots))}, safe mode {k.profile.safe_mode}{simulated}")
    return "\n".join(lines) + "\n"


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
