"""The runtime's make-safe (abort, Ctrl-C / SIGTERM, end of run) follows the failsafe reactions' rules (issue 25, 1).

The safe mode is asked again every 1.5 s of vehicle time until the autopilot accepts it and the heartbeat shows it; after 3 failed
asks, the next reaction of the firmware's table (ArduRover: HOLD, then a disarm). It is bounded: the table's chain at 3 asks 1.5 s
apart each (rover: HOLD, disarm: 9 s). Each step is a WARNING and a STATUSTEXT; the last lines say what it came to.
"""

from __future__ import annotations

import logging
from typing import Any

import py_trees
import pytest

from executive.cli.run import last_words
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import RuntimeOnLink
from executive.world.dialect import MAVLinkMessage, mavlink


def asked_when(r: RuntimeOnLink) -> list[tuple[float, tuple[Any, ...]]]:
    """Each command the autopilot receives from now on, with its vehicle time (seconds from now)."""
    start, seen = r.clock.now(), []
    answer = r.autopilot.on_command

    def on_command(msg: MAVLinkMessage) -> int | None:
        result = answer(msg)
        seen.append((round(r.clock.now() - start, 1), r.autopilot.commands[-1]))
        return result

    r.autopilot.on_command = on_command  # type: ignore[method-assign]
    return seen


def silent(r: RuntimeOnLink) -> None:
    """The autopilot hears the commands and never acks nor obeys them (its heartbeat still answers ours)."""

    def on_command(msg: MAVLinkMessage) -> int | None:
        kind = ("mode", r.autopilot.modes.decode(int(msg.param2))) if msg.command == mavlink.MAV_CMD_DO_SET_MODE else ("arm", msg.param1)
        r.autopilot.commands.append(kind)
        return None

    r.autopilot.on_command = on_command  # type: ignore[method-assign]


def said(caplog: pytest.LogCaptureFixture, level: int = logging.WARNING) -> list[str]:
    return [rec.getMessage() for rec in caplog.records if rec.name == "executive.runtime" and rec.levelno >= level]


def refusing_hold(square_mission: Mission, runtime_on_link) -> tuple[RuntimeOnLink, list[tuple[float, tuple[Any, ...]]]]:
    """A rover in GUIDED, armed, whose autopilot refuses HOLD (FAILED); what it is asked from now on."""
    r = runtime_on_link(square_mission)
    r.autopilot.beat()
    r.autopilot.refuse.add("HOLD")
    return r, asked_when(r)


