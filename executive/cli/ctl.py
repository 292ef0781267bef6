"""``executive ctl``: operator control of a running executive over its control socket.

``executive ctl [--socket PATH] [--json] REQUEST [ARGS]``; ``route`` takes an operation and its
arguments (``executive ctl route OPERATION --help``). Waypoint numbers are 1-based, as the status
line counts them. ``tree`` prints the running tree with each node's status and feedback (``--watch``:
again every ``--interval`` seconds until Ctrl-C or the executive stops). ``arm``, ``disarm`` and
``mode MODE`` command the vehicle for a person and wait (bounded) for the autopilot's answer;
mid-mission, a ``disarm`` or ``mode`` the vehicle shows pauses the mission hands off, a refused one changes nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_NO_VEHICLE, EXIT_OK, number
from executive.io.control import default_socket_path, request

REQUESTS = ("status", "start", "pause", "resume", "abort", "delete", "upload", "route", "tree", "arm", "disarm", "mode")
#: How long (wall clock) to wait for the autopilot's answer to arm, disarm or mode.
ANSWER_WAIT_S = 10.0
_PLAIN = {
    "status": "the mission's state and the vehicle's",
    "start": "start the loaded mission",
    "pause": "pause the mission: the vehicle holds",
    "resume": "resume a paused mission",
    "abort": "abort the mission: the vehicle holds",
    "delete": "delete the loaded mission",
}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ctl", help="control a running executive: status, tree, start, pause, resume, abort, delete, upload, route, arm, disarm, mode")
    p.add_argument("--socket", metavar="PATH", default=default_socket_path(), help="the executive's control socket (default %(default)s)")
    p.add_argument("--json", action="store_true", help="print the reply as JSON")
    # the same options after the request too: SUPPRESS keeps what was given before it
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--socket", metavar="PATH", default=argparse.SUPPRESS, help="the executive's control socket")
    common.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the reply as JSON")
    requests = p.add_subparsers(dest="request", required=True, metavar="REQUEST")
    for name, text in _PLAIN.items():
        requests.add_parser(name, parents=[common], help=text, description=text)
    upload = requests.add_parser("upload", parents=[common], help="load a mission file; while PAUSED, replace the mission", description=_UPLOAD_HELP)
    upload.add_argument("mission", help="the mission file")
    leg = "while PAUSED: continue from waypoint N of the new mission (default: the one the vehicle heads for)"
    upload.add_argument("--leg", type=_number, metavar="N", help=leg)
    _register_route(requests.add_parser("route", parents=[common], help="show or edit the route", description=_ROUTE_HELP), common)
    tree_help = "the running tree: each node's status (* running, ✓ succeeded, ✕ failed, - not ticked) and feedback"
    tree = requests.add_parser("tree", parents=[common], help=tree_help, description=tree_help + "; the status line says what it waits for")
    tree.add_argument("--watch", action="store_true", help="print it again every --interval seconds, until Ctrl-C or the executive stops")
    tree.add_argument(
        "--interval", type=number(at_least=0.05, at_most=3600), default=1.0, metavar="S", help="seconds between two prints with --watch (default 1)"
    )
    for name, text in _VEHICLE.items():
        command = requests.add_parser(name, parents=[common], help=text, description=f"{text}. {_PERSON_WINS}")
        if name == "mode":
            command.add_argument("mode", help="the mode's name as the autopilot shows it (HOLD, LOITER, MANUAL, RTL...)")
        else:
            command.add_argument("--force", action="store_true", help="skip the autopilot's checks (ArduPilot's 2989/21196 magic)")
    p.set_defaults(func=main)


_UPLOAD_HELP = """Load a mission file READY (while IDLE, READY, COMPLETED or ABORTED). While PAUSED, replace the
mission (route, limits, tree): same vehicle, autopilot and rc; it continues from the waypoint the
vehicle was heading for (or --leg N) with the samples already taken, and stays PAUSED until
`ctl resume`. The new route goes to the autopilot at once (uploaded and read back). An incompatible
mission is refused with the reason, and nothing changes."""

_VEHICLE = {
    "arm": "arm the vehicle",
    "disarm": "disarm the vehicle (mid-mission: once disarmed, the mission pauses, hands off)",
    "mode": "put the vehicle in a mode (mid-mission: once in it, the mission pauses, hands off)",
}
_PERSON_WINS = (
    "A person always wins: the command is sent whatever the mission's state; once the vehicle shows it, a running mission pauses "
    "rather than undoing it (`ctl resume` hands the vehicle back to it); refused by the autopilot, it changes nothing. Waits for the "
    "autopilot's answer."
)

_ROUTE_HELP = """Show or edit the route of the loaded mission (while READY, RUNNING or PAUSED). After an edit the
executive uploads the route to the autopilot and reads it back. Waypoint numbers are 1-based."""


def _register_route(route: argparse.ArgumentParser, common: argparse.ArgumentParser) -> None:
    ops = route.add_subparsers(dest="operation", required=True, metavar="OPERATION")

    def op(name: str, text: str) -> argparse.ArgumentParser:
        return ops.add_parser(name, parents=[common], help=text, description=text)

    op("show", "the route, the waypoint the vehicle heads for, and whether the autopilot holds it")
    add = op("add", "add a waypoint at the vehicle's position (or --lat/--lon): at the end, after the current one or after waypoint N")
    add.add_argument("--after", type=_after, default="end", metavar="end|current|N", help="where: end (default), current, or N (0: first)")
    _position_options(add)
    add.add_argument("--alt", type=float, dest="alt_m", metavar="M", help="altitude above home, m (air vehicles)")
    remove = op("remove", "remove the last waypoint, the current one, or waypoint N")
    remove.add_argument("waypoint", type=_which, metavar="last|current|N")
    op("clear", "remove every waypoint (home stays)")
    op("backwards", "reverse the waypoints: the vehicle finishes its leg, then drives back")
    offset = op("offset", "move every waypoint (or --waypoint N) a distance toward a compass bearing (GPS drift between days)")
    offset.add_argument("distance_m", type=float, metavar="DIST_M", help="metres (negative: the opposite way)")
    offset.add_argument("bearing_deg", type=float, metavar="BEARING_DEG", help="compass bearing, degrees")
    offset.add_argument("--waypoint", "--index", type=_number, metavar="N", help="only waypoint N")
    scale = op("scale-rotate", "scale the route and turn it (clockwise) about the centre of its bounding box")
    scale.add_argument("scale", type=float, metavar="SCALE", help="distance factor, > 0 (1: same size)")
    scale.add_argument("angle_deg", type=float, metavar="ANGLE_DEG", help="degrees clockwise (negative: anticlockwise)")
    _centre_option(scale)
    mirror = op("mirror", "mirror the route across an axis through the centre of its bounding box")
    mirror.add_argument("bearing_deg", type=float, metavar="BEARING_DEG", help="the axis's compass bearing, degrees")
    _centre_option(mirror)
    _position_options(op("set-home", "make the vehicle's position (or --lat/--lon) the mission's home, and the autopilot's"))


def _position_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--lat", type=float, metavar="DEG", help="latitude (with --lon; default: the vehicle's position)")
    parser.add_argument("--lon", type=float, metavar="DEG", help="longitude (with --lat)")


def _centre_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--centre", type=float, nargs=2, metavar=("LAT", "LON"), help="about this point instead (to undo an edit exactly)")


def _number(value: str) -> int:
    if not value.isdigit() or int(value) < 1:
        raise argparse.ArgumentTypeError(f"{value!r} is not a waypoint number (1, 2, ...)")
    return int(value)


def _which(value: str) -> str | int:
    return value if value in ("last", "current") else _number(value)


def _after(value: str) -> str | int:
    return value if value in ("end", "current") else 0 if value == "0" else _number(value)


def _route_request(args: argparse.Namespace) -> dict[str, Any]:
    """The route request's arguments: the operation and what was given of its options."""
    names = ("after", "lat", "lon", "alt_m", "waypoint", "distance_m", "bearing_deg", "scale", "angle_deg", "centre")
    extra = {name: getattr(args, name) for name in names if getattr(args, name, None) is not None}
    if ("lat" in extra) != ("lon" in extra):
        raise ValueError("--lat and --lon go together")
    return {"operation": args.operation.replace("-", "_"), **extra}


