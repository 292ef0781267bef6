"""A person's intervention and a firmware failsafe's latch, end to end: the runtime against the simulated ArduRover, in lock-step.

The ground station here acts on the simulated autopilot as a GCS's DO_SET_MODE does (``set_mode`` on
the vehicle's clock); the operator's resume is the request ``executive ctl resume`` makes (its
socket: tests/cli/test_ctl.py). Messages are packed and parsed as over a link (``as_bytes``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from executive import blackboard
from executive.clock import Clock
from executive.io.mavlink.dialect import MAVLinkMessage, mavlink
from executive.mission.lifecycle import MissionStatus
from executive.operator import Reply
from executive.runtime import Outcome
from executive.sim.autopilot import ArduPilotSim
from executive.sim.faults import EkfDegradation, Fault, FaultInjector
from executive.testing import Lockstep
from tests_support import line_mission


class GroundStation(FaultInjector):
    """Faults, and at ``actions`` times (vehicle seconds after boot) a ground station's mode change."""

    def __init__(self, clock: Clock, actions: dict[float, str] | None = None, faults: list[Fault] | None = None) -> None:
        super().__init__(faults or [], clock)
        self.actions = dict(actions or {})
        self.done: list[tuple[float, str]] = []

    def update(self, autopilot: ArduPilotSim) -> None:
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
) -> tuple[Outcome, Record]:
    """The line mission against the simulated rover with a ground station's ``actions`` and ``faults``; ``operator`` watches each step."""
    record = Record()
    sim = lockstep(line_mission("intervention line"), injector=lambda _, clock: GroundStation(clock, actions, faults), as_bytes=True)
    runtime = sim.runtime
    send = sim.link.send

    def spy(msg: MAVLinkMessage) -> None:
        if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            record.modes_sent.append((runtime.ticks, runtime.commander.modes.decode(int(msg.param2))))
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
