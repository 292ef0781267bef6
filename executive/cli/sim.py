"""``executive sim``: the simulated vehicle alone, for a separate executive or a ground station."""

from __future__ import annotations

import argparse
import logging
import re
import signal
import threading
from types import FrameType
from typing import TYPE_CHECKING

from executive.cli import EXIT_BAD_INPUT, EXIT_OK, BadInput, NoVehicle, number
from executive.cli.common import faults_or_report, mavlink_id, signing_key_arg
from executive.cli.examples import fault_file
from executive.io.mavlink.endpoint import unreachable
from executive.mission.declaration import plugin_kinds
from executive.operator.logs import setup_logging
from executive.sim.clients import ClientAddressError
from executive.sim.firmware import DEFAULT_HOME, Home
from executive.sim.registry import AUTOPILOTS, FIRMWARES, firmwares_for, simulated_model
from executive.sim.server import SimServer
from executive.world.clock import ScaledClock

if TYPE_CHECKING:
    import can

    from executive.sim.faults import FaultInjector


def _home(text: str) -> Home:
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LAT,LON[,HEADING] in degrees, got {text!r}") from None
    if len(values) not in (2, 3) or abs(values[0]) > 90 or abs(values[1]) > 180:
        raise argparse.ArgumentTypeError(f"expected LAT,LON[,HEADING] in degrees, got {text!r}")
    return values[0], values[1], values[2] if len(values) == 3 else 0.0


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "sim",
        help="run the simulated vehicle alone",
        description="Run a simulated ArduPilot or PX4 vehicle speaking MAVLink 2, until Ctrl-C or SIGTERM.",
    )
    # let "--home -35.36,149.16" through: argparse would take a negative latitude for an option
    parser._negative_number_matcher = re.compile(r"^-\.?\d[\d.,]*$")
    kinds = sorted(AUTOPILOTS) + sorted(kind for kind, spec in plugin_kinds().items() if spec.simulator is not None)  # a plugin's: on what it rides
    parser.add_argument("--vehicle", choices=kinds, default="rover", help="vehicle kind (default: %(default)s)")
    firmware = "the simulated autopilot firmware (default: %(default)s; px4 simulates the vtol and the rover)"
    parser.add_argument("--autopilot", choices=FIRMWARES, default="ardupilot", help=firmware)
    where = "where to listen: tcpin:HOST:PORT or udpin:HOST:PORT (default: %(default)s, as SITL)"
    parser.add_argument("--mavlink", metavar="URL", default="tcpin:127.0.0.1:5760", help=where)
    start = "start position and heading in degrees (default: ArduPilot SITL's CMAC)"
    parser.add_argument("--home", metavar="LAT,LON[,HEADING]", type=_home, default=DEFAULT_HOME, help=start)
    positive, non_negative = number(above=0), number(at_least=0)
    parser.add_argument("--speedup", metavar="X", type=positive, default=1.0, help="simulated time runs X times faster")
    ekf = "simulated seconds before the EKF uses GPS and arming is possible (default: the firmware's, ArduPilot 40, PX4 3)"
    parser.add_argument("--ekf-ready-after", metavar="S", type=non_negative, help=ekf)
    sysid = "the vehicle's MAVLink system id, 1-255 (SYSID_THISMAV; default: %(default)s)"
    parser.add_argument("--sysid", metavar="N", type=mavlink_id, default=1, help=sysid)
    parser.add_argument("--duration", metavar="S", type=positive, help="exit after S simulated seconds")
    parser.add_argument("--faults", metavar="FILE", type=fault_file, help="YAML list of faults to inject (link loss, EKF, GPS, compass, RC, battery)")
    parser.add_argument("--signing-key", metavar="FILE", help="MAVLink 2 signing key: sign everything, drop unsigned packets")
    can_help = "bunker: the AgileX base on this CAN bus (socketcan:vcan0, virtual:x...): RC and state frames out, motion commands in"
    parser.add_argument("--can", metavar="IFACE:CHANNEL", help=can_help)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Serve the simulated vehicle in the foreground; each MAVLink client that comes and goes is logged."""
    setup_logging()
    logging.getLogger("executive.sim.clients").setLevel(logging.INFO)
    if simulated_model(args.vehicle) not in firmwares_for(args.autopilot):
        known = ", ".join(firmwares_for(args.autopilot))
        raise BadInput(f"no simulated {args.autopilot} {args.vehicle} (known: {known})")
    if args.can is not None and args.vehicle != "bunker":
        raise BadInput(f"--can simulates the AgileX base of the tracked UGV: use it with --vehicle bunker, not {args.vehicle}")
    clock = ScaledClock(args.speedup)
    faults = None
    if args.faults is not None:
        faults = faults_or_report([args.faults], args.vehicle, clock, args.autopilot)
        if faults is None:
            return EXIT_BAD_INPUT
    signing_key = signing_key_arg(args.signing_key)
    can_bus = None
    if args.can is not None:
        from executive.io.can import CanOpenError, CanSpecError, open_can

        try:
            can_bus = open_can(args.can)
        except CanSpecError as exc:
            raise BadInput(f"--can: {exc}") from exc
        except CanOpenError as exc:
            raise NoVehicle(f"--can: {exc}") from exc
    try:
        return _serve(args, clock, faults, signing_key, can_bus)
    finally:
        if can_bus is not None:
            can_bus.shutdown()


def _serve(args: argparse.Namespace, clock: ScaledClock, faults: FaultInjector | None, signing_key: bytes | None, can_bus: can.BusABC | None) -> int:
    try:
        server = SimServer(
            args.vehicle,
            args.mavlink,
            clock=clock,
            home=args.home,
            system_id=args.sysid,
            ekf_ready_after_s=args.ekf_ready_after,
            faults=faults,
            signing_key=signing_key,
            can_bus=can_bus,
            autopilot=args.autopilot,
        )
    except ClientAddressError as exc:
        raise BadInput(f"--mavlink {exc}") from exc
    except OSError as exc:  # as run: an address that cannot be listened on is a vehicle that cannot be reached
        raise NoVehicle(f"--mavlink {unreachable(args.mavlink, exc)}") from exc
    done = threading.Event()

    def on_sigterm(signum: int, frame: FrameType | None) -> None:
        done.set()

    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, on_sigterm) if in_main_thread else None
    ap = server.autopilot
    print(
        f"executive: sim: {ap.FIRMWARE} {args.vehicle} listening on {args.mavlink} (connect to {server.url_for_client}), "
        f"system {args.sysid}, speed-up {args.speedup:g}x",
        flush=True,
    )
    if faults is not None:
        print(f"executive: sim: injecting {len(faults.faults)} fault(s) from {args.faults}", flush=True)
    if can_bus is not None:
        only_here = " (a virtual bus is seen only by this process)" if args.can.lower().startswith("virtual:") else ""
        print(f"executive: sim: AgileX base on CAN {args.can}{only_here}", flush=True)
    end = None if args.duration is None else clock.now() + args.duration
    try:
        with server:
            while not done.wait(0.05):
                if end is not None and clock.now() >= end:
                    break
    except KeyboardInterrupt:
        pass
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous)
    return EXIT_OK
