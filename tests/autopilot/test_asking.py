"""The one asking mechanism (executive.autopilot.asking): ask, confirm by what the vehicle reports, ask again, escalate or give up.

A stand-in autopilot port records what is asked and when (vehicle time on a manual clock); the test plays the autopilot's acks
and heartbeat by writing the keys the asker reads.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest

from executive.autopilot import Request
from executive.autopilot.asking import ARM, ASK_AGAIN_S, REACTION, Asker, Rules, Step, Voice
from executive.autopilot.fallbacks import DISARM
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.state import CommandState, CommandStatus, Outcome

MODE_KEY, ARMING_KEY = blackboard.command_key(Outcome.MODE), blackboard.command_key(Outcome.ARMING)


@dataclass
class _Capabilities:
    autopilot: str = "ardupilot"


@dataclass
class _Port:
    """What the asker asks, in order: (time, what); its tickets count up from 1."""

    clock: ManualClock
    capabilities: _Capabilities = field(default_factory=_Capabilities)
    asked: list[tuple[float, str]] = field(default_factory=list)
    cancelled: list[int] = field(default_factory=list)
    modes: tuple[str, ...] = ("HOLD", "RTL", "LOITER", "MANUAL", "AUTO")

    def _request(self, what: str, outcome: str) -> Request:
        self.asked.append((self.clock.now(), what))
        return Request(len(self.asked), outcome, what)

    def mode_name(self, mode: str) -> str:
        if mode not in self.modes:
            raise KeyError(mode)
        return mode

    def set_mode(self, mode: str) -> Request:
        return self._request(self.mode_name(mode), Outcome.MODE)

    def arm(self) -> Request:
        return self._request(ARM, Outcome.ARMING)

    def disarm(self) -> Request:
        return self._request(DISARM, Outcome.ARMING)

    def cancel(self, request: Request | None) -> None:
        if request is not None:
            self.cancelled.append(request.ticket)


class _Host:
    """An owner: a clock, the port, and the blackboard keys it reads (a dict the test writes)."""

    def __init__(self) -> None:
        self.clock = ManualClock()
        self.autopilot: Any = _Port(self.clock)
        self.keys: dict[str, Any] = {"/link/up": True, "/vehicle/armed": True, "/vehicle/mode": "AUTO"}

    def get(self, key: str) -> Any:
        return self.keys.get(key)

    def ack(self, state: CommandState, result_name: str = "FAILED", key: str = MODE_KEY) -> None:
        """The autopilot's answer to the latest ask."""
        ticket = len(self.autopilot.asked)
        self.keys[key] = CommandStatus(ticket, 176, "DO_SET_MODE", state, None, 1, self.clock.now(), result_name)

    def run(self, asker: Asker, seconds: float, tick_s: float = 0.1, *, refuse: bool = False) -> None:
        """``seconds`` of ticks; ``refuse``: the autopilot refuses each mode asked, in the tick after it."""
        for _ in range(round(seconds / tick_s)):
            self.clock.advance(tick_s)
            latest = self.get(MODE_KEY)
            if refuse and self.autopilot.asked and (latest is None or latest.ticket != len(self.autopilot.asked)):
                self.ack(CommandState.REJECTED)
            asker.follow_up(self.clock.now())


