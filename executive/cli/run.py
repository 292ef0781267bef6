"""``executive run MISSION``: the onboard runtime, against a vehicle or the built-in simulator."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_NO_VEHICLE, EXIT_OK
from executive.cli.common import faults_or_report, load_or_report, setup_logging, signing_key_arg
from executive.clock import ScaledClock
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission, SimulatorOptions
from executive.progress import Progress
from executive.runtime import Runtime

if TYPE_CHECKING:
    from executive.sim.faults import FaultInjector


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a mission (on the built-in simulated vehicle unless --mavlink is given)")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--mavlink", metavar="URL", help="autopilot link: udpin:0.0.0.0:14550, tcp:HOST:PORT, /dev/ttyACM0[,BAUD]")
    p.add_argument("--rate", type=float, default=10.0, metavar="HZ", help="tick rate (default 10)")
    p.add_argument("--speedup", type=float, default=1.0, metavar="X", help="simulator only: run X times faster than real time")
    p.add_argument("--sysid", type=int, default=1, help="our MAVLink system id (default 1, the vehicle's)")
    p.add_argument("--connect-timeout", type=float, default=30.0, metavar="S", help="seconds to wait for the autopilot (default 30)")
    p.add_argument("--faults", metavar="FILE", help="simulator only: YAML list of faults to inject into the simulated vehicle")
    p.add_argument("--tlog", metavar="FILE", help="record the whole MAVLink link in FILE (.tlog, for Mission Planner and pymavlink)")
    p.add_argument("--signing-key", metavar="FILE", help="MAVLink 2 signing key (32 bytes, 64 hex digits or a passphrase)")
    p.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-v info, -vv debug)")
    p.set_defaults(func=main)


@contextlib.contextmanager
def _vehicle_link(
    args: argparse.Namespace, mission: Mission, clock: ScaledClock, faults: FaultInjector | None, signing_key: bytes | None
) -> Iterator[PymavlinkLink]:
    """A link to the vehicle named by --mavlink, or to a simulated one started here."""
    options = {"system_id": args.sysid, "signing_key": signing_key, "tlog": args.tlog}
    if args.mavlink:
        link = PymavlinkLink(args.mavlink, **options)
        try:
            yield link
        finally:
            link.close()
        return
    from executive.sim import SimServer
    from executive.sim.autopilot import DEFAULT_HOME

    start = mission.home or (mission.waypoints[0] if mission.waypoints else None)
    home = (start.lat, start.lon, getattr(start, "heading_deg", 0.0)) if start else DEFAULT_HOME
    sim_options = mission.simulator or SimulatorOptions()
    model = sim_options.model or mission.vehicle
    with SimServer(model, clock=clock, home=home, faults=faults, signing_key=signing_key, ekf_ready_after_s=sim_options.ekf_ready_after_s) as sim:
        print(f"executive: simulated {model} on {sim.url_for_client} (speed-up {clock.speedup:g}x)", file=sys.stderr)
        link = PymavlinkLink(sim.url_for_client, **options)
        try:
            yield link
        finally:
            link.close()


def _event_files(args: argparse.Namespace, mission: Mission) -> list[str]:
    """The mission's simulator event file (relative to the mission file) and --faults, in that order."""
    files = []
    if mission.simulator and mission.simulator.events:
        files.append(str(Path(args.mission).parent / mission.simulator.events))
    if args.faults:
        files.append(args.faults)
    return files


def main(args: argparse.Namespace) -> int:
    setup_logging(args.verbose)
    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    if args.rate <= 0 or args.speedup <= 0:
        print("executive: run: --rate and --speedup must be > 0", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.mavlink and args.speedup != 1.0:
        print("executive: run: --speedup applies to the simulator only; ignored with --mavlink", file=sys.stderr)
    clock = ScaledClock(1.0 if args.mavlink else args.speedup)
    faults = None
    if args.faults is not None and args.mavlink:
        print("executive: run: --faults applies to the built-in simulator only; it cannot be used with --mavlink", file=sys.stderr)
        return EXIT_BAD_INPUT
    event_files = [] if args.mavlink else _event_files(args, mission)
    if event_files:
        faults = faults_or_report(event_files, mission.vehicle, clock)
        if faults is None:
            return EXIT_BAD_INPUT
    signing_key = signing_key_arg(args.signing_key)
    with _vehicle_link(args, mission, clock, faults, signing_key) as link:
        runtime = Runtime(mission, link, clock, rate_hz=args.rate, system_id=args.sysid, progress=Progress(sys.stdout, clock))
        if not runtime.connect(args.connect_timeout * clock.speedup):
            print(f"executive: run: no heartbeat from an autopilot within {args.connect_timeout:g} s", file=sys.stderr)
            return EXIT_NO_VEHICLE
        previous = {sig: signal.signal(sig, lambda s, _f: runtime.request_stop(signal.Signals(s).name)) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            outcome = runtime.run()
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
    print(f"executive: mission {mission.name!r} {outcome.status}: {outcome.reason} ({outcome.ticks} ticks)", file=sys.stderr)
    return EXIT_OK if outcome.status is MissionStatus.COMPLETED else EXIT_FAILED
