"""Whether a mission can run on this executive: what reading the file (:mod:`executive.mission`) cannot tell alone.

:mod:`executive.mission` reads and validates a mission file by itself (its schema, the rules between
its fields). Whether it can run here needs the trees, the plugins and the instruments: its ``tree:``
must be found (built in, a plugin's, ``module:function``) or, composed in the file, be made of the
node catalogue; its instrument's options must be those of its back end (:func:`load_mission`, every
error located in the file); the vehicle's firmware must drive it and its samples must be real
against a real vehicle (:func:`refusals`); every installed plugin must load (:func:`plugin_problems`).

``executive run`` (and ``run --wait``, ``service install``) and ``executive validate`` ask it of the
mission file before anything is opened (:func:`executive.cli.run_checks.check_mission`); a running
executive asks it of every mission ``ctl upload`` brings, with the vehicle's firmware and whether it
is the built-in simulator.
"""

from __future__ import annotations

import os

from executive import registry, trees
from executive.instruments.backends import option_errors, plugin_backend
from executive.instruments.backends import refusal as instrument_refusal
from executive.mission import loader
from executive.mission.errors import Path
from executive.mission.model import Mission
from executive.mission.rules import autopilot_errors, cross_field_errors
from executive.sensing.energy import planned
from executive.tree import composition
from executive.tree import select as mission_tree
from executive.tree.catalogue import plugin_behaviour


def mission_errors(mission: Mission) -> list[tuple[Path, str]]:
    """The rules between the mission's fields, its instrument's options, and its tree: each error the path of the offending value and why."""
    errors = cross_field_errors(mission)
    energy = planned(mission)
    if energy is not None and not isinstance(energy, str) and not energy.fits:  # not even on a full pack
        errors.append((("energy",), f"the route and the way home do not fit a full pack: {energy.figures()}"))
    if mission.sampling is not None and mission.sampling.instrument is not None:
        errors += option_errors(mission.sampling.instrument, ("sampling", "instrument"))
    if not isinstance(mission.tree, str):
        try:
            return errors + composition.errors(mission)
        except registry.PluginError as exc:
            return [*errors, (("tree",), str(exc))]
    try:
        mission_tree.build(mission)  # as run builds it: a user's tree that raises is refused here too
    except (trees.UnknownTree, registry.PluginError) as exc:
        errors.append((("tree",), str(exc)))
    return errors


def load_mission(path: str | os.PathLike[str]) -> Mission:
    """Read a mission file and check it can be built here (:func:`mission_errors`); MissionError listing every problem, located."""
    return loader.load_mission(path, mission_errors)


def load_mission_text(text: str, filename: str) -> Mission:
    """Mission YAML ``text`` read and checked as :func:`load_mission` does; ``filename`` is only used to locate errors."""
    return loader.load_mission_text(text, filename, mission_errors)


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


def plugin_problems() -> list[registry.PluginError]:
    """Every installed tree, behaviour and instrument plugin that cannot be loaded or is not what its group needs (empty: all load)."""
    errors: list[registry.PluginError] = []
    checks = ((registry.TREES, trees.plugin_tree), (registry.BEHAVIOURS, plugin_behaviour), (registry.INSTRUMENTS, plugin_backend))
    for group, check in checks:
        for point in registry.named(group).values():
            try:
                check(point)
            except registry.PluginError as exc:
                errors.append(exc)
    return errors
