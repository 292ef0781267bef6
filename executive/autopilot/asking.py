"""Asking the autopilot until the vehicle shows it is done: ask, confirm by what the vehicle reports, ask again, the next step or give up.

The one mechanism every place that asks the autopilot for something uses (the failsafes' reactions,
the mission's holds, the return's GUIDED, the make-safe, the RC switches, the commands of the trees, the
VTOL transitions, the repositions of :mod:`executive.behaviours.repositioning`).
An :class:`Asker` asks a step (a mode, an arm or a disarm, or any command with its own confirmation)
and, each time its owner calls :meth:`Asker.follow_up`, looks at what came back: the ack on
``/command/<outcome>`` and the vehicle's own report (the heartbeat's mode, armed state). An ask
refused, unanswered, or not seen in time is judged failed; the next one goes when :class:`Rules` say
(every :data:`ASK_AGAIN_S` for a reaction). After :attr:`Rules.asks_before_next` failed asks, or at
once when the firmware's source says the vehicle cannot enter it in its present state (a position mode
without a position estimate), the next step of the firmware's fallback chain is asked instead
(:mod:`executive.autopilot.fallbacks`, the mechanism's data); with no next step it is asked again,
or given up (:attr:`Asker.exhausted`). Each step is told to the owner's :class:`Voice`: the
reactions' (:class:`ReactionVoice`) logs a warning (the journal's ``failsafe`` event) and announces it
(a STATUSTEXT); a switch says it in its feedback, a command in its outcome.

It never blocks: the owner calls :meth:`Asker.follow_up` each tick and reads the blackboard keys in
:data:`READS` (add them to its own ``reads``).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from executive.autopilot.fallbacks import DISARM, Fallback, chain, fallback
from executive.autopilot.port import AutopilotPort, Request
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import CommandState, CommandStatus, EkfStatus, Outcome

log = logging.getLogger("executive.behaviours.failsafe")  # the journal's event kind: "failsafe"

#: A reaction the vehicle is not seen in yet is asked again this long after the last ask (vehicle time). ArduPilot answers
#: DO_SET_MODE as it handles it (GCS_MAVLINK::_set_mode_common, libraries/GCS_MAVLink/GCS_Common.cpp) and sends a HEARTBEAT at
#: once when its mode changes (Rover/system.cpp, ArduPlane/system.cpp set_mode), else once a second: 1.5 s is a heartbeat period
#: and a round trip, and the commander's ack time-out (an ask unanswered that long is lost). One ask per 1.5 s: no flood.
ASK_AGAIN_S = 1.5
#: Failed asks (refused; accepted and not seen; unanswered while heartbeats arrive) before the next reaction the firmware allows.
#: An ask unanswered while no heartbeat arrives says nothing of the vehicle (the link is down): asked again, not counted.
ASKS_BEFORE_NEXT = 3
#: Not a mode: arm the vehicle (a step as :data:`~executive.autopilot.fallbacks.DISARM` is).
ARM = "ARM"
#: The blackboard keys an owner of an :class:`Asker` reads.
READS = (
    "/vehicle/armed", "/vehicle/mode", "/vehicle/mode_set_by", "/vehicle/ekf", "/vehicle/ekf_failsafe", "/link/up",
    blackboard.command_key(Outcome.MODE), blackboard.command_key(Outcome.ARMING),
)  # fmt: skip
#: Told of each step a person must hear: a short text (a STATUSTEXT holds 50 characters), and whether it is a warning.
Announce = Callable[[str, bool], None]
_EPS = 1e-6  # a sum of tick periods lands a hair short of the interval it should reach


@dataclass(frozen=True)
class Rules:
    """How an asking goes, in vehicle time: when an ask is judged failed, when the next goes, when to move on or give up."""

    #: An ask neither refused nor seen is judged failed once it is older than this (from the port's last re-ask of a refusal).
    judge_after_s: float = ASK_AGAIN_S - _EPS
    #: The next ask goes no sooner than this after the last one ...
    again_after_s: float = ASK_AGAIN_S - _EPS
    #: ... nor sooner than this after the failure was judged.
    rest_s: float = 0.0
    #: Failed asks of a step before the next step of the fallback chain (None: no limit, nor an end of asking by count).
    asks_before_next: int | None = ASKS_BEFORE_NEXT
    #: Done only when the autopilot accepted one of the asks as well as the vehicle shows it (else the vehicle's report alone).
    needs_ack: bool = True
    #: An ask unanswered while no heartbeat arrives counts as failed (else it says nothing of the vehicle: asked again).
    link_down_counts: bool = False
    #: Given up at a failure after which the next ask would come later than this after the wish (None: no bound in time).
    give_up_after_s: float | None = None


#: The failsafes' reactions (and every mode the executive asks of itself until it holds): accepted and seen, 1.5 s apart, 3 each.
REACTION = Rules()


@dataclass
class Step:
    """One step asked of the autopilot until it is done: accepted (when the rules want it), and the vehicle seen in it."""

    step: str  # a mode as the trees name it, DISARM or ARM, or a command's name
    shown: str  # as the heartbeat names it (AUTO.LOITER on PX4), "disarm", "arm", or the command's name
    cause: str  # the condition it answers
    instead_of: str | None  # the step it replaces (refused, or impossible now)
    since: float  # the wish: what the rules' give-up bound counts from
    path: tuple[str, ...] = ()  # the steps asked (or passed over) to get here, this one last
    send: Callable[[], Request | None] | None = None  # a command's own ask (None: by the step's name)
    seen_by: Callable[[], bool] | None = None  # a command's own confirmation (None: by the step's name)
    request: Request | None = None  # the latest ask
    asked_at: float = -math.inf
    retried_at: float = -math.inf  # the port's last re-ask of a refusal of it (RETRYING): judged from then
    judged_at: float = -math.inf
    status: CommandStatus | None = None  # the ack of the latest judged ask (None: none of its own)
    asks: int = 0
    judged: bool = True  # the latest ask's outcome is counted
    acked: bool = False  # the autopilot accepted one of its asks
    confirmed: bool = False
    was_shown: bool = False  # the heartbeat showed the vehicle in it (since it was asked)
    gave_up: bool = False  # the rules' bound in time is reached
    failed: int = 0  # asks that failed (counted toward the next step)
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


class Voice:
    """How an asker's steps are told, each call one step; this one tells nothing (an owner overrides what it says)."""

    def asked(self, step: Step, again: bool) -> None:
        """``step`` was asked (``again``: not for the first time)."""

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        """The latest ask of ``step`` failed: ``outcome`` (``first``: the first such); see :attr:`Step.gave_up`."""

    def replaced(self, step: Step, after: str, why: str) -> None:
        """``step`` failed too often: ``after`` is asked instead (``why``: the firmware's word for it)."""

    def cannot_enter(self, cause: str, shown: str, missing: str, why: str, after: str) -> None:
        """``shown`` cannot be entered now (``missing``: a position): ``after`` instead."""

    def no_such_mode(self, cause: str, step: str) -> None:
        """The autopilot has no mode ``step``: the next step, if any."""

    def confirmed(self, step: Step, took_s: float) -> None:
        """``step`` is done: the vehicle seen in it (and accepted, if the rules want it)."""


