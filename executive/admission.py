"""Whether a mission may run on this executive's vehicle: the part of ``executive run``'s checks that depends on the mission.

``executive run`` (and ``run --wait``, ``service install``) ask it of the mission file before anything
is opened (:func:`executive.cli.run_checks.check_run`); a running executive asks it of every
mission ``ctl upload`` brings, with the vehicle's firmware and whether it is the built-in simulator.
"""

from __future__ import annotations

from executive.io.instruments import refusal as instrument_refusal
from executive.mission.model import Mission, autopilot_errors


def refusals(mission: Mission, *, autopilot: str | None, simulator: bool, autopilot_said_as: str | None = None) -> list[str]:
    """Why ``mission`` cannot run here (empty: it can), each as a person reads it.

    ``autopilot``: the firmware that drives the vehicle (None: not known yet, nothing to check);
    ``simulator``: the vehicle is the built-in simulator (False: its samples must come from a real
    instrument); ``autopilot_said_as``: how the firmware is named in the reason (``--autopilot px4``),
    by default ``autopilot px4``.
    """
    found = []
    if autopilot is not None and (errors := autopilot_errors(mission, autopilot)):
        found.append(f"{autopilot_said_as or f'autopilot {autopilot}'}: {'; '.join(errors)}")
    why = instrument_refusal(mission, simulator=simulator)
    if why is not None:
        found.append(why)
    return found
