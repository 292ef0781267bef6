"""``executive ctl``: operator control of a running executive over its control socket."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_NO_VEHICLE, EXIT_OK
from executive.io.control import default_socket_path, request
from executive.status import status_line

REQUESTS = ("status", "start", "pause", "resume", "abort", "delete", "upload")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ctl", help="control a running executive: status, start, pause, resume, abort, delete, upload MISSION")
    p.add_argument("--socket", metavar="PATH", default=default_socket_path(), help="the executive's control socket (default %(default)s)")
    p.add_argument("--json", action="store_true", help="print the reply as JSON")
    p.add_argument("request", choices=REQUESTS, help="what to ask")
    p.add_argument("mission", nargs="?", help="upload: the mission file")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    extra = {}
    if args.request == "upload":
        if not args.mission:
            print("executive: ctl: upload needs a MISSION file", file=sys.stderr)
            return EXIT_BAD_INPUT
        try:
            extra = {"filename": args.mission, "text": Path(args.mission).read_text(encoding="utf-8")}
        except (OSError, UnicodeDecodeError) as exc:
            print(f"{args.mission}:1:1: (file): {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
    elif args.mission:
        print(f"executive: ctl: {args.request} takes no file", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        reply = request(args.socket, args.request, **extra)
    except OSError as exc:
        print(f"executive: ctl: no executive answers on {args.socket}: {exc}", file=sys.stderr)
        return EXIT_NO_VEHICLE
    if args.json:
        print(json.dumps(reply))
    elif reply.get("ok"):
        print(status_line(reply["status"]) if "status" in reply else f"{reply['state']}: {reply['reason']}")
    else:
        print(f"executive: ctl: {args.request} refused ({reply.get('state', '?')}): {reply.get('reason')}", file=sys.stderr)
    return EXIT_OK if reply.get("ok") else EXIT_FAILED