class ReactionVoice(Voice):
    """A reaction's steps: each a warning to ``logger`` as ``<prefix><cause>: ...`` and a short announcement (a STATUSTEXT)."""

    def __init__(self, announce: Announce | None = None, logger: logging.Logger = log, prefix: str = "failsafe ") -> None:
        self.announce, self.log, self.prefix = announce, logger, prefix

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        if first:
            link = "" if counted else " and no heartbeat (the link is down)"
            text = f"{step.shown} {outcome}{link} -> asked again every {ASK_AGAIN_S:g} s"
            self._step(step.cause, text, f"{step.cause}: {step.shown} {_short(outcome)}")

    def replaced(self, step: Step, after: str, why: str) -> None:
        times = f" x{step.outcomes[step.last]}" if step.last else ""
        self._step(
            step.cause,
            f"{step.shown} {step.last}{times} after {step.asks} asks -> {after} instead ({why})",
            f"{step.cause}: {step.shown} {_short(step.last)}{times} -> {after}",
        )

    def cannot_enter(self, cause: str, shown: str, missing: str, why: str, after: str) -> None:
        self._step(cause, f"{shown} cannot be entered: {missing} ({why}) -> {after} instead", f"{cause}: no position for {shown} -> {after}")

    def no_such_mode(self, cause: str, step: str) -> None:
        self.log.error("%s%s: the autopilot has no mode %s", self.prefix, cause, step)

    def confirmed(self, step: Step, took_s: float) -> None:
        done = "disarmed" if step.step == DISARM else f"in {step.shown}"
        text = f"the vehicle {done} (accepted and seen; {step.asks} ask{'s' if step.asks > 1 else ''}, {took_s:.1f} s)"
        if step.failed or step.instead_of or step.last:
            self._step(step.cause, text, f"{step.cause}: {done}, confirmed", warning=False)
        else:
            self.log.info("%s%s: %s", self.prefix, step.cause, text)

    def _step(self, cause: str, text: str, short: str, *, warning: bool = True) -> None:
        """A step of a reaction: a warning (the journal's event), and a short STATUSTEXT (``warning``: else a notice)."""
        self.log.warning("%s%s: %s", self.prefix, cause, text)
        if self.announce is not None:
            self.announce(short, warning)


