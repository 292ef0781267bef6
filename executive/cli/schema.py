"""``executive schema [-o FILE]``: the JSON schema of mission files, for editors."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from executive.cli import EXIT_BAD_INPUT, EXIT_OK


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``schema`` subcommand."""
    parser = subparsers.add_parser(
        "schema", help="print the JSON schema of mission files", description="Print or write the mission file JSON schema."
    )
    parser.add_argument("-o", "--output", metavar="FILE", help="write the schema here instead of stdout")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the schema, or write it to ``--output``."""
    from executive.registry import PluginError
    from executive.tree.schema import mission_json_schema_text

    try:
        text = mission_json_schema_text()  # plugins' behaviours are in it
    except PluginError as exc:
        print(f"executive: schema: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.output is None:
        sys.stdout.write(text)
        return EXIT_OK
    try:
        Path(args.output).write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"executive: schema: cannot write {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK
