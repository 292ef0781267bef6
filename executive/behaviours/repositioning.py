"""A point asked of the autopilot with MAV_CMD_DO_REPOSITION until it accepts it: GoTo's and GoToLocal's ``method="reposition"``.

Asked by the one mechanism (:class:`~executive.autopilot.asking.Asker`) with :func:`until_accepted`'s
rules: the ack ACCEPTED is all the autopilot says of a reposition (the behaviour judges the arrival
itself, within its own time-out); a refusal, or no ack after the commander's own resends, is asked
again no sooner than ``resend_s`` after the last ask, for as long as the behaviour runs. Nothing is
announced: the refusal is named in the behaviour's feedback when its time is up
(:attr:`Repositioning.refusal`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from executive.autopilot import Request
from executive.autopilot.asking import Asker, Host, Rules, Step, Voice, refusal_reason
from executive.world.state import CommandStatus

#: The name a reposition's step goes by.
REPOSITION = "DO_REPOSITION"


def until_accepted(resend_s: float) -> Rules:
    """A reposition's asking: done once accepted; refused or unanswered, asked again ``resend_s`` after the last ask, without end.

    Never judged by time (an ask still waiting for its ack is the commander's to resend), never replaced, never given up.
    """
    return Rules(judge_after_s=math.inf, again_after_s=resend_s, asks_before_next=None, needs_ack=True, link_down_counts=True)


class Repositioning(Voice):
    """An owner's reposition (its clock, port and blackboard: it reads ``/vehicle/statustext`` and the reposition's ack).

    :meth:`follow_up` each tick with the ask to send; :meth:`aim` for a new point (asked at once),
    :meth:`restart` for a new run.
    """

    def __init__(self, owner: Host, resend_s: float) -> None:
        self.owner, self.resend_s = owner, resend_s
        self.asker = Asker(owner, None, rules=until_accepted(resend_s), voice=self, escalate=False)
        #: The refusal (or "no ack after N attempts") that the latest ask answered; None again once an ask stood ``resend_s``
        #: unrefused (accepted, or still waiting for its ack).
        self.refusal: str | None = None
        self._failed: tuple[CommandStatus | None, Request | None] = (None, None)

    def restart(self) -> None:
        """A new run: nothing asked, nothing refused."""
        self.asker.forget()
        self.refusal = None

    def aim(self) -> None:
        """A new point: asked at the next :meth:`follow_up` (the last refusal is kept until then)."""
        self.asker.forget()

    def follow_up(self, send: Callable[[], Request]) -> None:
        """Ask ``send`` if nothing is asked yet, else follow the ask: accepted, or asked again when the rules say."""
        asker, now = self.asker, self.owner.clock.now()
        asking = asker.asking
        if asking is None:
            asker.start_command(REPOSITION, send, lambda: True, REPOSITION)
            return
        asker.follow_up(now)
        if asking.asked_at < now and now - asking.asked_at >= self.resend_s:
            self.refusal = None  # an ask that stood resend_s unrefused: the autopilot has it, or its ack is still awaited

    # -- Voice: what becomes of the asks -----------------------------------------------------------

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        self._failed = (step.status, step.request)

    def asked(self, step: Step, again: bool) -> None:
        if again:  # asked again because the last ask failed: that refusal, as the autopilot's STATUSTEXT has it now
            self.refusal = refusal_reason(*self._failed, self.owner.get("/vehicle/statustext"))
