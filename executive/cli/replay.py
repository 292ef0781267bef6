"""``executive replay SNAPSHOTS [--tick N]``: the tree as it was at tick N of a recorded run; ``--web PORT``: in a browser, with a tick slider."""

from __future__ import annotations

import argparse
import sys

from executive.cli import EXIT_BAD_INPUT, EXIT_OK, BadInput, NoVehicle


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("replay", help="the tree as it was at a tick of a run recorded with `run --snapshots`")
    p.add_argument("snapshots", metavar="SNAPSHOTS", help="the snapshot file")
    p.add_argument("--tick", type=int, help="which tick (default: the last recorded)")
    p.add_argument("--all-keys", action="store_true", help="print the whole blackboard, not just what changed at that tick")
    p.add_argument("--web", metavar="[HOST:]PORT", help="show the recording in a browser on PORT (127.0.0.1 unless HOST is given), until Ctrl-C")
    p.set_defaults(func=main)


def _serve(args: argparse.Namespace) -> int:
    """The recording on the live view's page until Ctrl-C or SIGTERM."""
    import signal
    import threading

    from executive.web.replay import ReplaySource
    from executive.web.server import WebAddressError, WebServer, parse_address

    try:
        address = parse_address(args.web)
        source = ReplaySource(args.snapshots)
    except WebAddressError as exc:
        raise BadInput(f"--web: {exc}") from exc
    server = WebServer(address)  # nothing to command: no token
    try:
        server.start(source)
    except OSError as exc:
        raise NoVehicle(f"--web: cannot listen on {args.web}: {exc}") from exc
    recording = source.recording
    print(f"executive: replay of {args.snapshots} (ticks {recording.first} to {recording.last}) on {server.url}; Ctrl-C to stop", file=sys.stderr)
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda _s, _f: stop.set())
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        server.close()
    return EXIT_OK


def main(args: argparse.Namespace) -> int:
    from executive.snapshots import render, replay

    try:
        if args.web is not None:
            return _serve(args)
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
