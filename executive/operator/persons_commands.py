"""A person's arm, disarm and mode sent through the executive (``ctl``, the web view), followed to what the vehicle did.

A person's command changes the mission only by what it did to the vehicle, as a ground station's does
(:mod:`executive.operator.intervention`): the mission pauses, hands off, in the tick the heartbeat shows the
vehicle in the mode a person asked for (named as the heartbeat shows it: a FOLLOW refused then a SIMPLE
accepted pauses on SIMPLE), or disarmed after a person's disarm. A command the autopilot refuses,
leaves unanswered, or accepts and never shows within :data:`FOLLOWED_FOR_S`, changes nothing: a
RUNNING mission stays RUNNING. ``arm`` never pauses (a mission may wait for it).

Each answer is a warning in the log and the journal (event kind ``operator``), a refusal a STATUSTEXT
too; the latest command and its answer are ``/operator/command`` (the status's ``command``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from executive.autopilot.port import Request
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import CommandState, CommandStatus, Outcome

log = logging.getLogger("executive.operator")  # as the log and the journal (event kind "operator") have it

#: How long (vehicle time) after it was sent a person's command is followed: what the heartbeat shows later is not its doing
#: (the intervention watch's ``asked_within_s``: an ask of ours not seen within it is not why the mode changed).
FOLLOWED_FOR_S = 10.0
#: The blackboard keys of the acks of a person's commands (arming, mode).
COMMAND_KEYS = (blackboard.command_key(Outcome.ARMING), blackboard.command_key(Outcome.MODE))
#: The answers as a person reads them.
_ANSWERS = {CommandState.ACCEPTED: "ACCEPTED by the autopilot", CommandState.TIMED_OUT: "no answer from the autopilot"}


@dataclass
class _Sent:
    """One person's command being followed: what it is, who gave it, its request and what it should show."""

    what: str  # "mode HOLD", "force disarm"
    source: str  # ctl, web...
    request: Request
    mode: str | None  # the mode as the heartbeat names it; None for arm and disarm
    disarm: bool
    at: float
    answered: bool = False


class PersonsCommands:
    """A reader service (call :meth:`service` each tick, before the intervention watch): a person's commands to what they did."""

    def __init__(self, clock: Clock, mission_state: MissionState) -> None:
        self._clock = clock
        self.mission_state = mission_state
        self._sent: list[_Sent] = []
        self._bb = blackboard.reader("persons commands", ["/vehicle/mode", "/vehicle/armed", "/link/up", *COMMAND_KEYS])
        self._out = blackboard.writer("persons commands", ["/operator/command"])
        self._mode: str | None = None
        self._armed = False

    def sent(self, what: str, source: str, request: Request, *, mode: str | None = None, disarm: bool = False) -> None:
        """A person's command was sent (``mode``: as the heartbeat will show it); followed from the next tick."""
        self._sent.append(_Sent(what, source, request, mode, disarm, self._clock.now()))
        self._publish(self._sent[-1], "sent, no answer yet")

    def service(self) -> None:
        now = self._clock.now()
        mode, armed = self._bb.get("/vehicle/mode"), bool(self._bb.get("/vehicle/armed"))
        changed_to = mode if mode != self._mode and self._mode is not None else None
        disarmed = self._armed and not armed
        self._mode, self._armed = mode, armed
        if not self._bb.get("/link/up"):
            return
        for sent in list(self._sent):
            self._follow_answer(sent)
            shown = (sent.mode is not None and changed_to == sent.mode) or (sent.disarm and disarmed)
            if shown:
                self._sent.remove(sent)
                self._shown(sent)
            elif now - sent.at > FOLLOWED_FOR_S or self._refused(sent):
                self._sent.remove(sent)
                if not self._refused(sent) and (sent.mode or sent.disarm):
                    where = "armed" if sent.disarm else f"in {mode}"
                    log.warning("%s: %s: the vehicle still %s after %g s: nothing changed", sent.source, sent.what, where, FOLLOWED_FOR_S)

    def _shown(self, sent: _Sent) -> None:
        """The vehicle did what a person asked: a running mission pauses, hands off (the tree would otherwise undo it)."""
        done = "disarmed" if sent.disarm else f"{sent.mode} set"
        state = self.mission_state
        if state.status is not MissionStatus.RUNNING:
            now = "disarmed" if sent.disarm else f"in {sent.mode}"
            log.warning("%s: %s: the vehicle %s (the mission %s)", sent.source, sent.what, now, state.status)
            return
        reason = f"{done} by a person ({sent.source}: {sent.what})"
        log.warning("%s -> mission paused at leg %d, hands off until resumed", reason, state.legs.leg_index + 1)
        state.pause(reason, hold=False)

    def _follow_answer(self, sent: _Sent) -> None:
        """The autopilot's answer, said once: a warning (the journal's event), a refusal told to the ground station too."""
        if sent.answered:
            return
        status: CommandStatus | None = self._bb.get(blackboard.command_key(sent.request.outcome))
        if status is None or status.ticket < sent.request.ticket or (status.ticket == sent.request.ticket and not status.state.done):
            return
        sent.answered = True
        if status.ticket > sent.request.ticket:  # a newer command of its kind took its place: the heartbeat alone tells
            self._publish(sent, "superseded")
            return
        if status.state is CommandState.ACCEPTED:
            self._publish(sent, _ANSWERS[CommandState.ACCEPTED])
            log.warning("%s: %s ACCEPTED by the autopilot", sent.source, sent.what)
            return
        refused = status.state is CommandState.REJECTED
        answer = f"refused by the autopilot ({status.result_name})" if refused else _ANSWERS.get(status.state, str(status.state))
        self._publish(sent, answer, refused=refused)
        log.warning("%s: %s %s: nothing changed (the mission %s)", sent.source, sent.what, answer, self.mission_state.status)
        short = f"refused ({status.result_name})" if refused else "no answer"
        self.mission_state.announce(f"{sent.source}: {sent.what} {short}"[:50])

    def _refused(self, sent: _Sent) -> bool:
        status: CommandStatus | None = self._bb.get(blackboard.command_key(sent.request.outcome))
        return sent.answered and status is not None and status.ticket == sent.request.ticket and status.state is CommandState.REJECTED

    def _publish(self, sent: _Sent, answer: str, *, refused: bool = False) -> None:
        self._out.set(
            "/operator/command",
            {"what": sent.what, "by": sent.source, "answer": answer, "refused": refused, "t": round(self._clock.now(), 2)},
        )