def main(args: argparse.Namespace) -> int:
    if args.request == "tree" and args.watch:
        return _watch_tree(args)
    extra: dict[str, Any] = {}
    if args.request == "upload":
        try:
            extra = {"filename": args.mission, "text": Path(args.mission).read_text(encoding="utf-8")}
            if args.leg is not None:
                extra["leg"] = args.leg
        except (OSError, UnicodeDecodeError) as exc:
            print(f"{args.mission}:1:1: (file): {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
    elif args.request == "route":
        try:
            extra = _route_request(args)
        except ValueError as exc:
            print(f"executive: ctl: route {args.operation}: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
    elif args.request in _VEHICLE:
        extra = {"mode": args.mode} if args.request == "mode" else {"force": args.force}
    try:
        reply = request(args.socket, args.request, **extra)
        if reply.get("ok") and "command" in reply:
            return _report_answer(args, reply)
    except OSError as exc:
        print(f"executive: ctl: no executive answers on {args.socket}: {exc}", file=sys.stderr)
        return EXIT_NO_VEHICLE
    what = args.request if args.request != "route" else f"route {args.operation}"
    if args.json:
        print(json.dumps(reply))
    elif not reply.get("ok"):
        print(f"executive: ctl: {what} refused ({reply.get('state', '?')}): {reply.get('reason')}", file=sys.stderr)
    elif "tree" in reply:
        print(tree_text(reply))
    elif "status" in reply:
        from executive.operator.status import status_line  # an answer to show: an executive that is not there costs none of it

        print(status_line(reply["status"]))
    else:
        print(f"{reply['state']}: {reply['reason']}")
        if "route" in reply:
            print(route_lines(reply["route"]))
    return EXIT_OK if reply.get("ok") else EXIT_FAILED


def _report_answer(args: argparse.Namespace, reply: dict[str, Any]) -> int:
    """A person's command was sent: say so, wait (bounded) for the autopilot's answer and say it; 0 only when it accepted."""
    command = reply["command"]
    if not args.json:
        print(f"{reply['state']}: {reply['reason']}")
    deadline = time.monotonic() + ANSWER_WAIT_S
    outcome: dict[str, Any] = {"state": "QUEUED"}
    mission = reply["state"]
    while time.monotonic() < deadline:
        answer = request(args.socket, "command", ticket=command["ticket"], name=command["name"])
        outcome = answer.get("command") or {"state": "UNKNOWN", "result": answer.get("reason"), "final": True}
        mission = answer.get("state", mission)
        if outcome.get("final"):
            break
        time.sleep(0.1)
    accepted = outcome["state"] == "ACCEPTED"
    if args.json:
        print(json.dumps({**reply, "command": {**command, **outcome}}))
    elif accepted:
        print(f"{command['what']}: ACCEPTED by the autopilot")
    else:
        said = {"REJECTED": f"refused by the autopilot ({outcome.get('result')})", "TIMED_OUT": "no answer from the autopilot"}
        why = said.get(outcome["state"], f"{outcome['state'].lower()} ({outcome.get('result', 'no answer yet')})")
        print(f"executive: ctl: {command['what']}: {why}; nothing changed (the mission {mission})", file=sys.stderr)
    return EXIT_OK if accepted else EXIT_FAILED


def tree_text(reply: dict[str, Any]) -> str:
    """A ``tree`` reply for a person: the status line (what the tree waits for), then the tree at its latest tick."""
    from executive.operator.status import status_line
    from executive.tree.ticks import TickState, render_tree

    lines = [status_line(reply["status"]), *render_tree(TickState.from_tree_dict(reply["tree"]))]
    if not reply["tree"]["live"]:
        lines[1] += f" (the last tick of the run, which ended {reply['state']})"
    return "\n".join(lines)


def _watch_tree(args: argparse.Namespace) -> int:
    """``ctl tree --watch``: the tree every ``--interval`` s (in place on a terminal) until the run's last tick, Ctrl-C or the executive stops."""
    clear = "\x1b[H\x1b[2J" if sys.stdout.isatty() and not args.json else ""
    shown = 0
    try:
        while True:
            try:
                reply = request(args.socket, "tree")
            except OSError as exc:
                if not shown:
                    print(f"executive: ctl: no executive answers on {args.socket}: {exc}", file=sys.stderr)
                    return EXIT_NO_VEHICLE
                # it ended between two looks: what is shown is a tick before its last, and is said to be
                print(f"executive: ctl: the executive on {args.socket} has stopped; the tree above is from a tick before its last", file=sys.stderr)
                return EXIT_OK
            if args.json:
                print(json.dumps(reply), flush=True)
            elif reply.get("ok"):
                print(f"{clear}{tree_text(reply)}\n", flush=True)
            else:
                print(f"{clear}{reply['state']}: {reply['reason']}\n", flush=True)
            shown += 1
            if reply.get("ok") and not reply["tree"]["live"]:
                return EXIT_OK  # the run's last tick, shown: the watch ends on it, not on a frame of a tick still running
            time.sleep(args.interval)
    except KeyboardInterrupt:
        return EXIT_OK  # the way to stop watching


def route_lines(route: dict[str, Any]) -> str:
    """The route of a reply, for a person: one line per waypoint, ``>`` on the one the vehicle heads for."""
    upload = route.get("upload")
    held = "yes" if route["on_autopilot"] else "no"
    if upload is not None and upload["state"] != "DONE":
        held += f" ({upload['state'].lower()}: {upload['detail']})"
    count = len(route["waypoints"])
    lines = [f"{count} waypoint{'' if count == 1 else 's'}; on the autopilot: {held}"]
    names = route.get("names") or [None] * len(route["waypoints"])  # an older executive sends none
    for n, ((lat, lon, alt), name) in enumerate(zip(route["waypoints"], names, strict=False), start=1):
        named = f"  {name!r}" if name else ""
        lines.append(f"{'>' if n == route['current'] else ' '} {n:3d}  {lat:.7f}, {lon:.7f}{f'  alt {alt:g} m' if alt else ''}{named}")
    if route["home"] is not None:
        lines.append(f"  home {route['home'][0]:.7f}, {route['home'][1]:.7f}")
    return "\n".join(lines)