class Host(Protocol):
    """The owner of an :class:`Asker`: its clock, autopilot port and blackboard (with :data:`READS`)."""

    clock: Clock
    autopilot: AutopilotPort

    def get(self, key: str) -> Any: ...


class Asker:
    """One owner's asking, until done: :meth:`start` it, call :meth:`follow_up` each tick, show :meth:`state`.

    ``rules``: when asks are judged, repeated, replaced and given up (:data:`REACTION` by default).
    ``escalate``: after failed asks, or when the vehicle cannot enter it now, the next step the
    firmware allows; without it the same step is asked again until the rules or the owner give up.
    ``on_disarm`` is called when a disarm is asked (the owner re-arms the vehicle it disarmed).
    ``vehicle``: the vehicle kind (None: not known, no next steps and no follow-on modes).
    ``bounded``: nothing is asked once :attr:`exhausted` (the last reaction is not asked a fourth time).
    Its steps go to ``voice`` (by default a :class:`ReactionVoice` of ``announce``, ``logger`` and ``prefix``).
    """

    def __init__(
        self,
        host: Host,
        vehicle: str | None,
        *,
        rules: Rules = REACTION,
        voice: Voice | None = None,
        announce: Announce | None = None,
        escalate: bool = True,
        on_disarm: Callable[[], None] | None = None,
        bounded: bool = False,
        logger: logging.Logger = log,
        prefix: str = "failsafe ",
    ) -> None:
        self.host, self.vehicle, self.rules = host, vehicle, rules
        self.voice = voice if voice is not None else ReactionVoice(announce, logger, prefix)
        self.escalate, self.on_disarm, self.bounded = escalate, on_disarm, bounded
        self.asking: Step | None = None
        self._passed: list[str] = []  # the steps replaced by the next one, and why: ``HOLD refused (FAILED) x3``
        #: Every request made (cancelled when the owner stops, or a person takes the vehicle).
        self.tickets: list[Request] = []
        #: The mode asked for last: where the reaction leaves the vehicle.
        self.mode_in_force: str | None = None

    @property
    def _firmware(self) -> str:
        return self.host.autopilot.capabilities.autopilot

    def _fallback(self, step: str) -> Fallback:
        return fallback(self._firmware, self.vehicle or "", step)

    @property
    def done(self) -> bool:
        """The step asked last is done: the vehicle seen in it (and accepted, if the rules want it)."""
        return self.asking is not None and self.asking.confirmed

    @property
    def exhausted(self) -> bool:
        """Nothing more to ask: nothing could be, the rules' time is up, or the last step allowed failed its asks."""
        asking = self.asking
        if asking is None:
            return True
        if asking.confirmed:
            return False
        if asking.gave_up:
            return True
        then = self._fallback(asking.step).then if self.escalate else None
        limit = self.rules.asks_before_next
        return then is None and asking.judged and limit is not None and asking.failed >= limit

    def due(self, now: float) -> bool:
        """The latest ask failed and the next may go now (by the rules)."""
        asking = self.asking
        if asking is None or asking.confirmed or not asking.judged or asking.gave_up:
            return False
        return now - asking.asked_at >= self.rules.again_after_s and now - asking.judged_at >= self.rules.rest_s

    def time_to_exhaust(self, step: str) -> float:
        """How long asking ``step`` and each step after it may take: :data:`ASKS_BEFORE_NEXT` asks :data:`ASK_AGAIN_S` apart each."""
        steps = len(list(chain(self._firmware, self.vehicle or "", step))) if self.escalate else 1
        return steps * ASKS_BEFORE_NEXT * ASK_AGAIN_S

    def account(self) -> str:
        """What each step asked came to: ``HOLD refused (FAILED) x3, disarmed (confirmed)``, ``HOLD not answered x6 (no heartbeat: ...)``."""
        asking = self.asking
        if asking is None:
            return ", ".join(self._passed) or "nothing asked"
        if asking.confirmed:
            now = ("disarmed" if asking.step == DISARM else asking.shown) + " (confirmed)"
        elif asking.last is None:
            now = f"{asking.shown} asked, not answered yet"
        else:
            now = _outcome_text(asking)
            if asking.last == "no answer" and not self.host.get("/link/up"):
                now += " (no heartbeat: the link is down)"
        return ", ".join([*self._passed, now])

    def covers(self, step: str) -> bool:
        """``step`` is asked already, or was and was replaced by the next one."""
        return self.asking is not None and step in self.asking.path

    def track(self, request: Request, mode: str | None = None) -> None:
        """A request of the owner's that belongs to the asking (the manual mode before a disarm): cancelled with it."""
        self.tickets.append(request)
        if mode is not None:
            self.mode_in_force = mode

    def start(self, step: str, cause: str, instead_of: str | None = None, path: tuple[str, ...] = (), *, since: float | None = None) -> None:
        """Ask for ``step``, or the first step after it that the vehicle can enter in its present state (``since``: the wish, else now)."""
        now = self.host.clock.now()
        for candidate in chain(self._firmware, self.vehicle or "", step) if self.escalate else (step,):
            path = (*path, candidate)
            rule = self._fallback(candidate)
            shown = self._shown(candidate)
            if self.escalate and rule.needs_position and (missing := self._no_position()) and rule.then is not None:
                self.voice.cannot_enter(cause, shown, missing, rule.why, self._shown(rule.then))
                self._passed.append(f"{shown} cannot be entered ({missing})")
                instead_of = shown
                continue
            self.asking = Step(candidate, shown, cause, instead_of, now if since is None else since, path)
            if self._ask(self.asking):
                return
            self._passed.append(f"{shown}: the autopilot has no such mode")
            instead_of = shown  # the firmware has no such mode: the next one
        self.asking = None

    def start_command(self, name: str, send: Callable[[], Request | None], seen: Callable[[], bool], cause: str) -> None:
        """Ask a command of the owner's (``send``), done when ``seen`` says so; no fallback chain.

        ``send`` returning None asks nothing (the owner knows why: no position to aim from): nothing is being asked.
        """
        self.asking = Step(name, name, cause, None, self.host.clock.now(), (name,), send=send, seen_by=seen)
        if not self._ask(self.asking):
            self.asking = None

    def ask_again(self) -> None:
        """Ask the current step again now (the owner's choice: :meth:`due`, after its own conditions)."""
        if self.asking is not None:
            self._ask(self.asking)

    def forget(self) -> None:
        """Drop the current step (a new wish replaces it); its requests are not cancelled."""
        self.asking = None

    def follow_up(self, now: float, *, ask: bool = True) -> None:
        """The step asked for: done (seen, and accepted if the rules want it), or judged, asked again, or replaced by the next one.

        ``ask`` False: judged and confirmed only, nothing asked (the owner's time is up, or it asks by :meth:`ask_again`).
        """
        asking = self.asking
        if asking is None or asking.confirmed or asking.request is None:
            return
        status: CommandStatus | None = self.host.get(blackboard.command_key(asking.request.outcome))
        mine = status is not None and status.ticket == asking.request.ticket
        if mine and status.state is CommandState.ACCEPTED:
            asking.acked = True
        if (asking.acked or not self.rules.needs_ack) and self.seen(asking.step):
            asking.confirmed = True
            self.voice.confirmed(asking, now - asking.since)
            return
        if mine and status.state is CommandState.RETRYING:
            asking.retried_at = status.time  # the port asks again by itself (PX4's AUTO.MISSION while it checks a new mission)
        if not asking.judged:
            outcome = self._outcome(asking, status if mine else None, now)
            if outcome is not None:
                self._judge(asking, outcome, status if mine else None, now)
        if not ask or not self.due(now) or (self.bounded and self.exhausted):
            return
        then = self._fallback(asking.step).then if self.escalate else None
        limit = self.rules.asks_before_next
        if limit is not None and asking.failed >= limit and then is not None:
            self.voice.replaced(asking, self._shown(then), self._fallback(asking.step).why)
            self.host.autopilot.cancel(asking.request)  # its ask still waiting for an ack is not sent again (the commander would)
            self._passed.append(_outcome_text(asking))
            self.start(then, asking.cause, asking.shown, asking.path)
            return
        self._ask(asking)

    def state(self) -> str | None:
        """What the step waits for, or where it left the vehicle; None when nothing was asked."""
        asking = self.asking
        if asking is None:
            return None
        if not asking.confirmed:
            return asking.waits_for
        if not self.seen(asking.step):  # confirmed once, and changed since (the autopilot's own failsafe, a person): say so
            return "armed again" if asking.step == DISARM else f"{asking.shown} left: the vehicle in {self.host.get('/vehicle/mode')}"
        return "disarmed" if asking.step == DISARM else f"in {asking.shown}"

    def stand_back(self) -> None:
        """A person has the vehicle: what is still being asked is dropped (never retried over them), asked again once they let go."""
        self.cancel()
        if self.asking is not None and not self.asking.confirmed:
            # not a failed ask: asked again at once when they let go
            self.asking.asked_at, self.asking.judged_at, self.asking.judged = -math.inf, -math.inf, True

    def cancel(self) -> None:
        """Forget every request still waiting for an ack or a retry (the owner stopped)."""
        for ticket in self.tickets:
            self.host.autopilot.cancel(ticket)

    def seen(self, step: str) -> bool:
        """The vehicle shows ``step``: the heartbeat's mode (or showed it, and the autopilot went on from it by itself), armed state."""
        asking = self.asking if self.asking is not None and self.asking.step == step else None
        if asking is not None and asking.seen_by is not None:
            return asking.seen_by()
        if step == DISARM:
            return not self.host.get("/vehicle/armed")
        if step == ARM:
            return bool(self.host.get("/vehicle/armed"))
        mode, shown = self.host.get("/vehicle/mode"), self._shown(step)
        if mode == shown:
            if asking is not None:
                asking.was_shown = True
            return True
        # the autopilot went on from it by itself, by the firmware's own cause (executive.mode_cause: a sub at the surface)
        return asking is not None and asking.was_shown and self.host.get("/vehicle/mode_set_by") == "autopilot"

    # -- internals ---------------------------------------------------------------------------

    def _ask(self, asking: Step) -> bool:
        """Send one ask of ``asking``; False when the autopilot has no such mode, or the owner's command could not be asked."""
        if asking.send is not None:
            sent = asking.send()  # a command's own ask: a KeyError (no such mode) is its owner's to meet
            if sent is None:
                return False
            request = sent
        else:
            named = self._ask_by_name(asking)
            if named is None:
                return False
            request = named
        again = asking.asks > 0
        self.tickets.append(request)
        asking.request, asking.asked_at, asking.asks, asking.judged = request, self.host.clock.now(), asking.asks + 1, False
        self.voice.asked(asking, again)
        return True

    def _ask_by_name(self, asking: Step) -> Request | None:
        """Ask a disarm, an arm or a mode; None when the autopilot has no such mode."""
        autopilot = self.host.autopilot
        try:
            if asking.step == DISARM:
                request = autopilot.disarm()
                if self.on_disarm is not None:
                    self.on_disarm()
            elif asking.step == ARM:
                request = autopilot.arm()
            else:
                request = autopilot.set_mode(asking.step)
                self.mode_in_force = asking.step
        except KeyError:
            self.voice.no_such_mode(asking.cause, asking.step)
            return None
        return request

    def _outcome(self, asking: Step, status: CommandStatus | None, now: float) -> str | None:
        """What became of the latest ask, once known: refused, no answer, or accepted with the vehicle not seen in it."""
        if status is not None and status.state is CommandState.REJECTED:
            return f"refused ({status.result_name})"
        if status is not None and status.state is CommandState.TIMED_OUT:
            return "no answer"
        if status is not None and status.state is CommandState.RETRYING:
            return None  # the port asks again by itself, and ends it with the refusal at its own bound
        if not now - max(asking.asked_at, asking.retried_at) > self.rules.judge_after_s:
            return None
        if status is not None and status.state is CommandState.ACCEPTED:
            if asking.seen_by is not None:
                return "accepted, not confirmed"
            if asking.step in (DISARM, ARM):
                return f"accepted, the vehicle still {'armed' if asking.step == DISARM else 'disarmed'}"
            return f"accepted, the vehicle still in {self.host.get('/vehicle/mode') or 'an unknown mode'}"
        return "no answer"

    def _judge(self, asking: Step, outcome: str, status: CommandStatus | None, now: float) -> None:
        asking.judged, asking.judged_at, asking.status = True, now, status
        counts = self.rules.link_down_counts or outcome != "no answer" or bool(self.host.get("/link/up"))
        asking.failed += counts
        first = asking.outcomes[outcome] == 0
        asking.outcomes[outcome] += 1
        asking.last = outcome
        bound = self.rules.give_up_after_s
        asking.gave_up = bound is not None and now - asking.since + self.rules.rest_s > bound
        self.voice.failed(asking, outcome, first=first, counted=counts)

    def _shown(self, step: str) -> str:
        return "disarm" if step == DISARM else "arm" if step == ARM else self.host.autopilot.mode_name(step)

    def _no_position(self) -> str | None:
        """Why the autopilot has no position estimate now, if the reports say so (no report: not known, asked anyway)."""
        if self.host.get("/vehicle/ekf_failsafe"):
            return "the autopilot's EKF failsafe is on"
        ekf: EkfStatus | None = self.host.get("/vehicle/ekf")
        if ekf is not None and not ekf.position_ok():
            return f"the EKF has no position estimate (flags {int(ekf.flags):#x})"
        return None


