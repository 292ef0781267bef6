"""``executive replay SNAPSHOTS [--tick N]``: the tree as it was at tick N of a recorded run; ``--web PORT``: in a browser, with a tick slider;
``--groot2 PORT``: played to Groot2 as it ran."""

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
    p.add_argument(
        "--groot2",
        metavar="[HOST:]PORT",
        help="serve the recording to Groot2 on PORT and PORT+1 as it ran (127.0.0.1 unless HOST is given), until Ctrl-C",
    )
    p.add_argument("--speed", type=float, default=1.0, metavar="X", help="with --groot2: play the recording X times faster than it ran (default 1)")
    p.set_defaults(func=main)
    c = sub.add_parser("convert", help="a snapshot file of JSON lines (FILE and FILE.1) rewritten as one MCAP recording, for Foxglove")
    c.add_argument("old", metavar="OLD", help="the snapshot file of JSON lines (its rotated FILE.1 is read first)")
    c.add_argument("new", metavar="NEW.mcap", help="the MCAP file to write")
    c.set_defaults(func=convert_main)
    f = sub.add_parser("foxglove-layout", help="the Foxglove layout for a run's recording or live server: map, tree, log, plots")
    f.add_argument("-o", "--output", metavar="FILE", help="write it to FILE (default: print it)")
    f.set_defaults(func=layout_main)


def _until_stopped() -> None:
    """Wait for Ctrl-C or SIGTERM."""
    import signal
    import threading

    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda _s, _f: stop.set())
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)


def _serve_groot2(args: argparse.Namespace) -> int:
    """The recording played to Groot2 clients until Ctrl-C or SIGTERM."""
    from executive.observers.groot2.replay import ReplayFeed
    from executive.observers.groot2.server import Groot2AddressError, Groot2Server, parse_address
    from executive.observers.groot2.view import MonitorView
    from executive.observers.snapshots import Recording

    try:
        address = parse_address(args.groot2)
    except Groot2AddressError as exc:
        raise BadInput(f"--groot2: {exc}") from exc
    if args.speed <= 0.0:
        raise BadInput(f"--speed: {args.speed:g} is not above 0")
    recording = Recording(args.snapshots)
    if args.tick is not None:
        recording.tree_of(args.tick)  # LookupError, naming the ticks there are
    view = MonitorView()
    try:
        server = Groot2Server(address, view)
    except OSError as exc:
        raise NoVehicle(f"--groot2: {exc}") from exc
    feed = ReplayFeed(recording, view, args.speed, start=args.tick)
    server.start()
    feed.start()
    print(
        f"executive: replay of {args.snapshots} (ticks {recording.first} to {recording.last}) for Groot2 on {address.host} port {address.port} "
        f"(publisher {address.port + 1}); Ctrl-C to stop",
        file=sys.stderr,
        flush=True,
    )
    try:
        _until_stopped()
    finally:
        feed.close()
        server.close()
    return EXIT_OK


def _serve(args: argparse.Namespace) -> int:
    """The recording on the live view's page until Ctrl-C or SIGTERM."""
    from executive.observers.web.replay import ReplaySource
    from executive.observers.web.server import WebAddressError, WebServer, parse_address

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
    try:
        _until_stopped()
    finally:
        server.close()
    return EXIT_OK


def main(args: argparse.Namespace) -> int:
    from executive.observers.snapshots import render, replay

    try:
        if args.web is not None and args.groot2 is not None:
            raise BadInput("--web and --groot2: one at a time")
        if args.web is not None:
            return _serve(args)
        if args.groot2 is not None:
            return _serve_groot2(args)
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


def convert_main(args: argparse.Namespace) -> int:
    """``executive convert OLD NEW.mcap``: exit 2 for a file that is not a snapshot file of JSON lines (said where)."""
    from pathlib import Path

    from executive.observers.snapshots import convert

    old, new = Path(args.old), Path(args.new)
    if new.suffix.lower() != ".mcap":
        print(f"{args.new}:1:1: (file): the new file must end in .mcap", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        ticks = convert(old, new)
    except FileNotFoundError:
        print(f"{args.old}:1:1: (file): no such snapshot file", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        print(f"{args.new}:1:1: (file): cannot be written: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"executive: {args.old}: {ticks} tick lines written to {args.new}", file=sys.stderr)
    return EXIT_OK


def layout_main(args: argparse.Namespace) -> int:
    """``executive foxglove-layout [-o layout.json]``: Foxglove's layout JSON, to import in Foxglove (Layouts, Import from file)."""
    import json

    from executive.observers.foxglove.layout import layout

    text = json.dumps(layout(), indent=2) + "\n"
    if args.output is None:
        sys.stdout.write(text)
        return EXIT_OK
    try:
        with open(args.output, "w", encoding="utf-8") as f:
            f.write(text)
    except OSError as exc:
        print(f"{args.output}:1:1: (file): cannot be written: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"executive: wrote {args.output}: import it in Foxglove (Layouts, Import from file)", file=sys.stderr)
    return EXIT_OK
