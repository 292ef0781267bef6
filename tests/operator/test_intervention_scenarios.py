"""A person's intervention and a firmware failsafe's latch, end to end: the runtime against the simulated ArduRover, in lock-step.

The ground station here acts on the simulated autopilot as a GCS's DO_SET_MODE does (``set_mode`` on
the vehicle's clock); the operator's resume is the request ``executive ctl resume`` makes (its
socket: tests/cli/test_ctl.py). Messages are packed and parsed as over a link (``as_bytes``).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import pytest

from executive.autopilot_link.link import NOTHING_TO_MAKE_SAFE
from executive.mission.lifecycle import MissionStatus
from executive.operator import Reply
from executive.runtime.loop import RunOutcome
from executive.sim.faults import EkfDegradation, Fault, FaultInjector
from executive.sim.firmware import FirmwareSim
from executive.testing import Lockstep
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from tests_support import line_mission


class GroundStation(FaultInjector):
    """Faults, and at ``actions`` times (vehicle seconds after boot) a ground station's mode change."""

    def __init__(self, clock: Clock, actions: dict[float, str] | None = None, faults: list[Fault] | None = None) -> None:
        super().__init__(faults or [], clock)
        self.actions = dict(actions or {})
        self.done: list[tuple[float, str]] = []

    def update(self, autopilot: FirmwareSim) -> None:
        super().update(autopilot)
        for at_s, mode in list(self.actions.items()):
            if self.elapsed_s >= at_s:
                del self.actions[at_s]
                assert autopilot.set_mode(autopilot.profile.modes[mode])
                self.done.append((self.elapsed_s, mode))


class Record:
    """Per tick: the mode the heartbeat showed, the mission's state and reason, the leg; and what the executive sent."""

    def __init__(self) -> None:
        self.ticks: list[tuple[str | None, str, str, int]] = []
        self.modes_sent: list[tuple[int, str]] = []
        self.texts: list[str] = []  # STATUSTEXT the executive sent
        self.received: list[str] = []  # STATUSTEXT the autopilot sent

    def first(self, predicate: Callable[[tuple[str | None, str, str, int]], bool], after: int = 0) -> int:
        return next(i for i, t in enumerate(self.ticks) if i >= after and predicate(t))


def run(
    lockstep: Callable[..., Lockstep],
    actions: dict[float, str] | None = None,
    faults: list[Fault] | None = None,
    operator: Callable[[Lockstep], object] | None = None,
) -> tuple[RunOutcome, Record]:
    """The line mission against the simulated rover with a ground station's ``actions`` and ``faults``; ``operator`` watches each step."""
    record = Record()
    sim = lockstep(line_mission("intervention line"), injector=lambda _, clock: GroundStation(clock, actions, faults), as_bytes=True)
    runtime = sim.runtime
    send = sim.link.send

    def spy(msg: MAVLinkMessage) -> None:
        if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            record.modes_sent.append((runtime.ticks, runtime.link.commander.modes.decode(int(msg.param2))))
        if msg.get_type() == "STATUSTEXT":
            record.texts.append(msg.text)
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    bb = blackboard.reader("intervention test", ["/vehicle/mode", "/mission/state", "/mission/reason", "/mission/leg_index", "/vehicle/statustext"])
    tick = runtime.tick

    def observed_tick() -> Any:
        status = tick()
        record.ticks.append(tuple(bb.get(k) for k in ("/vehicle/mode", "/mission/state", "/mission/reason", "/mission/leg_index")))
        text = bb.get("/vehicle/statustext")
        if text is not None and (not record.received or record.received[-1] != text[1]):
            record.received.append(text[1])
        return status

    runtime.tick = observed_tick  # type: ignore[method-assign]
    if operator is not None:
        sim.observers.append(operator)
    return sim.run_to_end(limit_s=600), record


def test_a_ground_station_hold_pauses_the_mission_in_that_tick_and_ctl_resume_finishes_the_leg(lockstep) -> None:
    paused_at: list[float] = []
    resumed: list[Reply] = []

    def operator(sim: Lockstep) -> None:
        if not paused_at and sim.status is MissionStatus.PAUSED:
            paused_at.append(sim.clock.now())
        elif paused_at and not resumed and sim.clock.now() >= paused_at[0] + 5.0:  # the person looks around for 5 s
            resumed.append(sim.runtime.operator.request("resume", source="ctl"))

    outcome, record = run(lockstep, actions={12.0: "HOLD"}, operator=operator)  # mid leg 1 or 2 (QGroundControl's Pause on a rover)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    held = record.first(lambda t: t[0] == "HOLD", after=record.first(lambda t: t[0] == "GUIDED"))
    _, state, reason, leg = record.ticks[held]
    assert (state, reason) == ("PAUSED", "HOLD set by the ground station")  # in the tick the heartbeat showed it
    assert "mission PAUSED: HOLD set by the ground station" in record.texts
    back = record.first(lambda t: t[1] == "RUNNING", after=held)
    assert {t[3] for t in record.ticks[held:back]} == {leg}  # the leg kept
    assert [m for t, m in record.modes_sent if held <= t < back] == []  # hands off while paused: nothing commanded
    assert resumed and resumed[0].ok and resumed[0].state == "RUNNING"
    assert next(m for t, m in record.modes_sent if t >= back) == "GUIDED"  # the leg again, in its own mode