class _Told(Voice):
    """Every step as a line: what the owner was told, in order."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def asked(self, step: Step, again: bool) -> None:
        self.lines.append(f"asked {step.shown}" + (" again" if again else ""))

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        self.lines.append(f"{step.shown} {outcome}" + (" (gave up)" if step.gave_up else ""))

    def replaced(self, step: Step, after: str, why: str) -> None:
        self.lines.append(f"{step.shown} -> {after}")

    def cannot_enter(self, cause: str, shown: str, missing: str, why: str, after: str) -> None:
        self.lines.append(f"{shown} cannot be entered -> {after}")

    def confirmed(self, step: Step, took_s: float) -> None:
        self.lines.append(f"{step.shown} confirmed after {took_s:.1f} s")


@pytest.fixture
def host() -> _Host:
    return _Host()


def times(host: _Host) -> list[tuple[float, str]]:
    return [(round(t, 3), what) for t, what in host.autopilot.asked]


def test_confirmed_by_the_ack_and_the_heartbeat_is_asked_once(host: _Host) -> None:
    told = _Told()
    asker = Asker(host, "rover", voice=told)
    asker.start("HOLD", "ekf_loss")
    host.run(asker, 0.3)
    host.ack(CommandState.ACCEPTED)
    host.run(asker, 0.5)
    assert not asker.done  # accepted, the heartbeat not showing it yet
    host.keys["/vehicle/mode"] = "HOLD"
    host.run(asker, 3.0)
    assert asker.done and asker.state() == "in HOLD" and times(host) == [(0.0, "HOLD")]
    assert told.lines == ["asked HOLD", "HOLD confirmed after 0.9 s"]


def test_the_heartbeat_alone_does_not_confirm_a_reaction_but_does_when_the_rules_say_so(host: _Host) -> None:
    host.keys["/vehicle/mode"] = "HOLD"  # seen, never acked
    reaction = Asker(host, "rover")
    reaction.start("HOLD", "ekf_loss")
    host.run(reaction, 0.2)
    assert not reaction.done
    switch = Asker(host, None, rules=Rules(needs_ack=False), escalate=False)
    switch.start("HOLD", "switch C")
    host.run(switch, 0.1)
    assert switch.done


def test_refused_asked_again_every_interval_then_the_next_step_of_the_fallback_chain(host: _Host) -> None:
    told = _Told()
    asker = Asker(host, "rover", voice=told)
    asker.start("HOLD", "ekf_loss")
    host.run(asker, 5.0, refuse=True)
    # ArduRover's HOLD, then a disarm (executive/autopilot/fallbacks.py): 3 asks 1.5 s apart, then the next at once
    assert times(host) == [(0.0, "HOLD"), (1.5, "HOLD"), (3.0, "HOLD"), (4.5, DISARM)]
    assert host.autopilot.cancelled == [3]  # the last HOLD's retries end with it
    assert told.lines == [
        "asked HOLD",
        "HOLD refused (FAILED)",
        "asked HOLD again",
        "HOLD refused (FAILED)",
        "asked HOLD again",
        "HOLD refused (FAILED)",
        "HOLD -> disarm",
        "asked disarm",
    ]
    assert asker.state() == "asking disarm instead of HOLD" and asker.covers("HOLD") and asker.covers(DISARM)


def test_a_step_the_vehicle_cannot_enter_now_is_passed_over_at_once(host: _Host) -> None:
    told = _Told()
    host.keys["/vehicle/ekf_failsafe"] = True  # no position: ArduRover refuses RTL (Rover/mode.cpp Mode::enter)
    asker = Asker(host, "rover", voice=told)
    asker.start("RTL", "link_loss")
    assert times(host) == [(0.0, "HOLD")] and told.lines == ["RTL cannot be entered -> HOLD", "asked HOLD"]


def test_unanswered_while_the_link_is_down_is_asked_again_but_not_counted(host: _Host) -> None:
    host.keys["/link/up"] = False
    asker = Asker(host, "rover")
    asker.start("HOLD", "link_loss")
    host.run(asker, 9.05)
    assert [what for _, what in host.autopilot.asked] == ["HOLD"] * 7  # never replaced by the disarm: nothing is known
    assert asker.asking is not None and asker.asking.failed == 0 and not asker.exhausted


def test_bounded_gives_up_after_the_last_steps_asks(host: _Host) -> None:
    asker = Asker(host, "rover", bounded=True)
    asker.start("HOLD", "make safe")
    host.run(asker, asker.time_to_exhaust("HOLD") + 1.0)
    assert times(host) == [(0.0, "HOLD"), (1.5, "HOLD"), (3.0, "HOLD"), (4.5, DISARM), (6.0, DISARM), (7.5, DISARM)]
    assert asker.exhausted and not asker.done
    assert asker.account() == "HOLD not answered x3, disarm not answered x3"


def test_a_switch_rests_after_a_failure_and_gives_up_at_its_bound_in_time(host: _Host) -> None:
    told = _Told()
    rules = Rules(judge_after_s=5.0, again_after_s=0.0, rest_s=2.0, asks_before_next=None, needs_ack=False, give_up_after_s=20.0)
    asker = Asker(host, None, rules=rules, voice=told, escalate=False, bounded=True)
    asker.start("MANUAL", "switch C UP")
    host.run(asker, 30.0, tick_s=0.25)
    # judged on the first tick after 5 s, asked again 2 s after the failure; the next ask would come after 20 s from the wish: given up
    assert times(host) == [(0.0, "MANUAL"), (7.25, "MANUAL"), (14.5, "MANUAL")]
    assert told.lines[-2:] == ["asked MANUAL again", "MANUAL no answer (gave up)"]
    assert asker.exhausted and not asker.due(host.clock.now())


def test_one_ask_refused_is_given_up_at_once(host: _Host) -> None:
    told = _Told()
    host.keys["/vehicle/armed"] = False
    asker = Asker(
        host,
        None,
        rules=Rules(judge_after_s=5.0, asks_before_next=1, needs_ack=False, link_down_counts=True),
        voice=told,
        escalate=False,
        bounded=True,
    )
    asker.start(ARM, "switch D DOWN")
    host.run(asker, 0.2)
    host.ack(CommandState.REJECTED, key=ARMING_KEY)
    host.run(asker, 10.0)
    assert times(host) == [(0.0, ARM)] and asker.exhausted
    assert told.lines == ["asked arm", "arm refused (FAILED)"]


def test_a_command_of_its_own_is_confirmed_by_its_own_test_and_a_port_retry_is_waited_out(host: _Host) -> None:
    reached: list[bool] = [False]
    asker = Asker(host, None, rules=Rules(judge_after_s=5.0, asks_before_next=1, needs_ack=False), escalate=False, bounded=True)
    asker.start_command("Take off", lambda: host.autopilot._request("TAKEOFF", "take_off"), lambda: reached[0], "Take off")
    key = blackboard.command_key("take_off")
    host.run(asker, 4.0)
    host.ack(CommandState.RETRYING, "TEMPORARILY_REJECTED", key=key)  # the port asks again by itself: not judged meanwhile
    host.run(asker, 7.0)
    host.ack(CommandState.RETRYING, "TEMPORARILY_REJECTED", key=key)  # its last refusal, at 11 s
    host.run(asker, 1.0)
    host.ack(CommandState.ACCEPTED, "ACCEPTED", key=key)  # at 12 s; the take-off not confirmed yet
    host.run(asker, 3.9)
    assert asker.asking is not None and not asker.asking.judged  # 5 s from the port's last refusal: not yet
    host.run(asker, 0.2)
    assert asker.asking.judged and asker.asking.last == "accepted, not confirmed" and asker.exhausted
    assert times(host) == [(0.0, "TAKEOFF")]


def test_a_person_taking_the_vehicle_drops_the_ask_and_it_goes_again_at_once_when_they_let_go(host: _Host) -> None:
    asker = Asker(host, "rover")
    asker.start("HOLD", "ekf_loss")
    host.run(asker, 0.5)
    asker.stand_back()
    assert host.autopilot.cancelled == [1]
    host.clock.advance(0.1)
    asker.follow_up(host.clock.now())
    assert times(host) == [(0.0, "HOLD"), (0.6, "HOLD")]


def test_reaction_rules_are_the_documented_interval_and_count() -> None:
    assert REACTION.again_after_s == pytest.approx(ASK_AGAIN_S, abs=1e-5) and REACTION.asks_before_next == 3 and REACTION.needs_ack


def test_a_command_that_cannot_be_asked_asks_nothing(host: _Host) -> None:
    told = _Told()
    asker = Asker(host, None, rules=Rules(judge_after_s=5.0, asks_before_next=1, needs_ack=False), voice=told, escalate=False, bounded=True)
    asker.start_command("Transition to FW", lambda: None, lambda: False, "Transition to FW")  # no position to aim ahead from
    host.run(asker, 6.0)
    assert asker.asking is None and asker.state() is None and times(host) == [] and told.lines == []
