"""Failsafes: when a guard of the mission fails, the reaction its policy names, at once, then its recovery.

Every guard stands for a condition of the mission's ``failsafe:`` policy (:data:`CONDITIONS`:
:class:`~executive.behaviours.guards.LinkAlive` failing is ``link_loss``...); a guard standing for
none (a speed or depth limit) holds the vehicle and resumes, within ``limits.recovery_timeout_s``.

:class:`Failsafe` stands behind the guarded work in a reactive selector (``trees._parts.guarded``):
the guards are ticked every tick before the work, so the tick in which a condition becomes true on
the blackboard (the readers write it before the tree ticks) is the tick in which the route fails
and the failsafe runs; it asks the autopilot for the reaction there and then, and the runtime
sends it when that tick ends: zero ticks of delay.

A reaction is done only when the autopilot has accepted it (its COMMAND_ACK, on the blackboard)
and the heartbeat shows the vehicle in the mode (or disarmed) asked for. Until then the feedback
says what it waits for (``asking HOLD: refused (FAILED) x2``), and it is asked again every
:data:`ASK_AGAIN_S` of vehicle time. After :data:`ASKS_BEFORE_NEXT` failed asks (refused; accepted
but not seen; unanswered while heartbeats arrive), or at once when the firmware's source says the
vehicle cannot enter it in its present state (a position mode without a position estimate), the
next reaction the firmware allows is asked instead (:mod:`executive.autopilot.fallbacks`). Each
such step is a warning and an announcement to the ground station (a STATUSTEXT).

While it runs, every guard is judged each tick (not only the first that failed), so a condition
that becomes true during another one's reaction gets its own. A person who has the vehicle (a
failing ``wait`` guard that says so: the take-over switch, disarmed), or who drives it in a mode
of a person's (MANUAL, ACRO...: set by the RC, a ground station, or by us at the operator's request),
is never fought: nothing is commanded meanwhile. Each cause, reaction, recovery and abort is logged as a warning (the journal
keeps it as an event).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from executive import blackboard
from executive.autopilot import AutopilotPort, Request
from executive.autopilot.fallbacks import DISARM, chain, fallback
from executive.behaviours.actions import SetMode
from executive.behaviours.base import TimedBehaviour
from executive.behaviours.guards import (
    Armed,
    BatteryAbove,
    EkfOk,
    GpsNotGlitching,
    Guard,
    HeadingSane,
    InsideGeofence,
    LinkAlive,
    RcAutoMode,
    RcFresh,
    RcNotLost,
    RcNotTakingOver,
)
from executive.mission.lifecycle import MissionState
from executive.mission.model import REACTION_MODES, FailsafeCondition, FailsafePolicy
from executive.state import CommandState, CommandStatus, EkfStatus
from executive.vehicles import PROFILES

log = logging.getLogger(__name__)

#: Which failsafe condition a failing guard is.
CONDITIONS: tuple[tuple[type[Guard], str], ...] = (
    (LinkAlive, "link_loss"),
    (EkfOk, "ekf_loss"),
    (Armed, "disarmed"),
    (RcNotTakingOver, "rc_takeover"),
    (RcAutoMode, "rc_takeover"),
    (RcFresh, "rc_loss"),
    (RcNotLost, "rc_loss"),
    (GpsNotGlitching, "gps_glitch"),
    (HeadingSane, "heading_insane"),
    (BatteryAbove, "battery_low"),
    (InsideGeofence, "geofence_breach"),
)
#: A stronger reaction replaces a weaker one in force, never the reverse (a surfacing sub is not stopped by a later hold).
RANK = {"wait": 0, "hold": 1, "loiter": 1, "rtl": 2, "surface": 2, "disarm": 3}
REARM_RETRY_S = 2.0
#: A reaction the vehicle is not seen in yet is asked again this long after the last ask (vehicle time). ArduPilot answers
#: DO_SET_MODE as it handles it (GCS_MAVLINK::_set_mode_common, libraries/GCS_MAVLink/GCS_Common.cpp) and sends a HEARTBEAT at
#: once when its mode changes (Rover/system.cpp, ArduPlane/system.cpp set_mode), else once a second: 1.5 s is a heartbeat period
#: and a round trip, and the commander's ack time-out (an ask unanswered that long is lost). One ask per 1.5 s: no flood.
ASK_AGAIN_S = 1.5
#: Failed asks (refused; accepted and not seen; unanswered while heartbeats arrive) before the next reaction the firmware allows.
#: An ask unanswered while no heartbeat arrives says nothing of the vehicle (the link is down): asked again, not counted.
ASKS_BEFORE_NEXT = 3


def condition_of(guard: Guard) -> str | None:
    """The failsafe condition ``guard`` failing is, if any."""
    return next((condition for kind, condition in CONDITIONS if isinstance(guard, kind)), None)


@dataclass(frozen=True)
class _Reaction:
    guard: Guard
    policy: FailsafePolicy

    @property
    def rank(self) -> int:
        return RANK[self.policy.reaction]


@dataclass
class _Asking:
    """One reaction asked of the autopilot until it is done: accepted, and the vehicle seen in it."""

    step: str  # a mode as the trees name it, or DISARM
    shown: str  # as the heartbeat names it (AUTO.LOITER on PX4), or "disarm"
    cause: str  # the condition it answers
    instead_of: str | None  # the reaction it replaces (refused, or impossible now)
    since: float
    path: tuple[str, ...] = ()  # the reactions asked (or passed over) to get here, this one last
    request: Request | None = None  # the latest ask
    asked_at: float = -math.inf
    asks: int = 0
    judged: bool = True  # the latest ask's outcome is counted
    acked: bool = False  # the autopilot accepted one of its asks
    confirmed: bool = False
    failed: int = 0  # asks that failed (counted toward the next reaction)
    outcomes: Counter[str] = field(default_factory=Counter)
    last: str | None = None  # the latest outcome: "refused (FAILED)", "no answer", "accepted, the vehicle still in GUIDED"

    @property
    def waits_for(self) -> str:
        """``asking HOLD instead of RTL: refused (FAILED) x2``."""
        text = f"asking {self.shown}" + (f" instead of {self.instead_of}" if self.instead_of else "")
        if self.last is not None:
            count = self.outcomes[self.last]
            text += f": {self.last}" + (f" x{count}" if count > 1 else "")
        return text


class Failsafe(TimedBehaviour):
    """RUNNING while a guard fails and its policy says resume (the reaction commanded), FAILURE on abort or time-out.

    ``policy``: condition -> :class:`~executive.mission.model.FailsafePolicy`; ``fallback`` is the policy
    of a guard that stands for no condition. When every guard holds the branch it stands behind
    failed for another reason: FAILURE, with nothing to add. An abort leaves its feedback empty
    when the guard that caused it says why in the tree already; :attr:`left_in` is the mode it
    left the vehicle in (the runtime then leaves it there).
    """

    reads = (
        "/vehicle/vtol_state", "/vehicle/armed", "/vehicle/mode", "/vehicle/mode_set_by", "/mission/leg_index", "/mission/leg_count",
        "/vehicle/ekf", "/vehicle/ekf_failsafe", "/link/up",
        blackboard.command_key("DO_SET_MODE"), blackboard.command_key("COMPONENT_ARM_DISARM"),
    )  # fmt: skip
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    #: Where its steps are announced to a person (the ground station's STATUSTEXT); from ``setup(mission_state=...)`` when given.
    mission_state: MissionState | None = None
    catalogued = False  # made with the mission's policy by failsafe_guarded and checked

    def __init__(
        self, guards: Sequence[Guard], policy: Mapping[str, FailsafePolicy], vehicle: str, fallback: FailsafePolicy, name: str = "Wait for guards"
    ) -> None:
        super().__init__(name)
        self.guards = tuple(guards)
        self.policy = dict(policy)
        self.vehicle = vehicle
        self.fallback = fallback
        self._conditions = {g: condition_of(g) for g in self.guards}
        self.left_in: str | None = None
        self._own_disarm = False  # kept across a pause: the vehicle is still ours to re-arm
        # kept across re-entries: after a recovery, until the recovered condition's time limit, a refused mode change is asked again
        self._resume_until: float | None = None
        self._resume_causes = ""
        self._retry_said = False
        self._leg = 0
        self._reset()

    def setup(self, **services: Any) -> None:
        super().setup(**services)
        self.mission_state = services.get("mission_state")

    def _reset(self) -> None:
        self._since: dict[Guard, float] = {}
        self._in_force: _Reaction | None = None
        self._mode_in_force: str | None = None
        self._asking: _Asking | None = None
        self._tickets: list[Request] = []
        self._rearm_from: float | None = None
        self._rearm_at = float("-inf")

    def initialise(self) -> None:
        super().initialise()
        self._reset()
        self.left_in = None
        self._leg = self.get("/mission/leg_index")  # the leg to resume (the work may finish it in the tick it resumes)

    def policy_of(self, guard: Guard) -> FailsafePolicy:
        condition = self._conditions.get(guard)
        return self.policy.get(condition, self.fallback) if condition else self.fallback

    def _name(self, guard: Guard) -> str:
        return self._conditions.get(guard) or guard.name

    def terminate(self, new_status: Status) -> None:
        if self.left_in is not None or new_status == Status.FAILURE:
            return  # ended the mission: the reaction must reach the vehicle
        # interrupted: by the guards recovering (the work resumes) or by a pause; a reaction still being retried must not undo either
        for ticket in self._tickets:
            self.autopilot.cancel(ticket)
        if self._since and all(g.status == Status.SUCCESS for g in self.guards):
            causes = ", ".join(self._name(g) for g in self._since)
            self._resume_until = max(since + self.policy_of(g).timeout_s for g, since in self._since.items())
            self._resume_causes, self._retry_said = causes, False
            leg = f"{self._leg + 1}/{self.get('/mission/leg_count')}"
            log.warning("failsafe %s: recovered after %.1f s -> resume leg %s", causes, self.elapsed, leg)
            if self.mission_state is not None:
                self.mission_state.announce(f"failsafe {causes} recovered: leg {leg}", warning=False)
        self._since = {}

    def update(self) -> Status:
        now = self.clock.now()
        if self.get("/vehicle/armed"):
            self._own_disarm = False
        failing = {g: why for g in self.guards if (why := g.judge()) is not None}  # debounced: see guards
        if self._own_disarm:  # disarmed by this failsafe, not by a person
            failing = {g: why for g, why in failing.items() if self._conditions.get(g) != "disarmed"}
        for g in [g for g in self._since if g not in failing]:
            del self._since[g]
        new = [g for g in failing if g not in self._since]
        for g in new:
            self._since[g] = now
        if not failing:
            return self._rearm(now) if self._own_disarm else self._retry_refused_mode(now) or self._nothing_to_wait_for()
        self._rearm_from = None
        why = "; ".join(f"{g.name} {reason}" for g, reason in failing.items())
        person = next((g for g in failing if g.pilot_in_control), None)  # whatever a policy says (the loader refuses any but wait)
        driving = self._person_drives()
        hands_off = person is not None or driving is not None
        aborting = [_Reaction(g, self.policy_of(g)) for g in failing if self.policy_of(g).recovery == "abort"]
        if aborting:
            cause = max(aborting, key=lambda r: r.rank)
            if not hands_off:
                self._in_force = cause
            self._log(cause, failing[cause.guard], person, "abort the mission", driving)  # the cause first, then each step of its reaction
            mode = None if hands_off else self._react(cause)
            self.left_in = mode or self._mode_in_force
            self.feedback_message = "" if cause.guard.status == Status.FAILURE else f"{cause.guard.name} {failing[cause.guard]}"
            return Status.FAILURE
        chosen = None if hands_off else self._strongest(failing, new)
        if chosen is not None:
            self._in_force = chosen
        for g in new:
            reaction = _Reaction(g, self.policy_of(g))
            self._log(reaction, failing[g], person, f"resume when it recovers (within {reaction.policy.timeout_s:g} s)", driving)
        if hands_off:
            self._stand_back()
        else:
            if chosen is not None:
                self._react(chosen)
            self._follow_up(now)
        late = [g for g in failing if now - self._since[g] > self.policy_of(g).timeout_s]
        if late:
            limit = self.policy_of(late[0]).timeout_s
            log.warning("failsafe %s: not recovered within %g s -> abort the mission", self._name(late[0]), limit)
            self.left_in = self._mode_in_force
            self.feedback_message = f"not recovered after {limit:g} s: {why}"
            return Status.FAILURE
        waited, limit = max(((now - self._since[g], self.policy_of(g).timeout_s) for g in failing), key=lambda x: x[0] / x[1])
        self.feedback_message = f"{self._state(hands_off)} ({waited:.0f}/{limit:g} s): {why}"
        return Status.RUNNING

    def _state(self, hands_off: bool) -> str:
        """What the vehicle is left in, or what the reaction still waits for."""
        asking = self._asking
        if hands_off or asking is None:
            return "hands off"
        if not asking.confirmed:
            return asking.waits_for
        if not self._seen(asking.step):  # confirmed once, and changed since (the autopilot's own failsafe, a person): say so
            return "armed again" if asking.step == DISARM else f"{asking.shown} left: the vehicle in {self.get('/vehicle/mode')}"
        return "disarmed" if asking.step == DISARM else f"in {asking.shown}"

    # -- reactions ---------------------------------------------------------------------------

    def _strongest(self, failing: Iterable[Guard], new: list[Guard]) -> _Reaction | None:
        """The strongest reaction among the failing conditions, to command now, unless one as strong is in force (a new one: stronger or equal)."""
        candidates = [_Reaction(g, self.policy_of(g)) for g in failing if self.policy_of(g).reaction != "wait"]
        if not candidates:
            return None
        strongest = max(candidates, key=lambda r: (r.rank, r.guard in new))
        in_force = self._in_force.rank if self._in_force is not None else -1
        if strongest.rank > in_force or (strongest.guard in new and strongest.rank == in_force):
            return strongest
        return None

    def _react(self, reaction: _Reaction) -> str | None:
        """Ask for ``reaction`` (unless it, or a reaction after it, is asked already); the mode it leaves the vehicle in, if any."""
        self._in_force = reaction
        what = reaction.policy.reaction
        if what == "wait":
            return None
        mode = self._mode_of(what)
        first = DISARM if what == "disarm" else mode
        if self._asking is not None and first in self._asking.path:  # asked already (or refused, and the next one asked)
            return self._mode_in_force
        if what == "disarm":  # the manual mode first: re-armed later, the vehicle does not drive off
            try:
                self._tickets.append(self.autopilot.set_mode(mode))
                self._mode_in_force = mode
            except KeyError:
                log.error("failsafe %s: the autopilot has no mode %s", self._name(reaction.guard), mode)
        self._start(first, self._name(reaction.guard), None)
        return self._mode_in_force

    def _mode_of(self, what: str) -> str:
        modes = REACTION_MODES[what][self.vehicle]
        return modes[1] if self.get("/vehicle/vtol_state") == "FW" else modes[0]

    @property
    def _firmware(self) -> str:
        return self.autopilot.capabilities.autopilot

    # -- asking until done -------------------------------------------------------------------

    def _start(self, step: str, cause: str, instead_of: str | None, path: tuple[str, ...] = ()) -> None:
        """Ask for ``step``, or the first reaction after it that the vehicle can enter in its present state."""
        now = self.clock.now()
        for candidate in chain(self._firmware, self.vehicle, step):
            path = (*path, candidate)
            rule = fallback(self._firmware, self.vehicle, candidate)
            shown = self._shown(candidate)
            if rule.needs_position and (missing := self._no_position()) and rule.then is not None:
                after = self._shown(rule.then)
                self._announce(
                    cause, f"{shown} cannot be entered: {missing} ({rule.why}) -> {after} instead", f"{cause}: no position for {shown} -> {after}"
                )
                instead_of = shown
                continue
            self._asking = _Asking(candidate, shown, cause, instead_of, now, path)
            if self._ask(self._asking):
                return
            instead_of = shown  # the firmware has no such mode: the next one
        self._asking = None

    def _ask(self, asking: _Asking) -> bool:
        """Send one ask of ``asking``; False when the autopilot has no such mode."""
        try:
            if asking.step == DISARM:
                request = self.autopilot.disarm()
                self._own_disarm = True
            else:
                request = self.autopilot.set_mode(asking.step)
                self._mode_in_force = asking.step
        except KeyError:
            log.error("failsafe %s: the autopilot has no mode %s", asking.cause, asking.step)
            return False
        self._tickets.append(request)
        asking.request, asking.asked_at, asking.asks, asking.judged = request, self.clock.now(), asking.asks + 1, False
        return True

    def _follow_up(self, now: float) -> None:
        """The reaction asked for: done (accepted and seen), or judged, asked again, or replaced by the next one."""
        asking = self._asking
        if asking is None or asking.confirmed or asking.request is None:
            return
        status: CommandStatus | None = self.get(blackboard.command_key(asking.request.command))
        mine = status is not None and status.ticket == asking.request.ticket
        if mine and status.state is CommandState.ACCEPTED:
            asking.acked = True
        if asking.acked and self._seen(asking.step):
            asking.confirmed = True
            self._confirmed(asking, now)
            return
        if not asking.judged:
            outcome = self._outcome(asking, status if mine else None, now)
            if outcome is not None:
                self._judge(asking, outcome)
        if not asking.judged or now - asking.asked_at < ASK_AGAIN_S - 1e-6:
            return
        then = fallback(self._firmware, self.vehicle, asking.step).then
        if asking.failed >= ASKS_BEFORE_NEXT and then is not None:
            after = self._shown(then)
            times = f" x{asking.outcomes[asking.last]}" if asking.last else ""
            self._announce(
                asking.cause,
                f"{asking.shown} {asking.last}{times} after {asking.asks} asks -> {after} instead "
                f"({fallback(self._firmware, self.vehicle, asking.step).why})",
                f"{asking.cause}: {asking.shown} {_short(asking.last)}{times} -> {after}",
            )
            self.autopilot.cancel(asking.request)  # its ask still waiting for an ack is not sent again (the commander would)
            self._start(then, asking.cause, asking.shown, asking.path)
            return
        self._ask(asking)

    def _outcome(self, asking: _Asking, status: CommandStatus | None, now: float) -> str | None:
        """What became of the latest ask, once known: refused, no answer, or accepted with the vehicle not seen in it."""
        if status is not None and status.state is CommandState.REJECTED:
            return f"refused ({status.result_name})"
        if status is not None and status.state is CommandState.TIMED_OUT:
            return "no answer"
        if now - asking.asked_at < ASK_AGAIN_S - 1e-6:
            return None
        if status is not None and status.state is CommandState.ACCEPTED:
            if asking.step == DISARM:
                return "accepted, the vehicle still armed"
            return f"accepted, the vehicle still in {self.get('/vehicle/mode') or 'an unknown mode'}"
        return "no answer"

    def _judge(self, asking: _Asking, outcome: str) -> None:
        asking.judged = True
        counts = outcome != "no answer" or bool(self.get("/link/up"))
        asking.failed += counts
        first = asking.outcomes[outcome] == 0
        asking.outcomes[outcome] += 1
        asking.last = outcome
        if first:
            link = "" if counts else " and no heartbeat (the link is down)"
            self._announce(
                asking.cause,
                f"{asking.shown} {outcome}{link} -> asked again every {ASK_AGAIN_S:g} s",
                f"{asking.cause}: {asking.shown} {_short(outcome)}",
            )

    def _confirmed(self, asking: _Asking, now: float) -> None:
        done = "disarmed" if asking.step == DISARM else f"in {asking.shown}"
        text = f"the vehicle {done} (accepted and seen; {asking.asks} ask{'s' if asking.asks > 1 else ''}, {now - asking.since:.1f} s)"
        if asking.failed or asking.instead_of or asking.last:
            self._announce(asking.cause, text, f"{asking.cause}: {done}, confirmed", warning=False)
        else:
            log.info("failsafe %s: %s", asking.cause, text)

    def _seen(self, step: str) -> bool:
        """The heartbeat shows the vehicle in ``step`` (or in the mode the firmware goes on to by itself from it: a sub at the surface)."""
        if step == DISARM:
            return not self.get("/vehicle/armed")
        mode, shown = self.get("/vehicle/mode"), self._shown(step)
        return mode == shown or (mode is not None and mode == PROFILES[self.vehicle].follow_on_modes.get(shown))

    def _shown(self, step: str) -> str:
        return "disarm" if step == DISARM else self.autopilot.mode_name(step)

    def _no_position(self) -> str | None:
        """Why the autopilot has no position estimate now, if the reports say so (no report: not known, asked anyway)."""
        if self.get("/vehicle/ekf_failsafe"):
            return "the autopilot's EKF failsafe is on"
        ekf: EkfStatus | None = self.get("/vehicle/ekf")
        if ekf is not None and not ekf.position_ok():
            return f"the EKF has no position estimate (flags {int(ekf.flags):#x})"
        return None

    def _stand_back(self) -> None:
        """A person has the vehicle: what is still being asked is dropped (never retried over them), asked again once they let go."""
        for ticket in self._tickets:
            self.autopilot.cancel(ticket)
        if self._asking is not None and not self._asking.confirmed:
            self._asking.asked_at, self._asking.judged = -math.inf, True  # not a failed ask: asked again at once when they let go

    def _announce(self, cause: str, text: str, short: str, *, warning: bool = True) -> None:
        """A step of a reaction: a warning (the journal's event), and a short STATUSTEXT to the ground station (``warning``: else a notice)."""
        log.warning("failsafe %s: %s", cause, text)
        if self.mission_state is not None:
            self.mission_state.announce(short, warning=warning)

    def _rearm(self, now: float) -> Status:
        """Every condition cleared, the vehicle disarmed by this failsafe: arm it again (retried), then the work resumes."""
        if self._rearm_from is None:
            self._rearm_from = now
            log.warning("failsafe %s: recovered -> re-arm, then resume", self._name(self._in_force.guard) if self._in_force else "disarm")
        limit = self._in_force.policy.timeout_s if self._in_force else self.fallback.timeout_s
        if now - self._rearm_from > limit:
            log.warning("failsafe: could not re-arm within %g s -> abort the mission", limit)
            self.left_in = self._mode_in_force
            self.feedback_message = f"could not re-arm within {limit:g} s"
            return Status.FAILURE
        if now - self._rearm_at >= REARM_RETRY_S:
            self._rearm_at = now
            self._tickets.append(self.autopilot.arm())
        self.feedback_message = f"re-arming ({now - self._rearm_from:.0f}/{limit:g} s)"
        return Status.RUNNING

    def _retry_refused_mode(self, now: float) -> Status | None:
        """RUNNING when the work, resumed after a recovery, failed on a refused mode change and the recovery's time is not up.

        The firmware's own failsafe may still be latched (ArduRover refuses GUIDED and AUTO for about
        a second after its EKF recovered: ``failsafe.ekf``, Rover/ekf_check.cpp, Rover/mode.cpp): the
        work is ticked again next tick and asks again, until the recovered condition's time limit.
        """
        if self._resume_until is None or now > self._resume_until:
            return None
        refused = self._refused_mode_change()
        if refused is None:
            return None
        if not self._retry_said:
            self._retry_said = True
            log.warning(
                "failsafe %s: recovered, but %s -> asked again until the recovery's time limit (%.0f s more)",
                self._resume_causes, refused, self._resume_until - now,
            )  # fmt: skip
        self.feedback_message = f"resuming after {self._resume_causes}: {refused}; asking again"
        return Status.RUNNING

    def _refused_mode_change(self) -> str | None:
        """Why the guarded work failed on a mode change (the branch this failsafe stands behind), if it did."""
        if self.parent is None or not self.parent.children or self.parent.children[0] is self:
            return None
        for node in self.parent.children[0].iterate():
            if isinstance(node, SetMode) and node.status == Status.FAILURE:
                return f"{node.name}: {node.feedback_message}"
        return None

    def _nothing_to_wait_for(self) -> Status:
        self.feedback_message = ""  # the branch it stands behind failed: that is the reason to report
        return Status.FAILURE

    def _person_drives(self) -> str | None:
        """Why a person drives the vehicle, if one does: a mode in which a person drives (MANUAL, ACRO...) that this failsafe did not ask for.

        Set by the RC, a ground station, or by the executive at the operator's request (handed over):
        no failsafe of ours changes it; RC loss meanwhile is the autopilot's own RC failsafe's job.
        """
        mode = self.get("/vehicle/mode")
        set_by = self.get("/vehicle/mode_set_by")  # None: the boot mode, nobody's choice
        if mode in PROFILES[self.vehicle].pilot_modes and set_by is not None and mode != self._mode_in_force:
            return f"the vehicle is in {mode}: a person drives it"
        return None

    def _log(self, reaction: _Reaction, reason: str, person: Guard | None, recovery: str, driving: str | None = None) -> None:
        """``failsafe <condition>: <reason> -> <reaction>, <recovery>``: a warning, so an event in the journal."""
        what, condition = reaction.policy.reaction, self._name(reaction.guard)
        short = done = "wait: hands off"  # short: for a STATUSTEXT (50 characters)
        if person is not None:
            done = f"wait: hands off ({person.name.rstrip('?')} fails: a person has the vehicle)"
        elif driving is not None:
            job = "; RC loss is the autopilot's own RC failsafe's job" if condition == "rc_loss" else ""
            done = f"wait: hands off ({driving}{job})"
        elif what != "wait":
            mode = self._mode_of(what)
            short = done = f"disarm in {mode}" if what == "disarm" else f"{what} ({mode})"
            stronger = self._in_force
            if stronger is not None and stronger.rank > reaction.rank:
                done += f" not commanded: {stronger.policy.reaction} ({self._mode_in_force}) for {self._name(stronger.guard)} in force"
                short = f"{stronger.policy.reaction} kept"
        log.warning("failsafe %s: %s -> %s, %s", condition, reason, done, recovery)
        if self.mission_state is not None:
            self.mission_state.announce(f"failsafe {condition} -> {short}" + (", abort" if recovery == "abort the mission" else ""))


class FailsafeNote(py_trees.behaviour.Behaviour):
    """Logs a failsafe event for a tree that reacts with its own behaviours (the ASV's EKF wait), then SUCCESS.

    With ``guard``, its reason goes in the text: ``failsafe ekf_loss: <reason> -> <text>``.
    """

    node_refs = ("guard",)
    param_docs = {
        "condition": "the failsafe condition journalled (ekf_loss, rc_loss...)",
        "text": "what is done about it",
        "guard": "the name of a guard of the tree whose reason goes in the text",
    }

    def __init__(self, condition: FailsafeCondition, text: str, guard: Guard | None = None, name: str | None = None) -> None:
        super().__init__(name or f"Journal: {condition}")
        self.condition, self.text, self.guard = condition, text, guard

    def update(self) -> Status:
        reason = f"{self.guard.feedback_message} -> " if self.guard is not None else ""
        log.warning("failsafe %s: %s%s", self.condition, reason, self.text)
        return Status.SUCCESS


def failsafe_mode(root: py_trees.behaviour.Behaviour) -> str | None:
    """The mode a failsafe that ended the mission left the vehicle in, if one did."""
    return next((node.left_in for node in root.iterate() if isinstance(node, Failsafe) and node.left_in), None)


def _short(outcome: str | None) -> str:
    """An outcome for a STATUSTEXT (50 characters): ``accepted, still GUIDED``."""
    return (outcome or "").replace("the vehicle still in ", "still ").replace("the vehicle still ", "still ")
