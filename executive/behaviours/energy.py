"""The energy rule: the rest of the route and the way home must fit the battery above the mission's reserve.

:class:`EnergyFits` refuses a mission before arming when it does not fit (the figures in its
feedback: ``needs 41 Wh + 9 Wh home (+/- 6), has 38 Wh above the 20 % reserve``); :class:`EnergyEnough`
re-judges it every tick of the guarded route (the estimate moves at each battery report and each
leg) and, failing, is the failsafe condition ``energy``. Both read ``/energy/estimate``, made by
:class:`~executive.sensing.energy.EnergyWatch`.
"""

from __future__ import annotations

import logging

from py_trees.common import Status

from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.guards import Guard
from executive.sensing.energy import EnergyEstimate

log = logging.getLogger(__name__)

#: What a mission run unjudged is told to do about it.
UNJUDGED_HINT = "the battery floor (limits.battery_min_pct / battery_min_v) alone turns it back; energy: {check: off} says it is meant"

#: Once failed, the margin must be back above this share of the capacity to pass again: a margin hovering about zero does not flap.
HYSTERESIS_SHARE = 0.03


class EnergyEnough(Guard):
    """Enough energy to finish and return: the estimate's margin (left above the reserve, less the route, the way home and
    1 sigma) is not negative. Without an estimate it fails only for a mission that asked for the rule (``required``); for one
    that said nothing it passes unjudged (what the battery cannot tell is refused before arming by :class:`EnergyFits`).

    Debounce: fails after 5 s short (five battery reports: one noisy window does not turn the vehicle back); once failed,
    passes only after 10 s with the margin above 3 % of the capacity (hysteresis).
    """

    reads = ("/energy/estimate", "/energy/unknown", "/energy/not_judged")
    hold_after_s = 5.0
    resume_after_s = 10.0
    unknown_or_stale = (
        "no estimate (a battery that cannot tell its energy: /energy/unknown says what to set): fails; "
        "the estimate is re-made at each battery report (BATTERY_STATUS, 1 Hz)"
    )

    param_docs = {"required": "the mission asked for the rule (energy:): no estimate fails; else it passes unjudged (pre-flight refused)"}

    def __init__(self, required: bool = True, name: str = "Enough energy to finish and return?") -> None:
        super().__init__(name)
        self.required = required

    def awaits(self) -> str | None:
        if self.get("/energy/estimate") is not None or self.get("/energy/not_judged") or not self.required:
            return None
        return self.get("/energy/unknown") or "an energy estimate (BATTERY_STATUS)"

    def check(self) -> str | None:
        estimate: EnergyEstimate | None = self.get("/energy/estimate")
        if estimate is None and (why := self.get("/energy/not_judged") or (not self.required and "no estimate yet")):
            self.note = f"energy not judged: {why}"
            return None
        if estimate is None:
            return f"energy unknown: {self.get('/energy/unknown') or 'no estimate yet'}"
        floor = HYSTERESIS_SHARE * estimate.capacity_wh if self._failed else 0.0
        if estimate.margin_wh < floor:
            return f"energy short: {estimate.figures()}"
        self.note = estimate.figures()
        return None


class EnergyFits(TimedBehaviour):
    """Pre-flight: SUCCESS when the whole route and the way home fit; FAILURE with the figures when they do not, or, after
    ``timeout_s`` of the energy watch saying why it has none, naming what the battery cannot tell (what to set); while it
    says nothing yet (its model loading at a high speed-up), it waits. A mission without ``energy:`` on a
    battery that cannot tell its energy (``/energy/not_judged``): SUCCESS, with a warning saying so."""

    reads = ("/energy/estimate", "/energy/unknown", "/energy/not_judged")
    needs = ("clock",)
    param_docs = {"timeout_s": "FAILURE, naming what is missing, when no estimate has come by then"}

    def __init__(self, timeout_s: float = 10.0, name: str = "Route and way home fit the battery?") -> None:
        super().__init__(name)
        self.timeout_s = timeout_s

    def update(self) -> Status:
        estimate: EnergyEstimate | None = self.get("/energy/estimate")
        if estimate is None and (unjudged := self.get("/energy/not_judged")):
            self.feedback_message = f"energy not judged: {unjudged}"
            log.warning("energy not judged on this vehicle: %s; %s", unjudged, UNJUDGED_HINT)
            return SUCCESS
        if estimate is None:
            why = self.get("/energy/unknown")
            if not why:  # the energy watch has nothing to say yet (its model loading): the time to judge has not begun
                self.started = self.clock.now()
                self.feedback_message = "waiting for the energy estimate (the consumption model loading)"
                return RUNNING
            if self.elapsed > self.timeout_s:
                self.feedback_message = f"the energy rule cannot judge: {why}"
                return FAILURE
            self.feedback_message = f"waiting ({self.elapsed:.0f}/{self.timeout_s:g} s): {why}"
            return RUNNING
        if not estimate.fits:
            self.feedback_message = f"does not fit the battery: {estimate.figures()}"
            return FAILURE
        self.feedback_message = f"fits: {estimate.figures()}"
        return SUCCESS
