"""The ``executive`` command: one command, one module per subcommand."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback
from collections.abc import Callable, Sequence
from typing import Any

from executive import __version__

#: Exit codes (a contract with users and scripts).
EXIT_OK = 0  # success / mission COMPLETED
EXIT_FAILED = 1  # mission aborted or failed at run time
EXIT_BAD_INPUT = 2  # usage error, invalid mission file
EXIT_NO_VEHICLE = 3  # could not reach the vehicle
EXIT_INTERRUPTED = 130  # Ctrl-C before anything was commanded (128 + SIGINT, as a shell reports it)
EXIT_CRASHED = 70  # a bug: an exception nothing expected (sysexits' EX_SOFTWARE); a service restarts on it, not on 1

#: What each exit code means, for every subcommand: ``executive --help`` and the manual's table are made from it.
EXIT_CODES = {
    EXIT_OK: "success: the mission COMPLETED, or the command did what it was asked",
    EXIT_FAILED: "it ran and failed: a mission aborted or failed at run time; `ctl` refused (by the executive or the autopilot); "
    "`can decode` skipped lines it could not read",
    EXIT_BAD_INPUT: "bad input, nothing sent: usage, an invalid mission file, a malformed `--mavlink`/`--gcs`/`--can`, a user's tree or "
    "plugin that fails as it is built or set up, a journal that cannot be created or read",
    EXIT_NO_VEHICLE: "could not reach the vehicle or a port: no heartbeat, nothing listening at a `tcp:` endpoint, no such serial device "
    "or CAN bus, one another process holds or that sends no MAVLink, an address that cannot be listened on (a port in use); "
    "`ctl`: no executive answers",
    EXIT_CRASHED: "a crash (a bug of ours: the traceback is printed)",
    EXIT_INTERRUPTED: "Ctrl-C before anything was commanded (while waiting for the autopilot's first heartbeat)",
}


class BadInput(Exception):
    """Input a subcommand cannot use; ``main`` prints it and exits 2."""


class NoVehicle(Exception):
    """The vehicle (its link or bus) cannot be reached; ``main`` prints it and exits 3."""


def number(
    kind: type[int] | type[float] = float, *, above: float | None = None, at_least: float | None = None, at_most: float | None = None
) -> Callable[[str], Any]:
    """An argparse ``type=``: a number of ``kind`` within the bounds given, else a message saying which."""

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {'an integer' if kind is int else 'a number'}: {text!r}") from None
        if value != value or (above is not None and not value > above):  # NaN is no number of anything
            raise argparse.ArgumentTypeError(f"must be > {above:g}, got {text}")
        if at_least is not None and at_most is not None and not at_least <= value <= at_most:
            raise argparse.ArgumentTypeError(f"must be {at_least:g}-{at_most:g}, got {text}")
        if at_least is not None and not value >= at_least:
            raise argparse.ArgumentTypeError(f"must be at least {at_least:g}, got {text}")
        if at_most is not None and not value <= at_most:
            raise argparse.ArgumentTypeError(f"must be at most {at_most:g}, got {text}")
        return value

    return parse


#: Command -> the module of this package that registers it (``register(subparsers)`` setting ``func``).
COMMANDS = {
    "validate": "validate", "show": "show", "run": "run_options", "sim": "sim", "schema": "schema", "ctl": "ctl", "report": "report",
    "replay": "replay", "convert": "replay", "foxglove-layout": "replay", "can": "can", "import": "plan_files", "export": "plan_files",
    "service": "service", "behaviours": "behaviours", "examples": "examples",
}  # fmt: skip


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line; with ``only`` (a command), just its module is imported: ``ctl`` starts fast."""
    parser = argparse.ArgumentParser(
        prog="executive",
        description="Onboard behaviour-tree mission executive.",
        epilog="exit codes, the same for every command: " + "; ".join(f"{code}: {meaning}" for code, meaning in EXIT_CODES.items()),
    )
    parser.add_argument("--version", action="version", version=f"executive {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in dict.fromkeys(COMMANDS.values()) if only is None else (COMMANDS[only],):
        importlib.import_module(f"executive.cli.{module}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``executive`` console script; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv[0] if argv and argv[0] in COMMANDS else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse exits 2 on usage errors, 0 on --help
        return int(exc.code or 0)
    try:
        code = int(args.func(args))
    except BadInput as exc:
        print(f"executive: {args.command}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except NoVehicle as exc:
        print(f"executive: {args.command}: {exc}", file=sys.stderr)
        return EXIT_NO_VEHICLE
    except BrokenPipeError:  # `executive report j.db | head`: the reader has what it wanted
        _discard_stdout()
        return EXIT_OK
    except KeyboardInterrupt:  # a run catches Ctrl-C itself once it commands the vehicle; before that, nothing to undo
        print(f"executive: {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        registry = sys.modules.get("executive.registry")  # loaded if it raised: not imported here, ctl starts fast
        if registry is not None and isinstance(exc, registry.PluginError):
            print(f"executive: {args.command}: {exc}", file=sys.stderr)  # an installed plugin that cannot be loaded
            return EXIT_BAD_INPUT
        # a bug: its traceback, and an exit a service manager tells from a mission that ended badly (1)
        traceback.print_exc()
        print(f"executive: {args.command}: crashed (a bug, traceback above): exit {EXIT_CRASHED}", file=sys.stderr)
        return EXIT_CRASHED
    try:
        sys.stdout.flush()  # here, not at exit, where a reader that went away would cost a traceback
    except BrokenPipeError:
        _discard_stdout()
    return code


def _discard_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's last flush at exit finds no closed pipe (and prints no traceback)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


if __name__ == "__main__":
    sys.exit(main())
