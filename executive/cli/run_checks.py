"""What ``executive run`` refuses before anything is opened, in one function every way to start calls.

``executive run`` and ``run --wait`` call :func:`check_run` first thing; ``executive service install``
calls it on the very command line its unit will run (so a service is never installed to fail at
boot with exit 2, which its ``RestartPreventExitStatus`` would then never retry); ``executive
validate`` calls the mission's part of it (:func:`check_mission`: :func:`executive.admission.checks.refusals`
and the mission's simulator event file), and a running executive checks each mission ``ctl upload``
brings with :func:`executive.admission.checks.refusals`. A refusal is :class:`~executive.cli.BadInput`
(exit 2) naming the option or the mission field and why. What only the moment of starting can tell (an
instrument that does not open, a control socket another executive serves, a port in use) is
``run``'s alone.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from executive.admission import checks as admission
from executive.cli import BadInput
from executive.cli.common import print_errors, signing_key_arg
from executive.io.mavlink.endpoint import BadEndpoint, check_endpoint
from executive.mission.errors import MissionError
from executive.mission.model import Mission
from executive.runtime.pacing import MAX_TICKS_PER_WALL_S

if TYPE_CHECKING:
    from executive.sim.faults import Fault


@dataclass(frozen=True)
class Checked:
    """What the checks read, for ``run`` to go on with."""

    faults: tuple[Fault, ...]  # the built-in simulator's event and fault files, loaded (none with --mavlink)
    signing_key: bytes | None  # --signing-key, read
    notes: tuple[str, ...] = ()  # said on stderr before the run starts


def mission_events(mission_file: str, mission: Mission) -> list[str]:
    """The mission's simulator event file, relative to the mission file (none when it names none)."""
    if mission.simulator and mission.simulator.events:
        return [str(Path(mission_file).parent / mission.simulator.events)]
    return []


def event_files(args: argparse.Namespace, mission: Mission) -> list[str]:
    """The mission's simulator event file (relative to the mission file) and --faults, in that order (none with --mavlink)."""
    if args.mavlink:
        return []
    return mission_events(args.mission, mission) + ([args.faults] if args.faults else [])


def refusal(mission: Mission, *, autopilot: str | None, simulator: bool) -> str | None:
    """The first reason ``mission`` cannot run with ``--autopilot`` ``autopilot`` on the built-in ``simulator`` or a real vehicle."""
    said_as = f"--autopilot {autopilot}" if autopilot else None
    refused = admission.refusals(mission, autopilot=autopilot, simulator=simulator, autopilot_said_as=said_as)
    return refused[0] if refused else None


def check_mission(mission_file: str, mission: Mission, *, autopilot: str | None, simulator: bool) -> None:
    """What ``run`` refuses of the mission itself, with ``--autopilot`` ``autopilot``, on the built-in ``simulator`` (else ``--mavlink``).

    BadInput with the first refusal (:func:`executive.admission.checks.refusals`); MissionError with every
    located error of the mission's simulator event file (read with the simulator only). The same
    checks and words as :func:`check_run`'s.
    """
    if (why := refusal(mission, autopilot=autopilot, simulator=simulator)) is not None:
        raise BadInput(why)
    if simulator:
        _read_faults(mission_events(mission_file, mission), mission.vehicle)


def speedup_refusal(rate_hz: float, speedup: float) -> str | None:
    """Why the built-in simulator cannot run ``speedup`` times faster at ``rate_hz`` ticks a second, if it cannot.

    ``rate_hz * speedup`` ticks per wall second at :data:`~executive.runtime.pacing.MAX_TICKS_PER_WALL_S` or more
    is refused: ``--speedup 200`` at 10 Hz is 2000.
    """
    asked = rate_hz * speedup
    if asked < MAX_TICKS_PER_WALL_S:
        return None
    most = MAX_TICKS_PER_WALL_S / rate_hz
    return (
        f"--speedup {speedup:g}: the executive cannot follow it: {rate_hz:g} ticks per second of vehicle time would be {asked:g} per "
        f"second of wall time, and it keeps up with fewer than {MAX_TICKS_PER_WALL_S:g} (--speedup below {most:g} at --rate {rate_hz:g}); "
        "on a busy machine the speed-up is capped lower as it runs"
    )


