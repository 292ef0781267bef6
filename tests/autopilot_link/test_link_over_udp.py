"""The executive's link against the simulated ArduPilot over real UDP: streams, reboots, link loss."""

from __future__ import annotations

import py_trees
import pytest

from executive.io.mavlink.link import PymavlinkLink
from executive.runtime.assembly import build_runtime
from executive.runtime.loop import Runtime
from executive.sim import SimServer
from executive.testing.lockstep import LockstepClock
from executive.world.clock import ManualClock

HOME = (-35.363261, 149.165230, 0.0)


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


def lockstep_over_udp(sims: list[SimServer]) -> LockstepClock:
    """The kit's lock-step clock over real UDP: vehicle time moves only when the executive waits, and each step moves
    the simulated vehicles ``sims`` (their serving threads not started), so a fault lasts the same ticks on any machine."""

    def step_to(t: float) -> None:
        ManualClock.sleep_until(clock, t)
        for sim in sims:
            sim.step()

    clock = LockstepClock(step_to)
    return clock


def tick_until(runtime: Runtime, condition, max_ticks: int = 400) -> int:
    for n in range(max_ticks):
        runtime.tick()
        if condition():
            return n
        runtime.clock.sleep_until(runtime.clock.now() + runtime.period_s)
    pytest.fail("condition never met")


@pytest.fixture
def idle_runtime(square_mission):
    """A runtime whose tree never finishes, so the link can be watched on its own."""

    links: list[PymavlinkLink] = []

    def make(url: str, clock: ManualClock) -> Runtime:
        links.append(PymavlinkLink(url))
        return build_runtime(square_mission, links[-1], clock, root=py_trees.behaviours.Running("idle"))

    yield make
    for link in links:
        link.close()


def test_streams_are_set_up_and_set_up_again_after_an_autopilot_reboot(idle_runtime):
    sims: list[SimServer] = []
    clock = lockstep_over_udp(sims)
    first = SimServer("rover", clock=clock, home=HOME)
    sims.append(first)
    port = first.port
    runtime = idle_runtime(first.url_for_client, clock)
    try:
        assert runtime.link.connect(200.0)
        tick_until(runtime, lambda: runtime.link.streams.done)
        assert not runtime.link.streams.refused
        requested = bb("/command/message_rate").ticket
        first.stop()  # the autopilot reboots: a new one on the same port, its boot clock from zero
        second = SimServer("rover", url=f"udpin:127.0.0.1:{port}", clock=clock, home=HOME)
        sims[:] = [second]
        try:
            tick_until(runtime, lambda: bb("/link/reboots") >= 1)
            tick_until(
                runtime,
                lambda: runtime.link.streams.done and bb("/command/message_rate").ticket >= requested + len(runtime.link.streams.rates),
            )
            assert bb("/link/up")
        finally:
            second.stop()
    finally:
        first.stop()


def test_link_loss_is_seen_and_recovery_re_requests_streams(idle_runtime, tmp_path):
    from executive.sim.faults import FaultInjector, load_faults

    faults = tmp_path / "loss.yaml"
    faults.write_text("version: 1\nfaults:\n  - {kind: link_loss, at_s: 10, for_s: 6}\n")
    sims: list[SimServer] = []
    clock = lockstep_over_udp(sims)
    sim = SimServer("rover", clock=clock, home=HOME, faults=FaultInjector(load_faults(faults), clock))
    sims.append(sim)
    runtime = idle_runtime(sim.url_for_client, clock)
    try:
        assert runtime.link.connect(200.0)
        tick_until(runtime, lambda: runtime.link.streams.done)
        requested = bb("/command/message_rate").ticket
        tick_until(runtime, lambda: not bb("/link/up"))
        assert bb("/link/heartbeat_age_s") > runtime.link.reader.link_timeout_s
        tick_until(runtime, lambda: bb("/link/up"))
        tick_until(runtime, lambda: runtime.link.streams.done and bb("/command/message_rate").ticket > requested)
    finally:
        sim.stop()
