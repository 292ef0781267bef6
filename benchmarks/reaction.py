"""Reaction latency: from an EKF_STATUS_REPORT that fails the EKF guard leaving the vehicle to the safe-mode command leaving the executive.

Real time on a real clock: the built-in simulated rover serves a loopback UDP link from its thread, the
runtime ticks at 10 Hz in this one. While the rover drives a leg, its EKF loses its position (the
flags ArduPilot reports in constant-position mode, as the ``ekf_degradation`` fault makes them);
the autopilot reports it at once (at a random moment against the executive's ticks) and then in its
stream. The first report saying so is timed as it goes onto the socket, the DO_SET_MODE HOLD as the
executive hands it to its link. Then the EKF recovers, the leg resumes, and it happens again.
"""

from __future__ import annotations

import random
import threading
import time

from benchmarks.common import Row, median, offset, rover_mission
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.lifecycle import MissionStatus
from executive.runtime.assembly import build_runtime
from executive.runtime.loop import Runtime
from executive.sim import SimServer
from executive.sim.ardupilot.base import EKF_FLAGS_READY
from executive.world.clock import ScaledClock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.vehicles import PROFILES

RATE_HZ = 10.0
SLACK_S = 0.010
#: EKF_STATUS_REPORT flags with the horizontal position lost (constant-position mode), as the ekf_degradation fault sends them.
LOST_FLAGS = (EKF_FLAGS_READY & ~mavlink.EKF_POS_HORIZ_ABS) | mavlink.EKF_CONST_POS_MODE


class _Probe:
    """Timestamps (perf_counter) of the breaking report leaving the vehicle and of the safe command leaving the executive."""

    def __init__(self, hold_mode: int) -> None:
        self.hold_mode = hold_mode
        self.broken = False
        self.bad_sent: float | None = None
        self.safe_sent: float | None = None
        self.tick_starts: list[float] = []

    def vehicle_sent(self, msg: MAVLinkMessage) -> None:
        if self.broken and self.bad_sent is None and msg.get_type() == "EKF_STATUS_REPORT" and msg.flags == LOST_FLAGS:
            self.bad_sent = time.perf_counter()

    def executive_sent(self, msg: MAVLinkMessage) -> None:
        if (
            self.bad_sent is not None
            and self.safe_sent is None
            and msg.get_type() == "COMMAND_LONG"
            and msg.command == mavlink.MAV_CMD_DO_SET_MODE
            and int(msg.param2) == self.hold_mode
        ):
            self.safe_sent = time.perf_counter()


def _instrument(sim: SimServer, link: PymavlinkLink, runtime: Runtime, probe: _Probe) -> None:
    """Break the EKF on demand and time both ends (wrapping the sim's report builder and both links' send)."""
    ap = sim.autopilot
    build = ap._builders[mavlink.MAVLINK_MSG_ID_EKF_STATUS_REPORT]

    def ekf_report() -> MAVLinkMessage | None:
        msg = build()
        if probe.broken and msg is not None:
            msg.flags = LOST_FLAGS
        return msg

    ap._builders[mavlink.MAVLINK_MSG_ID_EKF_STATUS_REPORT] = ekf_report
    mav = sim._conn.mav
    mav_send = mav.send

    def vehicle_send(msg: MAVLinkMessage, *args: object, **kwargs: object) -> None:
        mav_send(msg, *args, **kwargs)
        probe.vehicle_sent(msg)

    mav.send = vehicle_send  # type: ignore[method-assign]
    link_send = link.send

    def executive_send(msg: MAVLinkMessage) -> None:
        link_send(msg)
        probe.executive_sent(msg)

    link.send = executive_send  # type: ignore[method-assign]  # the commander holds this link: it sends through the wrapper
    tick = runtime.tick

    def timed_tick():  # type: ignore[no-untyped-def]
        probe.tick_starts.append(time.perf_counter())
        return tick()

    runtime.tick = timed_tick  # type: ignore[method-assign]