def check_run(args: argparse.Namespace, mission: Mission) -> Checked:
    """``executive run``'s checks of ``args`` (its parsed options) and ``mission``: BadInput with the first refusal; nothing opened or sent."""
    for option, value in (("--rate", args.rate), ("--speedup", args.speedup)):
        if not value > 0 or value == float("inf"):  # NaN is no number of anything
            raise BadInput(f"{option} {value:g}: must be a number > 0")
    if args.resume and not args.journal:
        raise BadInput("--resume needs --journal DB")
    simulator = not args.mavlink
    if (why := refusal(mission, autopilot=args.autopilot, simulator=simulator)) is not None:
        raise BadInput(why)
    if mission.rc.source == "can" and not args.can:  # else the RC guard waits out its limit for a report that never comes
        raise BadInput(
            f"{args.mission}: rc.source: can reads the transmitter from the AgileX base's CAN bus (frame 0x241): give --can IFACE:CHANNEL "
            "(socketcan:can0, slcan:/dev/ttyACM0@115200; with the built-in simulator a virtual:NAME bus), or rc.source: mavlink"
        )
    notes = []
    if args.mavlink and args.speedup != 1.0:
        # a SITL at --speedup 5 drives 5 s in each wall second: ticking on the wall clock, the executive would react five times
        # less often in the vehicle's time (issue 14: GUIDED 44.4 s at 1x, 49.2 s at 10x)
        notes.append(f"the vehicle's time runs {args.speedup:g}x real time (a simulator's speed-up)")
    elif simulator and (why := speedup_refusal(args.rate, args.speedup)) is not None:
        raise BadInput(why)
    if args.faults is not None and args.mavlink:
        raise BadInput("--faults applies to the built-in simulator only; it cannot be used with --mavlink")
    faults = _load_faults(event_files(args, mission), mission.vehicle)
    for option, url in (("--mavlink", args.mavlink), ("--gcs", args.gcs)):
        if url is not None:
            try:
                check_endpoint(url)
            except BadEndpoint as exc:
                raise BadInput(f"{option} {exc}") from exc
    signing_key = signing_key_arg(args.signing_key)
    _check_other_inputs(args)
    if (why := vehicle_option_refusal(args, mission)) is not None:
        raise BadInput(why)
    return Checked(faults, signing_key, tuple(notes))


def _load_faults(paths: list[str], vehicle: str) -> tuple[Fault, ...]:
    """Every fault and event of ``paths``; BadInput after printing each located error."""
    try:
        return _read_faults(paths, vehicle)
    except MissionError as exc:
        print_errors(exc)
        raise BadInput(f"{len(exc.errors)} error(s) in the simulator's event and fault files (above): nothing was started") from exc


def _read_faults(paths: list[str], vehicle: str) -> tuple[Fault, ...]:
    """Every fault and event of ``paths``; MissionError naming each located error."""
    if not paths:
        return ()
    from executive.sim.faults import load_faults

    faults: list[Fault] = []
    for path in paths:
        faults += load_faults(path, vehicle=vehicle).faults
    return tuple(faults)


def _check_other_inputs(args: argparse.Namespace) -> None:
    """The camera's, the CAN bus's and the live view's options: their form, and the options they need."""
    if args.obstacles is not None:
        from executive.io.obstacles import ObstacleSpecError, parse_endpoint

        try:
            parse_endpoint(args.obstacles)
        except ObstacleSpecError as exc:
            raise BadInput(f"--obstacles: {exc}") from exc
    if args.can is None and args.can_log:
        raise BadInput("--can-log needs --can IFACE:CHANNEL")
    if args.can is not None:
        from executive.io.can import CanSpecError
        from executive.io.can.bus import parse_spec

        try:
            parse_spec(args.can)
        except CanSpecError as exc:
            raise BadInput(f"--can: {exc}") from exc
    if args.web is None and args.web_token_file:
        raise BadInput("--web-token-file needs --web [HOST:]PORT")
    if args.web is not None:
        from executive.observers.web.server import WebAddressError, parse_address, read_token

        try:
            parse_address(args.web)
            if args.web_token_file:
                read_token(args.web_token_file)
        except WebAddressError as exc:
            raise BadInput(f"--web: {exc}") from exc


def vehicle_option_refusal(args: argparse.Namespace, mission: Mission) -> str | None:
    """Why an option of ``run`` does not fit the mission's vehicle, if one does not (docs/running.md lists them under the run options).

    ``--can`` is the AgileX tracked base's bus, driven from ArduRover's skid-steer outputs: SERVO1 the left track, SERVO3
    the right (``libraries/AR_Motors/AP_MotorsUGV.cpp`` output_skid_steering; SERVO1_FUNCTION 73 and SERVO3_FUNCTION 74,
    ``libraries/SRV_Channel/SRV_Channel.h``). Only a rover on ArduPilot has them; on the built-in simulator only the
    ``bunker`` model is skid-steered with a base on the bus (another's steering and throttle would be read as tracks).
    """
    if args.can is None:
        return None
    base = "--can: the bus of the AgileX tracked base, driven from ArduRover's skid-steer outputs (SERVO1 left track, SERVO3 right)"
    if mission.vehicle != "rover":
        return f"{base}: this mission drives a {mission.vehicle} (vehicle: {mission.vehicle}), which has no tracks to drive"
    autopilot = args.autopilot or mission.autopilot
    if autopilot == "px4":
        return f"{base}: the autopilot is PX4 (--autopilot/autopilot: px4), whose rover outputs are not ArduRover's skid-steer channels"
    model = (mission.simulator.model if mission.simulator else None) or mission.vehicle
    if not args.mavlink and model != "bunker":
        return f"{base}: the built-in simulator's {model} has no tracked base on a bus (simulator.model: bunker simulates one)"
    return None
