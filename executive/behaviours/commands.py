"""Commands and their acks: ask the autopilot port for an outcome once, then watch the blackboard for its effect.

An action never waits inside a tick. It asks in ``initialise`` (the command goes out after the
tick) and each ``update`` looks at what came back: the ack in ``/command/<outcome>`` and, for the
effect itself, the vehicle state (ArduPilot can ack a mode change that the heartbeat never shows).
The asking is the one mechanism's (:class:`~executive.autopilot.asking.Asker`, with :data:`ONE_ASK`'s
rules). Here: the framework (:class:`CommandAction`) and the commands of modes, arming and speed.

Every action needs the ``clock`` and the ``autopilot`` (an :class:`~executive.autopilot.AutopilotPort`)
from ``tree.setup``.
"""

from __future__ import annotations

from dataclasses import replace

from py_trees.common import Status

from executive.autopilot import AutopilotPort, Request
from executive.autopilot.asking import Asker, Rules, Step, Voice, accepted, refusal_reason, retry_reason
from executive.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS, TimedBehaviour
from executive.mission.model import Waypoint
from executive.world import blackboard
from executive.world.state import CommandStatus, Outcome

#: A command's asking: one ask (the commander resends it unacked), confirmed by the vehicle's state alone, judged failed when
#: refused, unanswered or not confirmed after the action's ``confirm_timeout_s``; never asked again nor replaced.
ONE_ASK = Rules(asks_before_next=1, needs_ack=False, link_down_counts=True)


class CommandAction(TimedBehaviour):
    """Request a command once; SUCCESS when the vehicle state confirms it, FAILURE when refused or unconfirmed.

    A refusal the autopilot port asks again by itself (RETRYING) is waited out: the confirmation
    timeout counts from the last refusal, and the port's own bound ends it with the refusal.
    Asked by an :class:`~executive.autopilot.asking.Asker` (:data:`ONE_ASK`); its outcome is the feedback.
    """

    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    outcome = ""  # what the request asks of the autopilot (an Outcome): its ack is on blackboard.command_key(outcome)
    catalogued = False  # a base: its subclasses are the actions

    def __init__(self, name: str, confirm_timeout_s: float = 5.0) -> None:
        self.reads = (*self.reads, blackboard.command_key(self.outcome), "/vehicle/statustext")
        super().__init__(name)
        self.confirm_timeout_s = confirm_timeout_s
        self._asker = Asker(self, None, rules=ONE_ASK, voice=_CommandVoice(self), escalate=False, bounded=True)
        self._rules = ONE_ASK  # the rules of the last run: made again only when its time allowed differs (Surface's depends on the depth)

    @property
    def _ticket(self) -> Request | None:
        """The request of this run (None: nothing asked)."""
        asking = self._asker.asking
        return asking.request if asking is not None else None

    def request(self) -> Request:
        """Ask the autopilot for the command; returns its request."""
        raise NotImplementedError

    def confirmed(self) -> bool:
        """The vehicle state shows the command took effect."""
        raise NotImplementedError

    def progress(self) -> str | None:
        """What the vehicle shows so far (for the feedback while waiting, and in a timeout's reason)."""
        return None

    def initialise(self) -> None:
        super().initialise()
        self._asker.forget()  # a new run: the ack of the previous one (ChangeSpeed's confirmation) says nothing about it
        if self._rules.judge_after_s != self.confirm_timeout_s:  # frozen: the same rules serve every run with the same time allowed
            self._rules = replace(ONE_ASK, judge_after_s=self.confirm_timeout_s)
        self._asker.rules = self._rules
        if not self.confirmed():
            self._asker.start_command(self.name, self.request, self.confirmed, self.name)

    def terminate(self, new_status: Status) -> None:
        if new_status == INVALID:  # interrupted: what it asked for no longer matters
            self.autopilot.cancel(self._ticket)

    def update(self) -> Status:
        if self.confirmed():
            self.feedback_message = "confirmed"
            return SUCCESS
        asking = self._asker.asking
        if asking is None:  # confirmed when it started, not since: nothing was asked to make it so
            self.feedback_message = "no longer confirmed"
            return FAILURE
        self._asker.follow_up(self.clock.now(), ask=False)
        if asking.judged:  # refused, unanswered or not confirmed in time: the voice said which
            return FAILURE
        status: CommandStatus | None = self.get(blackboard.command_key(self.outcome))
        retrying = retry_reason(status, asking.request, self.get("/vehicle/statustext"))
        self.feedback_message = retrying or self.progress() or "waiting for the autopilot"
        return RUNNING


class _CommandVoice(Voice):
    """A command's failed ask, as its feedback: the refusal, or what the vehicle shows after the time allowed."""

    def __init__(self, action: CommandAction) -> None:
        self.action = action

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        action = self.action
        refusal = refusal_reason(step.status, step.request, action.get("/vehicle/statustext"))
        if refusal is None:
            seen = action.progress()
            refusal = f"not confirmed after {action.confirm_timeout_s:g} s" + (f": {seen}" if seen else "")
        action.feedback_message = refusal