def test_the_ground_station_setting_the_legs_mode_again_resumes(lockstep) -> None:
    outcome, record = run(lockstep, actions={12.0: "HOLD", 18.0: "GUIDED"})
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    held = record.first(lambda t: t[1] == "PAUSED")
    back = record.first(lambda t: t[1] == "RUNNING", after=held)
    assert record.ticks[back][2] == f"resumed at leg {record.ticks[held][3] + 1}: GUIDED set again"
    assert [m for t, m in record.modes_sent if held <= t <= back] == []


def test_the_firmwares_ekf_failsafe_latch_is_waited_out_and_the_mission_completes(lockstep) -> None:
    """The simulated ArduRover latches its EKF failsafe (Rover/ekf_check.cpp), holds, and refuses GUIDED until it clears; the leg resumes."""
    outcome, record = run(lockstep, faults=[EkfDegradation(kind="ekf_degradation", at_s=14.0, for_s=6.0, variance=1.2, lose_position=True)])
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    # the firmware's latch engaged and cleared: our failsafe had held already, so it latched unannounced (failsafe_ekf_event
    # returns before its "EKF failsafe" in a mode that needs no position) and announced the clearing (failsafe_ekf_off_event)
    assert "EKF failsafe cleared" in record.received
    assert all(t[1] == "RUNNING" for t in record.ticks if t[1] != "COMPLETED")  # its HOLD paused nothing
    held = next(t for t, m in record.modes_sent if m == "HOLD")
    assert any(m == "GUIDED" for t, m in record.modes_sent if t > held)  # the leg again, in its own mode


# -- who chose the mode the vehicle is left in (issue 28) --------------------------------------------------------------------------

BOOT_MODE = (
    "commanding HOLD: the vehicle is in MANUAL, the mode it was in when the executive found it "
    "(its boot mode, or one set before; nobody changed it while the executive watched)"
)


def _said(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "executive.runtime"]


def test_ctrl_c_while_waiting_for_the_ekf_after_boot_leaves_the_vehicle_as_it_was(lockstep, caplog) -> None:
    """Ctrl-C right after boot, the EKF not ready: nothing was armed or commanded, so nothing is (issue 34: it used to be put in HOLD)."""
    caplog.set_level(logging.INFO, logger="executive")
    sim = lockstep(line_mission("boot mode"), ekf_ready_after_s=40.0)
    sim.at(5.0, lambda s: s.runtime.request_stop("SIGINT"))
    outcome = sim.run_to_end(limit_s=60)
    assert (outcome.status, outcome.reason) == (MissionStatus.ABORTED, "stopped: SIGINT")
    assert sim.autopilot.mode == "MANUAL" and not sim.autopilot.armed  # its boot mode, as it was
    said = _said(caplog)
    assert NOTHING_TO_MAKE_SAFE in said and BOOT_MODE not in said
    assert not any("a person drives it" in text for text in said), said


def test_the_operators_silence_is_not_a_person_driving(lockstep, caplog) -> None:
    """Nobody arms the vehicle: the wait gives up and the mission aborts; nothing was commanded, so the vehicle is left in its boot MANUAL."""
    caplog.set_level(logging.INFO, logger="executive")
    mission = line_mission("nobody arms", auto_arm=False, limits={"acceptance_radius_m": 1.5, "recovery_timeout_s": 5.0})
    sim = lockstep(mission)
    outcome = sim.run_to_end(limit_s=120)
    assert outcome.status is MissionStatus.ABORTED and "Wait for the operator to arm" in outcome.reason, outcome.reason
    said = _said(caplog)
    assert NOTHING_TO_MAKE_SAFE in said and sim.autopilot.mode == "MANUAL"
    assert not any("a person drives it" in text for text in said), said


def test_a_mode_a_ground_station_set_while_we_watched_is_a_persons_and_kept(lockstep, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    sim = lockstep(line_mission("driver"), injector=lambda _, clock: GroundStation(clock, {12.0: "MANUAL"}))
    sim.at(20.0, lambda s: s.runtime.request_stop("SIGINT"))
    outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED
    assert sim.autopilot.mode == "MANUAL"
    assert "not commanding HOLD: the vehicle is in MANUAL, set by the RC or a ground station while the executive watched: a person drives it" in (
        _said(caplog)
    )
