"""The autopilot's clock against ours: a simulator at another speed-up is said once, with both rates and the flag to use.

Issue 28: ``executive sim --speedup 20`` and ``executive run ... --mavlink`` without ``--speedup``
COMPLETED rover_square in 38 ticks (~0.5 Hz of vehicle time), silently, though SYSTEM_TIME and every
``time_boot_ms`` showed the vehicle's time running 20 times ours.
"""

from __future__ import annotations

import logging
import random
import re

import pytest

from executive.io.mavlink.vehicle_clock import VehicleClockWatch, speedup_flag
from executive.runtime.assembly import build_runtime
from executive.sim import make_autopilot
from executive.testing import FakeLink
from executive.testing.lockstep import Wire
from executive.world.clock import ManualClock, ScaledClock
from tests_support import LINE_HOME, line_mission

LOGGER = "executive.io.mavlink.vehicle_clock"


def warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == LOGGER]


def test_a_simulator_at_20x_behind_an_executive_at_1x_is_said_once_with_the_flag(caplog: pytest.LogCaptureFixture) -> None:
    """The runtime on an in-memory link; the simulated ArduRover's clock moves 2 s for each 0.1 s tick of ours."""
    caplog.set_level(logging.WARNING, logger=LOGGER)
    ours, theirs = ManualClock(100.0), ManualClock(0.0)
    autopilot = make_autopilot("rover", theirs, (*LINE_HOME, 0.0))
    link, wire = FakeLink(), Wire(1, 1)
    runtime = build_runtime(line_mission("fast sim"), link, ours)
    for _ in range(200):  # 20 s of ours, 400 s of the vehicle's
        ours.advance(0.1)
        theirs.advance(2.0)
        link.incoming.extend(wire.carry(autopilot.update()))
        runtime.tick()
    said = warnings(caplog)
    assert said == [
        "the autopilot's clock runs 20x real time and the executive's 1x (20 s of the vehicle's time per second of ours): "
        "the executive ticks and times out in its own clock; run it with --speedup 20 (the simulator's speed-up)"
    ]
    assert runtime.link.reader.clock_watch.ratio == pytest.approx(20.0, rel=0.01)


def feed(watch: VehicleClockWatch, clock: ManualClock, rate: float, seconds: float, jitter_s: float, rng: random.Random, boot: list[float]) -> None:
    """Our clock on ``seconds`` in ticks of 0.1 s; each tick the latest of ~4 messages a vehicle second, late by up to ``jitter_s``."""
    for _ in range(round(seconds / 0.1)):
        clock.advance(0.1)
        boot[0] += 0.1 * rate
        late = rng.uniform(0.0, jitter_s)  # the message left the vehicle this much (ours) before we handled it
        if rng.random() < 0.15:  # a burst: nothing this tick, all of it at the next
            continue
        watch.sample(round((boot[0] - late * rate) * 1000) / 1000, clock.now())


@pytest.mark.parametrize("seed", range(5))
def test_link_jitter_makes_no_warning_and_moves_the_measure_little(seed: int, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger=LOGGER)
    clock, rng, boot = ManualClock(0.0), random.Random(seed), [50.0]
    watch = VehicleClockWatch(clock)
    feed(watch, clock, 1.0, 300.0, 0.3, rng, boot)  # a radio link: up to 0.3 s late, bursts
    assert warnings(caplog) == []
    assert watch.ratio == pytest.approx(1.0, abs=0.15)


def test_warned_once_again_only_when_it_changes_a_lot_and_when_it_comes_back(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger=LOGGER)
    clock, rng, boot = ManualClock(0.0), random.Random(7), [0.0]
    watch = VehicleClockWatch(clock)
    feed(watch, clock, 8.0, 60.0, 0.05, rng, boot)  # a SITL at --speedup 8
    feed(watch, clock, 7.0, 60.0, 0.05, rng, boot)  # it cannot keep 8 on a busy machine: not news
    (first,) = warnings(caplog)
    assert re.match(r"the autopilot's clock runs (7\.9\d|8|8\.0\d)x real time and the executive's 1x \(", first), first
    assert first.endswith("run it with --speedup 8 (the simulator's speed-up)")
    feed(watch, clock, 2.5, 60.0, 0.05, rng, boot)  # restarted at 2.5
    feed(watch, clock, 1.0, 60.0, 0.05, rng, boot)  # and at real time
    said = warnings(caplog)
    assert len(said) == 3 and said[1].endswith("run it with --speedup 2.5 (the simulator's speed-up)"), said
    assert said[2].startswith("the autopilot's clock keeps to the executive's again (1")


def test_an_executive_at_20x_against_a_real_vehicle_is_told_to_drop_its_speedup(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger=LOGGER)
    ours = ScaledClock(20.0)  # only its speed-up is read: the times are fed by hand
    clock, boot = ManualClock(0.0), [1000.0]
    watch = VehicleClockWatch(ours)
    feed_on = VehicleClockWatch.sample
    for _ in range(800):  # 80 s of ours: 4 s of the vehicle's
        clock.advance(0.1)
        boot[0] += 0.1 / 20.0
        feed_on(watch, boot[0], clock.now())
    assert warnings(caplog)[0].startswith("the autopilot's clock runs 1x real time and the executive's 20x (0.05 s of the vehicle's time")
    assert warnings(caplog)[0].endswith("run it with --speedup 1 (a real vehicle: no --speedup)")


def test_a_reboot_starts_the_measure_again(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger=LOGGER)
    clock, watch = ManualClock(0.0), VehicleClockWatch(ManualClock())
    for boot in (500.0, 500.1, 500.2, 0.3, 0.4, 0.5):  # its clock went back: rebooted; a window over it would be a huge negative rate
        clock.advance(0.1)
        watch.sample(boot, clock.now())
    for i in range(60):
        clock.advance(0.1)
        watch.sample(0.6 + 0.1 * i, clock.now())
    assert warnings(caplog) == [] and watch.ratio == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("rate", "flag"), [(19.3, "--speedup 20"), (20.4, "--speedup 20"), (8.1, "--speedup 8"), (2.5, "--speedup 2.5"), (1.02, "--speedup 1")]
)
def test_the_flag_is_a_round_speedup_near_the_measured_rate(rate: float, flag: str) -> None:
    """A simulator asked for 20 measures 19.3 on a busy machine (seen against `executive sim --speedup 20`): the flag says 20."""
    assert speedup_flag(rate) == flag
