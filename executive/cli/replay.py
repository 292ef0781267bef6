"""``executive replay SNAPSHOTS [--tick N]``: the tree as it was at tick N of a recorded run."""

from __future__ import annotations

import argparse
import sys

from executive.cli import EXIT_BAD_INPUT, EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("replay", help="the tree as it was at a tick of a run recorded with `run --snapshots`")
    p.add_argument("snapshots", metavar="SNAPSHOTS", help="the snapshot file")
    p.add_argument("--tick", type=int, help="which tick (default: the last recorded)")
    p.add_argument("--all-keys", action="store_true", help="print the whole blackboard, not just what changed at that tick")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from executive.snapshots import render, replay

    try:
        state = replay(args.snapshots, args.tick)
    except FileNotFoundError:
        print(f"{args.snapshots}:1:1: (file): no such snapshot file", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as exc:  # not a snapshot file, or a broken line: located
        print(exc, file=sys.stderr)
        return EXIT_BAD_INPUT
    except LookupError as exc:  # no such tick: the ticks there are
        print(f"executive: replay: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print("\n".join(render(state, all_keys=args.all_keys)))
    return EXIT_OK
