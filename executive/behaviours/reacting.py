"""Asking the autopilot for a failsafe reaction until it is done, else the next one the firmware allows.

A reaction (a mode, or a disarm) is done only when the autopilot has accepted it (its COMMAND_ACK on
``/command/...``) and the heartbeat shows the vehicle in it. Until then :meth:`Reacting.state` says
what it waits for (``asking HOLD: refused (FAILED) x2``), and it is asked again every
:data:`ASK_AGAIN_S` of vehicle time. After :data:`ASKS_BEFORE_NEXT` failed asks (refused; accepted
but not seen; unanswered while heartbeats arrive), or at once when the firmware's source says the
vehicle cannot enter it in its present state (a position mode without a position estimate), the
next reaction the firmware allows is asked instead (:mod:`executive.autopilot.fallbacks`). Each such
step is a warning (the journal's ``failsafe`` event) and an announcement (a STATUSTEXT).

It never blocks: the behaviour that owns it calls :meth:`Reacting.follow_up` each tick and reads the
blackboard keys in :data:`READS` (add them to its own ``reads``).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from executive.autopilot import AutopilotPort, Request
from executive.autopilot.fallbacks import DISARM, Fallback, chain, fallback
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
#: The blackboard keys a behaviour that reacts reads.
READS = (
    "/vehicle/armed", "/vehicle/mode", "/vehicle/mode_set_by", "/vehicle/ekf", "/vehicle/ekf_failsafe", "/link/up",
    blackboard.command_key(Outcome.MODE), blackboard.command_key(Outcome.ARMING),
)  # fmt: skip
#: Told of each step a person must hear: a short text (a STATUSTEXT holds 50 characters), and whether it is a warning.
Announce = Callable[[str, bool], None]


class Host(Protocol):
    """The behaviour that owns a :class:`Reacting`: its clock, autopilot port and blackboard (with :data:`READS`)."""

    clock: Clock
    autopilot: AutopilotPort

    def get(self, key: str) -> Any: ...


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
    was_shown: bool = False  # the heartbeat showed the vehicle in it (since it was asked)
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


class Reacting:
    """One behaviour's reaction, asked until done: :meth:`start` it, call :meth:`follow_up` each tick, show :meth:`state`.

    ``escalate``: after refusals, or when the vehicle cannot enter it now, the next reaction the
    firmware allows; without it the same reaction is asked again until the owner gives up.
    ``on_disarm`` is called when a disarm is asked (the owner re-arms the vehicle it disarmed).
    ``vehicle``: the vehicle kind (None: not known, no next reactions and no follow-on modes).
    ``bounded``: the owner stops once :attr:`exhausted` (the last reaction is not asked a fourth time).
    Its steps go to ``logger`` as ``<prefix><cause>: ...`` (a failsafe's: ``failsafe ekf_loss: ...``).
    """

    def __init__(
        self,
        host: Host,
        vehicle: str | None,
        *,
        announce: Announce | None = None,
        escalate: bool = True,
        on_disarm: Callable[[], None] | None = None,
        bounded: bool = False,
        logger: logging.Logger = log,
        prefix: str = "failsafe ",
    ) -> None:
        self.host, self.vehicle = host, vehicle
        self.announce, self.escalate, self.on_disarm = announce, escalate, on_disarm
        self.log, self.prefix, self.bounded = logger, prefix, bounded
        self.asking: _Asking | None = None
        self._passed: list[str] = []  # the reactions replaced by the next one, and why: ``HOLD refused (FAILED) x3``
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
        """The reaction asked last is done: accepted, and the vehicle seen in it."""
        return self.asking is not None and self.asking.confirmed

    @property
    def exhausted(self) -> bool:
        """Nothing more to ask: nothing could be, or the last reaction the firmware allows failed :data:`ASKS_BEFORE_NEXT` asks."""
        asking = self.asking
        if asking is None:
            return True
        then = self._fallback(asking.step).then if self.escalate else None
        return not asking.confirmed and then is None and asking.judged and asking.failed >= ASKS_BEFORE_NEXT

    def time_to_exhaust(self, step: str) -> float:
        """How long asking ``step`` and each reaction after it may take: :data:`ASKS_BEFORE_NEXT` asks :data:`ASK_AGAIN_S` apart each."""
        steps = len(list(chain(self._firmware, self.vehicle or "", step))) if self.escalate else 1
        return steps * ASKS_BEFORE_NEXT * ASK_AGAIN_S

    def account(self) -> str:
        """What each reaction asked came to: ``HOLD refused (FAILED) x3, disarmed (confirmed)``, ``HOLD not answered x6 (no heartbeat: ...)``."""
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
        """A request of the owner's that belongs to the reaction (the manual mode before a disarm): cancelled with it."""
        self.tickets.append(request)
        if mode is not None:
            self.mode_in_force = mode

    def start(self, step: str, cause: str, instead_of: str | None = None, path: tuple[str, ...] = ()) -> None:
        """Ask for ``step``, or the first reaction after it that the vehicle can enter in its present state."""
        now = self.host.clock.now()
        for candidate in chain(self._firmware, self.vehicle or "", step) if self.escalate else (step,):
            path = (*path, candidate)
            rule = self._fallback(candidate)
            shown = self._shown(candidate)
            if self.escalate and rule.needs_position and (missing := self._no_position()) and rule.then is not None:
                after = self._shown(rule.then)
                self._step(
                    cause, f"{shown} cannot be entered: {missing} ({rule.why}) -> {after} instead", f"{cause}: no position for {shown} -> {after}"
                )
                self._passed.append(f"{shown} cannot be entered ({missing})")
                instead_of = shown
                continue
            self.asking = _Asking(candidate, shown, cause, instead_of, now, path)
            if self._ask(self.asking):
                return
            self._passed.append(f"{shown}: the autopilot has no such mode")
            instead_of = shown  # the firmware has no such mode: the next one
        self.asking = None

    def follow_up(self, now: float, *, ask: bool = True) -> None:
        """The reaction asked for: done (accepted and seen), or judged, asked again, or replaced by the next one.

        ``ask`` False: judged and confirmed only, nothing asked (the owner's time is up).
        """
        asking = self.asking
        if asking is None or asking.confirmed or asking.request is None:
            return
        status: CommandStatus | None = self.host.get(blackboard.command_key(asking.request.outcome))
        mine = status is not None and status.ticket == asking.request.ticket
        if mine and status.state is CommandState.ACCEPTED:
            asking.acked = True
        if asking.acked and self.seen(asking.step):
            asking.confirmed = True
            self._confirmed(asking, now)
            return
        if not asking.judged:
            outcome = self._outcome(asking, status if mine else None, now)
            if outcome is not None:
                self._judge(asking, outcome)
        if not asking.judged or now - asking.asked_at < ASK_AGAIN_S - 1e-6 or not ask or (self.bounded and self.exhausted):
            return
        then = self._fallback(asking.step).then if self.escalate else None
        if asking.failed >= ASKS_BEFORE_NEXT and then is not None:
            after = self._shown(then)
            times = f" x{asking.outcomes[asking.last]}" if asking.last else ""
            self._step(
                asking.cause,
                f"{asking.shown} {asking.last}{times} after {asking.asks} asks -> {after} instead ({self._fallback(asking.step).why})",
                f"{asking.cause}: {asking.shown} {_short(asking.last)}{times} -> {after}",
            )
            self.host.autopilot.cancel(asking.request)  # its ask still waiting for an ack is not sent again (the commander would)
            self._passed.append(_outcome_text(asking))
            self.start(then, asking.cause, asking.shown, asking.path)
            return
        self._ask(asking)

    def state(self) -> str | None:
        """What the reaction waits for, or where it left the vehicle; None when nothing was asked."""
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
            self.asking.asked_at, self.asking.judged = -math.inf, True  # not a failed ask: asked again at once when they let go

    def cancel(self) -> None:
        """Forget every request still waiting for an ack or a retry (the owner stopped)."""
        for ticket in self.tickets:
            self.host.autopilot.cancel(ticket)

    def seen(self, step: str) -> bool:
        """The heartbeat shows the vehicle in ``step``, or showed it and the autopilot went on from it by itself (a sub at the surface)."""
        if step == DISARM:
            return not self.host.get("/vehicle/armed")
        mode, shown = self.host.get("/vehicle/mode"), self._shown(step)
        asking = self.asking if self.asking is not None and self.asking.step == step else None
        if mode == shown:
            if asking is not None:
                asking.was_shown = True
            return True
        # the autopilot went on from it by itself, by the firmware's own cause (executive.autopilot.mode_cause: a sub at the surface)
        return asking is not None and asking.was_shown and self.host.get("/vehicle/mode_set_by") == "autopilot"

    # -- internals ---------------------------------------------------------------------------

    def _ask(self, asking: _Asking) -> bool:
        """Send one ask of ``asking``; False when the autopilot has no such mode."""
        autopilot = self.host.autopilot
        try:
            if asking.step == DISARM:
                request = autopilot.disarm()
                if self.on_disarm is not None:
                    self.on_disarm()
            else:
                request = autopilot.set_mode(asking.step)
                self.mode_in_force = asking.step
        except KeyError:
            self.log.error("%s%s: the autopilot has no mode %s", self.prefix, asking.cause, asking.step)
            return False
        self.tickets.append(request)
        asking.request, asking.asked_at, asking.asks, asking.judged = request, self.host.clock.now(), asking.asks + 1, False
        return True

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
            return f"accepted, the vehicle still in {self.host.get('/vehicle/mode') or 'an unknown mode'}"
        return "no answer"

    def _judge(self, asking: _Asking, outcome: str) -> None:
        asking.judged = True
        counts = outcome != "no answer" or bool(self.host.get("/link/up"))
        asking.failed += counts
        first = asking.outcomes[outcome] == 0
        asking.outcomes[outcome] += 1
        asking.last = outcome
        if first:
            link = "" if counts else " and no heartbeat (the link is down)"
            self._step(
                asking.cause,
                f"{asking.shown} {outcome}{link} -> asked again every {ASK_AGAIN_S:g} s",
                f"{asking.cause}: {asking.shown} {_short(outcome)}",
            )

    def _confirmed(self, asking: _Asking, now: float) -> None:
        done = "disarmed" if asking.step == DISARM else f"in {asking.shown}"
        text = f"the vehicle {done} (accepted and seen; {asking.asks} ask{'s' if asking.asks > 1 else ''}, {now - asking.since:.1f} s)"
        if asking.failed or asking.instead_of or asking.last:
            self._step(asking.cause, text, f"{asking.cause}: {done}, confirmed", warning=False)
        else:
            self.log.info("%s%s: %s", self.prefix, asking.cause, text)

    def _shown(self, step: str) -> str:
        return "disarm" if step == DISARM else self.host.autopilot.mode_name(step)

    def _no_position(self) -> str | None:
        """Why the autopilot has no position estimate now, if the reports say so (no report: not known, asked anyway)."""
        if self.host.get("/vehicle/ekf_failsafe"):
            return "the autopilot's EKF failsafe is on"
        ekf: EkfStatus | None = self.host.get("/vehicle/ekf")
        if ekf is not None and not ekf.position_ok():
            return f"the EKF has no position estimate (flags {int(ekf.flags):#x})"
        return None

    def _step(self, cause: str, text: str, short: str, *, warning: bool = True) -> None:
        """A step of a reaction: a warning (the journal's event), and a short STATUSTEXT (``warning``: else a notice)."""
        self.log.warning("%s%s: %s", self.prefix, cause, text)
        if self.announce is not None:
            self.announce(short, warning)


def _outcome_text(asking: _Asking) -> str:
    """``HOLD refused (FAILED) x3``, ``disarm not answered x3``: a reaction's judged asks, for an account."""
    last = "not answered" if asking.last == "no answer" else asking.last
    count = asking.outcomes[asking.last] if asking.last is not None else 0
    return f"{asking.shown} {last}" + (f" x{count}" if count > 1 else "")


def _short(outcome: str | None) -> str:
    """An outcome for a STATUSTEXT (50 characters): ``accepted, still GUIDED``."""
    return (outcome or "").replace("the vehicle still in ", "still ").replace("the vehicle still ", "still ")