class SetMode(CommandAction):
    """Put the autopilot in a flight mode (by name); confirmed by the heartbeat.

    With ``confirm_by_ack`` the ack ACCEPTED of its own latest request confirms it too, until the
    next heartbeat speaks: ArduPilot changes mode before it acks (GCS_MAVLINK::_set_mode_common,
    libraries/GCS_MAVLink/GCS_Common.cpp, acks ACCEPTED only when set_mode succeeded), while its
    heartbeat comes once a second. A step re-ticked every tick does not ask again meanwhile; a
    heartbeat after the ack showing another mode (someone changed it since) is believed.
    """

    reads = ("/vehicle/mode", "/link/last_heartbeat")
    outcome = Outcome.MODE
    param_docs = {"confirm_by_ack": "its own ACCEPTED ack confirms it too, until the next heartbeat (moving a tick after the ack)"}

    def __init__(self, mode: str, name: str | None = None, confirm_timeout_s: float = 5.0, confirm_by_ack: bool = False) -> None:
        super().__init__(name or f"Set {mode.upper()}", confirm_timeout_s)
        self.mode = mode.upper()
        self.confirm_by_ack = confirm_by_ack
        self._last_request: Request | None = None  # kept across runs: its ack still counts until a heartbeat comes

    def request(self) -> Request:
        self._last_request = self.autopilot.set_mode(self.mode)
        return self._last_request

    def confirmed(self) -> bool:
        if self.get("/vehicle/mode") == self.autopilot.mode_name(self.mode):
            return True
        if not self.confirm_by_ack:
            return False
        status: CommandStatus | None = self.get(blackboard.command_key(self.outcome))
        heartbeat: float | None = self.get("/link/last_heartbeat")
        if status is None or heartbeat is None or not accepted(status, self._last_request):
            return False
        return heartbeat <= status.time


class Arm(CommandAction):
    """Arm the vehicle; confirmed by the heartbeat. A refusal (pre-arm checks) is a FAILURE to retry later."""

    reads = ("/vehicle/armed",)
    outcome = Outcome.ARMING

    def __init__(self, name: str = "Arm", confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name, confirm_timeout_s)

    def request(self) -> Request:
        return self.autopilot.arm()

    def confirmed(self) -> bool:
        return bool(self.get("/vehicle/armed"))


class Disarm(Arm):
    """Disarm the vehicle; confirmed by the heartbeat."""

    def __init__(self, name: str = "Disarm", confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name, confirm_timeout_s)

    def request(self) -> Request:
        return self.autopilot.disarm()

    def confirmed(self) -> bool:
        return not self.get("/vehicle/armed")


class HoldFor(SetMode):
    """Hold the vehicle in ``mode`` for ``seconds``: set the mode (confirmed by the heartbeat), then RUNNING until the time is up.

    The time counts from the heartbeat showing the mode. A refused or unconfirmed mode is a
    FAILURE (as SetMode); so is the vehicle leaving the mode during the hold (someone else has it).
    """

    param_units = {"seconds": "s"}
    param_docs = {"seconds": "how long the mode is held, from the heartbeat showing it"}

    def __init__(self, seconds: float, mode: str = "LOITER", name: str | None = None, confirm_timeout_s: float = 5.0) -> None:
        super().__init__(mode, name or f"Hold {mode.upper()} {seconds:g} s", confirm_timeout_s)
        self.seconds = seconds
        self._holding_since: float | None = None

    def initialise(self) -> None:
        super().initialise()
        self._holding_since = None

    def update(self) -> Status:
        if self._holding_since is None:
            status = super().update()
            if status != SUCCESS:
                return status
            self._holding_since = self.clock.now()
        elif not self.confirmed():
            self.feedback_message = f"left {self.mode} (now {self.get('/vehicle/mode')}) after {self.clock.now() - self._holding_since:.1f} s"
            return FAILURE
        held = self.clock.now() - self._holding_since
        if held >= self.seconds:
            self.feedback_message = f"held {self.mode} for {self.seconds:g} s"
            return SUCCESS
        self.feedback_message = f"holding {self.mode}: {held:.0f}/{self.seconds:g} s"
        return RUNNING


class ChangeSpeed(CommandAction):
    """Set the speed of the current leg (its waypoint's ``speed_m_s``) with MAV_CMD_DO_CHANGE_SPEED.

    SUCCESS at once when the waypoint has no speed. Confirmed by the ack ACCEPTED: ArduPilot
    reports the new speed nowhere else. Refused or unanswered: FAILURE. ``airspeed`` for a plane
    in wing-borne flight, else ground speed.
    """

    reads = ("/mission/target",)
    outcome = Outcome.SPEED
    param_docs = {"airspeed": "an airspeed (a plane in wing-borne flight), else a ground speed"}

    def __init__(self, name: str = "Change speed", airspeed: bool = False, confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name, confirm_timeout_s)
        self.airspeed = airspeed
        self.speed_m_s: float | None = None

    def initialise(self) -> None:
        target: Waypoint | None = self.get("/mission/target")
        self.speed_m_s = target.speed_m_s if target is not None else None
        super().initialise()

    def request(self) -> Request:
        assert self.speed_m_s is not None
        return self.autopilot.change_speed(self.speed_m_s, airspeed=self.airspeed)

    def confirmed(self) -> bool:
        return self.speed_m_s is None or accepted(self.get(blackboard.command_key(self.outcome)), self._ticket)

    def update(self) -> Status:
        status = super().update()
        if status == SUCCESS:
            self.feedback_message = "no speed for this leg" if self.speed_m_s is None else f"{self.speed_m_s:g} m/s"
        return status