def test_a_refused_safe_mode_is_asked_again_then_the_vehicle_is_disarmed(square_mission: Mission, runtime_on_link, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    r, asked = refusing_hold(square_mission, runtime_on_link)
    r.runtime.report()  # the load's STATUSTEXT goes out first
    r.texts()
    assert r.runtime.make_safe() is True
    assert asked == [(0.0, ("mode", "HOLD")), (1.5, ("mode", "HOLD")), (3.0, ("mode", "HOLD")), (4.5, ("arm", 0.0))]
    assert r.autopilot.armed is False
    assert said(caplog) == [
        "make safe: HOLD refused (FAILED) -> asked again every 1.5 s",
        "make safe: HOLD refused (FAILED) x3 after 3 asks -> disarm instead "
        "(ArduRover HOLD needs no position (Rover/mode.h); a disarm stops the motors (Rover/AP_Arming_Rover.cpp))",
        "make safe: the vehicle disarmed (accepted and seen; 1 ask, 0.8 s)",
    ]
    assert said(caplog, logging.INFO)[-1] == r.runtime.safe_report == "the vehicle made safe: HOLD refused (FAILED) x3, disarmed (confirmed)"
    assert r.texts() == [
        "make safe: HOLD refused (FAILED)",
        "make safe: HOLD refused (FAILED) x3 -> disarm",
        "make safe: disarmed, confirmed",
    ]


def test_a_safe_mode_never_answered_is_bounded_by_the_chain_and_reported_not_confirmed(square_mission: Mission, runtime_on_link, caplog) -> None:
    """Heartbeats come, acks never: HOLD x3, a disarm x3, 1.5 s apart; then it ends (9 s), saying the vehicle is not seen safe."""
    caplog.set_level(logging.INFO, logger="executive")
    r = runtime_on_link(square_mission)
    r.autopilot.beat()
    silent(r)
    asked = asked_when(r)
    start = r.clock.now()
    assert r.runtime.make_safe() is False
    assert asked == [(t, ("mode", "HOLD")) for t in (0.0, 1.5, 3.0)] + [(t, ("arm", 0.0)) for t in (4.5, 6.0, 7.5)]
    assert r.clock.now() - start == pytest.approx(9.0, abs=0.06)
    assert r.autopilot.mode == "GUIDED" and r.autopilot.armed
    assert said(caplog, logging.ERROR) == [r.runtime.safe_report]
    assert r.runtime.safe_report == "could not make the vehicle safe: HOLD not answered x3, disarm not answered x3"
    assert r.texts()[-1] == "could not make the vehicle safe"


def test_with_no_heartbeat_the_safe_mode_is_asked_until_the_bound_and_never_replaced(square_mission: Mission, runtime_on_link) -> None:
    """No heartbeat: nothing says the vehicle cannot take HOLD (it may hear us), so HOLD it stays, every 1.5 s, for the chain's 9 s."""
    r = runtime_on_link(square_mission)
    silent(r)
    r.autopilot.beat = lambda: None  # type: ignore[method-assign]
    asked = asked_when(r)
    start = r.clock.now()
    assert r.runtime.make_safe() is False
    assert asked == [(1.5 * n, ("mode", "HOLD")) for n in range(6)]
    assert r.clock.now() - start == pytest.approx(9.0, abs=0.06)
    assert r.runtime.safe_report == "could not make the vehicle safe: HOLD not answered x6 (no heartbeat: the link is down)"


def test_a_safe_mode_accepted_late_is_confirmed_when_the_ack_and_the_heartbeat_come(square_mission: Mission, runtime_on_link, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    r = runtime_on_link(square_mission)
    r.autopilot.beat()
    late: list[MAVLinkMessage] = []
    answer, beat = r.autopilot.on_command, r.autopilot.beat
    first = r.clock.now()

    def on_command(msg: MAVLinkMessage) -> int | None:
        late.append(msg)  # answered with the next heartbeat 2 s on
        return None

    def beat_late() -> None:
        if late and r.clock.now() - first >= 2.0:
            r.autopilot.acknowledge(mavlink.MAV_CMD_DO_SET_MODE, answer(late.pop()))
        beat()

    r.autopilot.on_command = on_command  # type: ignore[method-assign]
    r.autopilot.beat = beat_late  # type: ignore[method-assign]
    assert r.runtime.make_safe() is True
    assert r.autopilot.mode == "HOLD" and r.autopilot.armed  # never disarmed: HOLD came
    assert "make safe: HOLD no answer -> asked again every 1.5 s" in said(caplog)
    assert r.runtime.safe_report == "the vehicle made safe: HOLD (confirmed)"
    assert said(caplog, logging.INFO)[-1] == r.runtime.safe_report


def test_the_last_lines_say_what_making_the_vehicle_safe_came_to(square_mission: Mission, runtime_on_link) -> None:
    r = runtime_on_link(square_mission, beat=True)
    r.autopilot.refuse.add("HOLD")
    r.runtime.mission_state.start()
    r.runtime.request_stop("SIGINT")
    outcome = r.runtime.run(start=False)
    assert outcome.status is MissionStatus.ABORTED
    assert last_words(outcome, r.runtime.mission_state)[-2:] == [
        "the vehicle made safe: HOLD refused (FAILED) x3, disarmed (confirmed)",
        f"mission 'square' ABORTED: stopped: SIGINT ({outcome.ticks} ticks)",
    ]


def test_a_person_taking_the_vehicle_while_it_is_made_safe_is_left_alone(square_mission: Mission, runtime_on_link, caplog) -> None:
    """HOLD refused; meanwhile a ground station puts the vehicle in MANUAL: no more asks, no disarm, said so (once, a warning)."""
    caplog.set_level(logging.INFO, logger="executive")
    r, asked = refusing_hold(square_mission, runtime_on_link)
    beat = r.autopilot.beat

    def beat_manual() -> None:
        if r.autopilot.commands.count(("mode", "HOLD")) == 2:
            r.autopilot.mode = "MANUAL"
        beat()

    r.autopilot.beat = beat_manual  # type: ignore[method-assign]
    assert r.runtime.make_safe() is False
    assert [c for _, c in asked] == [("mode", "HOLD")] * 2 and r.autopilot.mode == "MANUAL" and r.autopilot.armed
    assert r.runtime.safe_report == (
        "not commanding HOLD: the vehicle is in MANUAL, set by the RC or a ground station while the executive made it safe: a person drives it"
    )
    assert said(caplog)[-2:] == ["make safe: HOLD refused (FAILED) -> asked again every 1.5 s", r.runtime.safe_report]


@pytest.mark.parametrize(("set_by", "commanded"), [("autopilot", True), ("others", False)])
def test_a_pilot_mode_the_autopilot_chose_itself_is_nobodys_and_is_made_safe(square_mission: Mission, runtime_on_link, set_by, commanded) -> None:
    """As the failsafes judge it: MANUAL set by the autopilot's own transition (executive.autopilot.mode_cause) is no person driving;
    MANUAL set by the RC or a ground station is, and is left alone."""
    r = runtime_on_link(square_mission)
    r.autopilot.mode = "MANUAL"
    r.autopilot.beat()
    r.runtime.link.reader.drain()
    blackboard = py_trees.blackboard.Client(name="test")
    blackboard.register_key("/vehicle/mode_set_by", access=py_trees.common.Access.WRITE)
    blackboard.set("/vehicle/mode_set_by", set_by)
    asked = asked_when(r)
    r.runtime.make_safe()
    assert (("mode", "HOLD") in [c for _, c in asked]) is commanded, (asked, r.runtime.safe_report)


def test_a_run_stopped_before_it_commanded_anything_leaves_the_vehicle_as_it_was(square_mission: Mission) -> None:
    """Stopped while its pre-flight waits for the EKF: only heartbeats, stream requests and parameter reads went out; nothing is commanded."""
    from executive.autopilot_link.link import NOTHING_TO_MAKE_SAFE
    from executive.testing import Lockstep
    from tests_support import acting

    received: list[MAVLinkMessage] = []
    with Lockstep(square_mission, ekf_ready_after_s=600.0) as sim:
        handle = sim.autopilot.handle
        sim.autopilot.handle = lambda msg: received.append(msg) or handle(msg)  # type: ignore[method-assign]
        assert sim.run(60, until=lambda: sim.clock.now() > 10.0) is None
        sim.runtime.request_stop("SIGTERM")
        outcome = sim.run_to_end(limit_s=30)
    assert outcome.status is MissionStatus.ABORTED and outcome.safe == NOTHING_TO_MAKE_SAFE
    assert last_words(outcome, sim.runtime.mission_state)[0] == NOTHING_TO_MAKE_SAFE
    assert acting(received) == [] and sim.autopilot.mode == "MANUAL" and not sim.autopilot.armed  # its boot mode, disarmed
