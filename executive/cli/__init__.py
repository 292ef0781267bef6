"""The ``executive`` command: one command, one module per subcommand."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from executive import __version__

#: Exit codes (a contract with users and scripts).
EXIT_OK = 0  # success / mission COMPLETED
EXIT_FAILED = 1  # mission aborted or failed at run time
EXIT_BAD_INPUT = 2  # usage error, invalid mission file
EXIT_NO_VEHICLE = 3  # could not reach the vehicle

#: Subcommand modules of this package; each has ``register(subparsers)`` setting ``func``.
SUBCOMMANDS = ("validate", "show", "run", "sim", "schema")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="executive", description="Onboard behaviour-tree mission executive.")
    parser.add_argument("--version", action="version", version=f"executive {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        importlib.import_module(f"executive.cli.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``executive`` console script; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse exits 2 on usage errors, 0 on --help
        return int(exc.code or 0)
    from executive.cli.common import BadInput

    try:
        return int(args.func(args))
    except BadInput as exc:
        print(f"executive: {args.command}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
