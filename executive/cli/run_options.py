"""``executive run``'s command line: its options, without what running a mission imports (``executive run --help`` starts fast).

The run itself is :func:`executive.cli.run.main`.
"""

from __future__ import annotations

import argparse

from executive.cli import number
from executive.cli.common import mavlink_id
from executive.cli.examples import fault_file, mission_file
from executive.io.control import default_socket_path


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``run`` subcommand."""
    p = sub.add_parser("run", help="run a mission (on the built-in simulated vehicle unless --mavlink is given)")
    p.add_argument("mission", type=mission_file, help="mission YAML file, or an example's name (executive examples)")
    p.add_argument("--mavlink", metavar="URL", help="autopilot link: udpin:0.0.0.0:14550, tcp:HOST:PORT, /dev/ttyACM0[,BAUD]")
    p.add_argument("--rate", type=float, default=10.0, metavar="HZ", help="tick rate (default 10)")
    p.add_argument(
        "--speedup",
        type=float,
        default=1.0,
        metavar="X",
        help="the built-in simulator runs X times faster than real time; with --mavlink, the vehicle's own speed-up (ArduPilot SITL's "
        "--speedup): the executive ticks and counts its timeouts in the vehicle's time. Never with a real vehicle",
    )
    p.add_argument("--sysid", type=mavlink_id, default=1, help="our MAVLink system id (default 1, the vehicle's)")
    p.add_argument(
        "--autopilot",
        choices=("ardupilot", "px4"),
        help="the autopilot firmware, whatever its HEARTBEAT says (default: the mission's autopilot:, else the HEARTBEAT's); "
        "without --mavlink, the simulated vehicle runs it",
    )
    target = "the autopilot to command, alone (its HEARTBEAT's system id); required when several vehicles share the link"
    p.add_argument("--target-system", type=mavlink_id, metavar="N", help=target)
    p.add_argument("--target-component", type=mavlink_id, default=1, metavar="N", help="the autopilot's component id (default 1)")
    p.add_argument("--connect-timeout", type=float, default=30.0, metavar="S", help="seconds to wait for the autopilot (default 30)")
    p.add_argument(
        "--faults",
        metavar="FILE",
        type=fault_file,
        help="simulator only: YAML list of faults to inject into the simulated vehicle; or an example's, by name",
    )
    p.add_argument("--tlog", metavar="FILE", help="record the whole MAVLink link in FILE (.tlog, for Mission Planner and pymavlink)")
    p.add_argument("--signing-key", metavar="FILE", help="MAVLink 2 signing key (32 bytes, 64 hex digits or a passphrase)")
    p.add_argument(
        "--socket",
        metavar="PATH",
        help="control socket for `executive ctl`, owner-only (default `$XDG_RUNTIME_DIR/executive.sock`, else `/tmp/executive-UID.sock`: "
        f"here {default_socket_path()}; when another executive serves the default, one with this one's process id beside it, "
        "`executive-PID.sock` under `$XDG_RUNTIME_DIR`, else `executive-UID-PID.sock`, said at start-up; a --socket another executive "
        "serves is refused, exit 2); 'none': no control socket",
    )
    p.add_argument("--wait", action="store_true", help="load the mission READY, wait for `ctl start`, and keep serving after it ends")
    p.add_argument("--gcs", metavar="URL", help="a MAVLink endpoint for ground stations (e.g. udpin:0.0.0.0:14551)")
    p.add_argument("--gcs-sysid", type=int, action="append", metavar="N", help="system id allowed to command us (repeatable; default 255)")
    p.add_argument("--journal", metavar="DB", help="record the run (transitions, legs, samples, events) in this SQLite journal")
    p.add_argument("--resume", action="store_true", help="continue the last unfinished run of this mission in --journal (after a crash)")
    p.add_argument("--snapshots", metavar="FILE", help="record every tick (statuses, blackboard) for `executive replay`; FILE.mcap: MCAP (Foxglove)")
    p.add_argument(
        "--snapshots-rotate-mb",
        type=number(at_least=0.01),
        default=50.0,
        metavar="MB",
        help="past MB MiB the --snapshots file is finished (an MCAP file indexed) and moved to FILE.1, the one before dropped; default 50",
    )
    p.add_argument("--can", metavar="IFACE:CHANNEL", help="the AgileX base's CAN bus (socketcan:can0, slcan:/dev/ttyACM0@115200, virtual:x...)")
    p.add_argument("--can-log", metavar="FILE", help="record the CAN bus (candump .log format) while running")
    p.add_argument("--obstacles", metavar="URL", help="a camera's obstacle distances (JSON over UDP, udpin:HOST:PORT), sent on as OBSTACLE_DISTANCE")
    p.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help="the live view in a browser on PORT (127.0.0.1 unless HOST is given; beyond it the buttons need the token printed at start-up)",
    )
    p.add_argument(
        "--groot2",
        metavar="[HOST:]PORT",
        help="serve the running tree to Groot2 (BehaviorTree.CPP's monitor protocol, ZeroMQ) on PORT and PORT+1 (127.0.0.1 unless HOST is given)",
    )
    p.add_argument(
        "--foxglove",
        metavar="[HOST:]PORT",
        help="serve the run live to Foxglove (its WebSocket protocol) on PORT, the channels of --snapshots FILE.mcap (127.0.0.1 unless HOST)",
    )
    p.add_argument("--web-token-file", metavar="FILE", help="the live view's token (its first line, >= 16 characters), instead of a new one")
    p.add_argument(
        "-v", "--verbose", action="count", default=0, help="more log output (default: warnings and the operator's events; -v all info, -vv debug)"
    )
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from executive.cli.run import main

    return main(args)
