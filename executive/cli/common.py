"""Helpers shared by subcommands: loading a mission the CLI way, its signing key, MAVLink ids."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from executive.cli import BadInput, number

if TYPE_CHECKING:
    from executive.mission.errors import MissionError
    from executive.mission.model import Mission
    from executive.sim.faults import FaultInjector
    from executive.world.clock import Clock


def print_errors(exc: MissionError) -> None:
    """Every located error of a refused file, one per line, on stderr."""
    for error in exc.errors:
        print(error, file=sys.stderr)


def load_or_report(path: str) -> Mission | None:
    """The mission in ``path``, or ``None`` after printing every error to stderr."""
    from executive.admission.checks import load_mission
    from executive.mission.errors import MissionError

    try:
        return load_mission(path)
    except MissionError as exc:
        print_errors(exc)
        return None


def faults_or_report(paths: list[str], vehicle: str, clock: Clock, autopilot: str = "ardupilot") -> FaultInjector | None:
    """One fault injector playing every event/fault file in ``paths``, or ``None`` after printing every error."""
    from executive.mission.errors import MissionError
    from executive.sim.faults import FaultInjector, load_faults

    faults = []
    try:
        for path in paths:
            faults += load_faults(path, vehicle=vehicle, autopilot=autopilot).faults
    except MissionError as exc:
        print_errors(exc)
        return None
    return FaultInjector(faults, clock)


def signing_key_arg(path: str | None) -> bytes | None:
    """The signing key of ``--signing-key`` (None without one); BadInput if it cannot be read."""
    if path is None:
        return None
    from executive.io.mavlink.link import load_signing_key

    try:
        return load_signing_key(path)
    except (OSError, ValueError) as exc:
        raise BadInput(f"--signing-key: {exc}") from exc


#: A MAVLink system or component id: 1-255.
mavlink_id = number(int, at_least=1, at_most=255)
