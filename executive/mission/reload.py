"""Hot reload: whether a paused mission may be replaced by another, the leg it continues from, and the samples it keeps.

A replacement is made only while PAUSED (``executive ctl upload MISSION [--leg N]``). It is
*compatible* when the new mission is for the same kind of vehicle, names no other autopilot than
the one driven (and that autopilot can fly it), and has the same ``rc:`` section (the RC inputs
and the take-over watch are wired when the executive starts: a person's take-over must be read
as the running mission reads it).

The leg: the waypoint the vehicle was heading for, found in the new mission (the same place,
within the new mission's ``limits.acceptance_radius_m``; of several, the one numbered nearest);
or the one the operator names (``--leg N``, 1-based). A current waypoint that is not in the new
mission, or a finished route, needs ``--leg``.

The samples: a sample taken at a waypoint is kept for the new mission's waypoint at the same
place, renumbered to its leg, so it is never taken again; one whose place is not in the new
mission is left out (the journal's run of the old mission keeps it).

Everything here is a pure function of the two missions: :func:`plan` raises :class:`Incompatible`
with the reason, and changes nothing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from executive.mission.model import Mission, Waypoint, waypoint_label
from executive.mission.rules import autopilot_errors
from executive.world.geo import distance
from executive.world.state import SampleRecord

#: The outcome a journal gives the run of a mission that another replaced (the run of the new one continues it).
REPLACED = "REPLACED"


class Incompatible(ValueError):
    """The new mission cannot replace the paused one; ``str()`` says why."""


@dataclass(frozen=True)
class Replacement:
    """What replacing the paused mission would do: the new mission, the leg it continues from, the samples it keeps."""

    mission: Mission
    leg_index: int  # 0-based, in the new mission
    samples: tuple[SampleRecord, ...]  # renumbered to the new mission's legs
    left_out: tuple[int, ...]  # 0-based legs of the old mission whose samples have no place in the new one
    leg_reason: str  # how the leg was chosen, for a person

    def describe(self, old: Mission) -> str:
        """``mission replaced: 'a' -> 'b', at leg 2/5 (the same waypoint, ...); 1 sample kept (leg 3)``."""
        at = f"at leg {self.leg_index + 1}/{len(self.mission.waypoints)} ({self.leg_reason})"
        words = [f"mission replaced: {old.name!r} -> {self.mission.name!r}, {at}"]
        if self.samples:
            kept = ", ".join(str(s.leg_index + 1) for s in self.samples)
            words.append(f"{len(self.samples)} sample{'' if len(self.samples) == 1 else 's'} kept (leg {kept})")
        if self.left_out:
            legs = ", ".join(str(i + 1) for i in self.left_out)
            words.append(f"not in the new mission: the sample{'' if len(self.left_out) == 1 else 's'} of old leg {legs}")
        return "; ".join(words)


def plan(
    old: Mission, leg_index: int, samples: Sequence[SampleRecord], new: Mission, *, autopilot: str | None, leg: int | None = None
) -> Replacement:
    """How ``new`` would replace ``old`` (paused at ``leg_index`` with ``samples``), driven by ``autopilot``; ``leg``: the 1-based leg chosen.

    Raises :class:`Incompatible` with the reason.
    """
    problems = incompatibilities(old, new, autopilot)
    if problems:
        raise Incompatible("; ".join(problems))
    if leg is not None:
        if not 1 <= leg <= len(new.waypoints):
            raise Incompatible(f"--leg {leg}: {new.name!r} has {len(new.waypoints)} waypoints (1-{len(new.waypoints)})")
        new_leg, why = leg - 1, "chosen by the operator"
    else:
        new_leg, why = _same_leg(old, leg_index, new)
    kept, left_out = _carry_samples(old, samples, new)
    return Replacement(new, new_leg, kept, left_out, why)


def incompatibilities(old: Mission, new: Mission, autopilot: str | None) -> list[str]:
    """Why ``new`` cannot replace ``old`` on this vehicle, whatever the leg (empty when it can)."""
    problems = []
    if new.vehicle != old.vehicle:
        problems.append(f"vehicle: the running mission is for a {old.vehicle}, this one for a {new.vehicle}")
    if autopilot is not None:
        if new.autopilot is not None and new.autopilot != autopilot:
            problems.append(f"autopilot: the vehicle runs {autopilot}, the mission is for {new.autopilot}")
        problems += [f"autopilot: {why}" for why in autopilot_errors(new, autopilot)]
    if new.rc != old.rc:
        problems.append("rc: differs from the running mission's (the RC inputs and the take-over watch are wired when the executive starts)")
    return problems


def _same_leg(old: Mission, leg_index: int, new: Mission) -> tuple[int, str]:
    """The new leg heading for the waypoint the vehicle was heading for; Incompatible when there is none."""
    if leg_index >= len(old.waypoints):
        raise Incompatible(f"every waypoint of {old.name!r} is done: choose the leg to continue from (ctl upload MISSION --leg N)")
    target = old.waypoints[leg_index]
    found = _same_place(target, leg_index, new)
    if found is None:
        raise Incompatible(
            f"the waypoint the vehicle heads for ({_named(target, leg_index)}) is not in {new.name!r}: "
            "choose the leg to continue from (ctl upload MISSION --leg N)"
        )
    return found, f"the waypoint of old leg {leg_index + 1}" + (f", {target.name!r}" if target.name else "")


def _carry_samples(old: Mission, samples: Sequence[SampleRecord], new: Mission) -> tuple[tuple[SampleRecord, ...], tuple[int, ...]]:
    kept: list[SampleRecord] = []
    left_out: list[int] = []
    for sample in sorted((s for s in samples if s.complete), key=lambda s: s.leg_index):  # a partial one did not do its point
        taken = {s.leg_index for s in kept}
        found = None
        if sample.leg_index < len(old.waypoints):
            found = _same_place(old.waypoints[sample.leg_index], sample.leg_index, new, exclude=taken)
        if found is None:
            left_out.append(sample.leg_index)
        else:
            kept.append(replace(sample, leg_index=found))
    return tuple(kept), tuple(left_out)


def _same_place(waypoint: Waypoint, index: int, new: Mission, exclude: set[int] | frozenset[int] = frozenset()) -> int | None:
    """The index of the new mission's waypoint at ``waypoint``'s place (within its acceptance radius), the one numbered nearest ``index``."""
    radius = new.limits.acceptance_radius_m
    here = [i for i, wp in enumerate(new.waypoints) if i not in exclude and distance(waypoint.lat, waypoint.lon, wp.lat, wp.lon) <= radius]
    return min(here, key=lambda i: (abs(i - index), i)) if here else None


def _named(waypoint: Waypoint, index: int) -> str:
    return f"{waypoint_label(index, waypoint.name)} at {waypoint.lat:.7f}, {waypoint.lon:.7f}"


__all__ = ["REPLACED", "Incompatible", "Replacement", "incompatibilities", "plan"]