def refusal_reason(status: CommandStatus | None, request: Request | None, statustext: tuple[int, str] | None) -> str | None:
    """Why the command of ``request`` failed (refused, or no ack after every retry); None if it has not."""
    if status is None or request is None or status.ticket != request.ticket:
        return None
    if status.state is CommandState.TIMED_OUT:
        return f"no ack after {status.attempts} attempts"
    if status.state is CommandState.REJECTED:
        return f"refused: {status.result_name}" + (f" ({statustext[1]})" if statustext else "")
    return None


def retry_reason(status: CommandStatus | None, request: Request | None, statustext: tuple[int, str] | None) -> str | None:
    """The refusal the autopilot port answers by asking again (PX4's AUTO.MISSION while it checks a new mission); None if not."""
    if status is None or request is None or status.ticket != request.ticket or status.state is not CommandState.RETRYING:
        return None
    return f"refused: {status.result_name}" + (f" ({statustext[1]})" if statustext else "") + "; asked again"


def accepted(status: CommandStatus | None, request: Request | None) -> bool:
    """The command of ``request`` was accepted."""
    return status is not None and request is not None and status.ticket == request.ticket and status.state is CommandState.ACCEPTED


def _outcome_text(asking: Step) -> str:
    """``HOLD refused (FAILED) x3``, ``disarm not answered x3``: a step's judged asks, for an account."""
    last = "not answered" if asking.last == "no answer" else asking.last
    count = asking.outcomes[asking.last] if asking.last is not None else 0
    return f"{asking.shown} {last}" + (f" x{count}" if count > 1 else "")


def _short(outcome: str | None) -> str:
    """An outcome for a STATUSTEXT (50 characters): ``accepted, still GUIDED``."""
    return (outcome or "").replace("the vehicle still in ", "still ").replace("the vehicle still ", "still ")