def run(trials: int = 8, seed: int = 1, settle_s: float = 3.0, speedup: float = 1.0) -> list[Row]:
    """``trials`` guard failures during a leg (the first after ``settle_s`` of driving); median and worst latency in ms and in ticks.

    ``speedup``: the vehicle's clock against the wall's (the figure is for real time, 1; a smoke test may run faster).
    """
    rng = random.Random(seed)
    clock = ScaledClock(speedup)
    far = offset(-35.363261, 149.165230, 1000.0, 0.0)
    mission = rover_mission([far], ekf_ready_after_s=1.0)
    latencies: list[float] = []
    ticks: list[int] = []
    with SimServer("rover", clock=clock, home=(-35.363261, 149.165230, 0.0), ekf_ready_after_s=1.0) as sim:
        link = PymavlinkLink(sim.url_for_client)
        try:
            runtime = build_runtime(mission, link, clock, rate_hz=RATE_HZ)
            probe = _Probe(PROFILES[runtime.mission.vehicle].modes[PROFILES[runtime.mission.vehicle].safe_mode])
            _instrument(sim, link, runtime, probe)
            if not runtime.link.connect(10.0 * speedup):
                raise RuntimeError("no heartbeat from the simulated rover")
            runtime.mission_state.start()
            period = 1.0 / RATE_HZ
            next_tick = clock.now()
            state = "drive"  # drive -> broken -> recovering -> drive ...
            settle_until = clock.now() + settle_s + rng.random()
            deadline = clock.now() + 30.0 + 4.0 * trials
            while len(latencies) < trials:
                if clock.now() > deadline:
                    raise RuntimeError(f"only {len(latencies)} of {trials} reactions within the time limit")
                runtime.tick()
                if runtime.mission_state.status is not MissionStatus.RUNNING:
                    raise RuntimeError(f"mission {runtime.mission_state.status}: {runtime.mission_state.reason}")
                driving = runtime.link.get("/vehicle/mode") == "GUIDED" and runtime.mission_state.legs.leg_index == 0 and runtime.tree is not None
                if state == "drive" and driving and clock.now() >= settle_until:
                    threading.Timer(rng.random() * period / speedup, _break, (sim, probe)).start()  # a wall-clock timer
                    state = "broken"
                elif state == "broken" and probe.safe_sent is not None:
                    assert probe.bad_sent is not None
                    latencies.append(probe.safe_sent - probe.bad_sent)
                    ticks.append(sum(probe.bad_sent < t <= probe.safe_sent for t in probe.tick_starts))
                    with sim.lock:
                        probe.broken = False
                        sim.autopilot.ekf_position_lost = False
                    probe.bad_sent = probe.safe_sent = None
                    probe.tick_starts.clear()
                    state = "recovering"
                elif state == "recovering" and driving and _guards_pass(runtime):
                    settle_until = clock.now() + 0.3 + rng.random()  # a random phase against the ticks and the vehicle's streams
                    state = "drive"
                next_tick += period
                clock.sleep_until(next_tick)
        finally:
            link.close()
    worst = max(latencies)
    limit = period + SLACK_S
    return [
        Row(
            "reaction",
            "reaction, guard-breaking input -> safe command",
            round(worst * 1e3, 1),
            "ms worst",
            f"<= 1 tick + {SLACK_S * 1e3:g} ms ({limit * 1e3:g} ms)",
            worst <= limit,
            f"median {median(latencies) * 1e3:.1f} ms over {len(latencies)}; ticks {min(ticks)}-{max(ticks)} "
            f"(10 Hz, {'real time' if speedup == 1.0 else f'{speedup:g}x real time'}, UDP loopback)",
            {"latencies_ms": [round(x * 1e3, 2) for x in latencies], "ticks": ticks},
        )
    ]


def _break(sim: SimServer, probe: _Probe) -> None:
    """The EKF loses its position; the autopilot reports it at its next step (within ``sim.period_s``)."""
    with sim.lock:
        probe.broken = True
        sim.autopilot.ekf_position_lost = True
        sim.autopilot._emit(sim.autopilot._builders[mavlink.MAVLINK_MSG_ID_EKF_STATUS_REPORT]())


def _guards_pass(runtime: Runtime) -> bool:
    """The route runs again: the link is up and the tree is back at the go-to (every guard passed at the last tick)."""
    tip = runtime.tree.root.tip() if runtime.tree is not None else None
    return bool(runtime.link.get("/link/up")) and tip is not None and tip.name == "Go to waypoint"
