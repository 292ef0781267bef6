"""A person's intervention and a firmware failsafe's latch, end to end: a runtime over real UDP to the simulated ArduRover.

The ground station here acts on the simulated autopilot as a GCS's DO_SET_MODE does (``set_mode``
under the server's lock, on the vehicle's clock); the operator's resume goes through the control
socket (``executive ctl resume``'s path).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from executive import blackboard
from executive.assembly import build_runtime, control_socket
from executive.clock import ScaledClock
from executive.io.control import request
from executive.io.mavlink.dialect import MAVLinkMessage, mavlink
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.lifecycle import MissionStatus
from executive.sim import SimServer
from executive.sim.autopilot import ArduPilotSim
from executive.sim.faults import EkfDegradation, FaultInjector
from tests_support import LINE_EKF_READY_S, LINE_HOME, line_mission

HOME, EKF_READY_S = LINE_HOME, LINE_EKF_READY_S


class GroundStation(FaultInjector):
    """Faults, and at ``actions`` times (vehicle seconds after boot) a ground station's mode change."""

    def __init__(self, clock: ScaledClock, actions: dict[float, str] | None = None, faults: list[Any] | None = None) -> None:
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


def run(tmp_path: Path, station: GroundStation, clock: ScaledClock, operator: Callable[[Any, str], None] | None = None) -> tuple[Any, Record]:
    """The line mission over UDP against the simulated rover with ``station``; ``operator(runtime, socket)`` runs in a thread."""
    record = Record()
    sock = str(tmp_path / "ctl.sock")
    with SimServer("rover", clock=clock, home=(*HOME, 0.0), faults=station, ekf_ready_after_s=EKF_READY_S) as sim:
        link = PymavlinkLink(sim.url_for_client)
        try:
            runtime = build_runtime(line_mission("intervention line"), link, clock, plugs=[control_socket(sock)])
            send = link.send

            def spy(msg: MAVLinkMessage) -> None:
                if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                    record.modes_sent.append((runtime.ticks, runtime.commander.modes.decode(int(msg.param2))))
                if msg.get_type() == "STATUSTEXT":
                    record.texts.append(msg.text)
                send(msg)

            link.send = spy  # type: ignore[method-assign]
            bb = blackboard.reader(
                "intervention test", ["/vehicle/mode", "/mission/state", "/mission/reason", "/mission/leg_index", "/vehicle/statustext"]
            )
            tick = runtime.tick

            def observed_tick() -> Any:
                status = tick()
                record.ticks.append(tuple(bb.get(k) for k in ("/vehicle/mode", "/mission/state", "/mission/reason", "/mission/leg_index")))
                text = bb.get("/vehicle/statustext")
                if text is not None and (not record.received or record.received[-1] != text[1]):
                    record.received.append(text[1])
                return status

            runtime.tick = observed_tick  # type: ignore[method-assign]
            assert runtime.connect(10.0 * clock.speedup)
            thread = threading.Thread(target=operator, args=(runtime, sock), daemon=True) if operator else None
            if thread:
                thread.start()
            outcome = runtime.run()
            if thread:
                thread.join(5.0)
            runtime.close()
        finally:
            link.close()
    return outcome, record


def wait_for(predicate: Callable[[], bool], clock: ScaledClock, limit_s: float) -> None:
    deadline = clock.now() + limit_s
    while not predicate():
        assert clock.now() < deadline, "timed out (vehicle time)"
        clock.sleep_until(clock.now() + 0.1)


def test_a_ground_station_hold_pauses_the_mission_in_that_tick_and_ctl_resume_finishes_the_leg(tmp_path: Path) -> None:
    clock = ScaledClock(20.0)
    station = GroundStation(clock, actions={12.0: "HOLD"})  # mid leg 1 or 2 (QGroundControl's Pause on a rover)
    resumed: list[dict[str, Any]] = []

    def operator(runtime: Any, sock: str) -> None:
        wait_for(lambda: runtime.mission_state.status is MissionStatus.PAUSED, clock, 60.0)
        clock.sleep_until(clock.now() + 5.0)  # the person looks around for 5 s
        resumed.append(request(sock, "resume"))

    outcome, record = run(tmp_path, station, clock, operator)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    held = record.first(lambda t: t[0] == "HOLD", after=record.first(lambda t: t[0] == "GUIDED"))
    _, state, reason, leg = record.ticks[held]
    assert (state, reason) == ("PAUSED", "HOLD set by the ground station")  # in the tick the heartbeat showed it
    assert "mission PAUSED: HOLD set by the ground station" in record.texts
    back = record.first(lambda t: t[1] == "RUNNING", after=held)
    assert {t[3] for t in record.ticks[held:back]} == {leg}  # the leg kept
    assert [m for t, m in record.modes_sent if held <= t < back] == []  # hands off while paused: nothing commanded
    assert resumed and resumed[0]["ok"] and resumed[0]["state"] == "RUNNING"
    assert next(m for t, m in record.modes_sent if t >= back) == "GUIDED"  # the leg again, in its own mode


def test_the_ground_station_setting_the_legs_mode_again_resumes(tmp_path: Path) -> None:
    clock = ScaledClock(20.0)
    station = GroundStation(clock, actions={12.0: "HOLD", 18.0: "GUIDED"})
    outcome, record = run(tmp_path, station, clock)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    held = record.first(lambda t: t[1] == "PAUSED")
    back = record.first(lambda t: t[1] == "RUNNING", after=held)
    assert record.ticks[back][2] == f"resumed at leg {record.ticks[held][3] + 1}: GUIDED set again"
    assert [m for t, m in record.modes_sent if held <= t <= back] == []


def test_the_firmwares_ekf_failsafe_latch_is_waited_out_and_the_mission_completes(tmp_path: Path) -> None:
    """The simulated ArduRover latches its EKF failsafe (Rover/ekf_check.cpp), holds, and refuses GUIDED until it clears; the leg resumes."""
    clock = ScaledClock(20.0)
    station = GroundStation(clock, faults=[EkfDegradation(kind="ekf_degradation", at_s=14.0, for_s=6.0, variance=1.2, lose_position=True)])
    outcome, record = run(tmp_path, station, clock)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    # the firmware's latch engaged and cleared: our failsafe had held already, so it latched unannounced (failsafe_ekf_event
    # returns before its "EKF failsafe" in a mode that needs no position) and announced the clearing (failsafe_ekf_off_event)
    assert "EKF failsafe cleared" in record.received
    assert all(t[1] == "RUNNING" for t in record.ticks if t[1] != "COMPLETED")  # its HOLD paused nothing
    held = next(t for t, m in record.modes_sent if m == "HOLD")
    assert any(m == "GUIDED" for t, m in record.modes_sent if t > held)  # the leg again, in its own mode
