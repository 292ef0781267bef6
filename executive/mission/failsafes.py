"""The failsafe policy tables: per condition, the reaction and the recovery of each vehicle kind.

The ``failsafe:`` section says, per condition, what the executive does when it becomes true during
the guarded part of a mission: a *reaction* commanded in the same tick, then a *recovery* (resume
the same leg once the condition clears, within ``timeout_s``, default ``limits.recovery_timeout_s``;
or abort the mission at once, the vehicle left in the reaction's mode). An entry, or a field of
one, left out takes the default of the tree where it declares one (its ``DECLARATION``'s ``failsafes``,
:mod:`executive.mission.declaration`), else of the vehicle kind (:func:`executive.mission.rules.failsafe_policy`).
The vehicle kinds' defaults (reaction, recovery):

================  ==============  ==============  =================  ============================
condition         rover           boat            sub                vtol
================  ==============  ==============  =================  ============================
link_loss         hold, resume    loiter, resume  surface, resume    hold, resume
rc_takeover       wait, resume    wait, resume    wait, resume       wait, resume
disarmed          wait, resume    wait, resume    wait, resume       wait, resume
rc_loss           hold, resume    loiter, resume  hold, resume       hold, resume
ekf_loss          hold, resume    hold, resume    hold, resume       hold, resume
gps_glitch        hold, resume    hold, resume    hold, resume       hold, resume
heading_insane    hold, resume    hold, resume    hold, resume       hold, resume
battery_low       rtl, abort      rtl, abort      surface, abort     rtl, abort
geofence_breach   hold, abort     rtl, abort      surface, abort     rtl, abort
energy            rtl, abort      rtl, abort      surface, abort     rtl, abort
keep_out          rtl, abort      rtl, abort      surface, abort     rtl, abort
================  ==============  ==============  =================  ============================

rc_takeover and disarmed are a person's acts (or the autopilot's own failsafe's): a person always wins, so
their reaction is ``wait`` (hands off) and nothing else; any other is refused at load
(:data:`PERSON_CONDITIONS`). Their recovery is the mission's to choose.

A tree's own defaults are in its declaration (``executive behaviours --trees`` lists them): the seed systems' differ.

Reactions (:data:`REACTION_MODES`): ``hold`` rover/boat HOLD, sub POSHOLD, vtol QLOITER; ``loiter``
rover/boat LOITER, sub POSHOLD, vtol QLOITER; ``rtl`` rover/boat RTL, vtol QRTL (no sub); ``surface``
sub SURFACE only; ``disarm`` the manual mode, then disarm, re-armed on resume (no vtol); ``wait``
nothing: hands off. A vtol flying as a plane holds, loiters in LOITER and returns in RTL; it returns in RTL
from the moment a transition to fixed-wing flight starts, or at a wing-borne ground speed not yet reported as FW
(QRTL asked then would hover the whole way home: :mod:`executive.sensing.vtol_flight`).
heading_insane is judged on rovers and boats only (the heading filter checks the compass against
the course over ground, which a sub or a vtol does not follow); geofence_breach only with a
``geofence:`` section; rc_loss once an RC transmitter has been seen (or, a tree guarding fresh RC, stale RC); keep_out with
``geofence.keep_out`` zones, and never while a person has the vehicle (:data:`JUDGED_AFTER_PERSON`).

A return (``rtl``) of a rover or a boat on a mission with keep-out zones or rally points is the executive's own
where the firmware's RTL would not do (:mod:`executive.behaviours.returning`): to the nearest rally point or home,
around the zones, in GUIDED legs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

FailsafeCondition = Literal[
    "link_loss",
    "rc_takeover",
    "disarmed",
    "rc_loss",
    "ekf_loss",
    "gps_glitch",
    "heading_insane",
    "battery_low",
    "geofence_breach",
    "energy",
    "keep_out",
]
FailsafeReaction = Literal["hold", "loiter", "rtl", "surface", "disarm", "wait"]
FailsafeRecovery = Literal["resume", "abort"]
FAILSAFE_CONDITIONS: tuple[str, ...] = get_args(FailsafeCondition)

#: reaction -> vehicle kind -> the mode it commands (a vtol flying as a plane: the second); a kind left out has no such reaction.
REACTION_MODES: dict[str, dict[str, tuple[str, str]]] = {
    "hold": {"rover": ("HOLD", "HOLD"), "boat": ("HOLD", "HOLD"), "sub": ("POSHOLD", "POSHOLD"), "vtol": ("QLOITER", "LOITER")},
    "loiter": {"rover": ("LOITER", "LOITER"), "boat": ("LOITER", "LOITER"), "sub": ("POSHOLD", "POSHOLD"), "vtol": ("QLOITER", "LOITER")},
    "rtl": {"rover": ("RTL", "RTL"), "boat": ("RTL", "RTL"), "vtol": ("QRTL", "RTL")},
    "surface": {"sub": ("SURFACE", "SURFACE")},
    "disarm": {"rover": ("MANUAL", "MANUAL"), "boat": ("MANUAL", "MANUAL"), "sub": ("MANUAL", "MANUAL")},
}
NO_REACTION = {"rtl": "a sub has no RTL: use surface", "surface": "only a sub can surface", "disarm": "disarming a vtol would drop it"}
#: Conditions that are a person's act: a person always wins, so their only reaction is ``wait`` (hands off); why, for the loader's error.
PERSON_CONDITIONS: dict[str, str] = {
    "rc_takeover": "a person who takes over always wins: the executive keeps its hands off (reaction wait), "
    "it never commands against the take-over switch",
    "disarmed": "a vehicle disarmed mid-mission was disarmed by a person (or by the autopilot's own failsafe), who always wins: "
    "the executive keeps its hands off (reaction wait)",
}

_R, _W, _A = "resume", "wait", "abort"
_COMMON = {"rc_takeover": (_W, _R), "disarmed": (_W, _R), "ekf_loss": ("hold", _R), "gps_glitch": ("hold", _R), "heading_insane": ("hold", _R)}
#: energy: home the shortest safe way while it still fits (RTL, where the firmware's RTL goes home); a sub surfaces.
_ENERGY = {"rover": ("rtl", _A), "boat": ("rtl", _A), "sub": ("surface", _A), "vtol": ("rtl", _A)}
#: The default failsafe policy of each vehicle kind: condition -> (reaction, recovery). The table in the module docstring.
VEHICLE_FAILSAFES: dict[str, dict[str, tuple[str, str]]] = {
    "rover": _COMMON | {"link_loss": ("hold", _R), "rc_loss": ("hold", _R), "battery_low": ("rtl", _A), "geofence_breach": ("hold", _A)},
    "boat": _COMMON | {"link_loss": ("loiter", _R), "rc_loss": ("loiter", _R), "battery_low": ("rtl", _A), "geofence_breach": ("rtl", _A)},
    "sub": _COMMON | {"link_loss": ("surface", _R), "rc_loss": ("hold", _R), "battery_low": ("surface", _A), "geofence_breach": ("surface", _A)},
    "vtol": _COMMON | {"link_loss": ("hold", _R), "rc_loss": ("hold", _R), "battery_low": ("rtl", _A), "geofence_breach": ("rtl", _A)},
}
for _kind, _rule in _ENERGY.items():
    VEHICLE_FAILSAFES[_kind]["energy"] = _rule
    # keep_out: a rover or a boat holds, then returns around the zones (behaviours.returning); a sub surfaces, a vtol returns
    VEHICLE_FAILSAFES[_kind]["keep_out"] = _rule
#: Conditions not judged while a person has the vehicle (a take-over, a mode a person drives in): a person who drives near a
#: pier does it on purpose. They act in the tick the person hands back, if still true then.
JUDGED_AFTER_PERSON = frozenset({"keep_out"})


@dataclass(frozen=True)
class FailsafePolicy:
    """One condition's policy, every field decided."""

    condition: str
    reaction: str
    recovery: str
    timeout_s: float
