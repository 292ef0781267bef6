"""The loop says when it cannot keep up: late and skipped ticks, a rate-limited warning, the simulator's speed-up capped or refused."""

from __future__ import annotations

import gc
import logging
import sys
from collections.abc import Iterator

import py_trees
import pytest
from py_trees.common import Status

from executive.cli import main
from executive.operator.status import StatusSource
from executive.runtime.assembly import Wiring, build_runtime
from executive.runtime.pacing import MIN_SWITCH_INTERVAL_S, Behind, SpeedGovernor, TickPacer, caps_logged, keeping_time
from executive.runtime.services import FunctionService
from executive.testing import ObedientAutopilot
from executive.world.clock import ManualClock, ScaledClock


def slow_ticks(cost_s: float):
    """A plug whose reader takes ``cost_s`` of clock time each tick (a machine too slow for the rate)."""

    def plug(w: Wiring) -> None:
        w.readers.append(FunctionService("slow", lambda: w.clock.advance(cost_s)))  # type: ignore[attr-defined]

    return plug


def at_the_square(mission, link) -> None:
    """The autopilot's heartbeat and position, at the first waypoint (no tree runs before the vehicle's position is known)."""
    first = mission.waypoints[0]
    ObedientAutopilot(link, start=(first.lat, first.lon)).beat()


class TicksThenSucceeds(py_trees.behaviour.Behaviour):
    def __init__(self, ticks: int) -> None:
        super().__init__("counted")
        self.left = ticks

    def update(self) -> Status:
        self.left -= 1
        return Status.SUCCESS if self.left <= 0 else Status.RUNNING


def test_a_loop_on_time_has_no_late_tick(square_mission, link, clock):
    runtime = build_runtime(square_mission, link, clock, root=TicksThenSucceeds(120))
    at_the_square(square_mission, link)
    runtime.run()
    assert (runtime.pacer.ticks, runtime.pacer.late, runtime.pacer.skipped) == (120, 0, 0)
    assert StatusSource().snapshot()["late_ticks"] == 0


def test_slow_ticks_are_counted_reported_and_warned_about_once_a_minute(square_mission, link, clock, caplog):
    caplog.set_level(logging.WARNING, logger="executive")
    # each tick costs 0.25 s of clock time at 10 Hz: every tick after the first starts 0.15 s late or more, and ticks are skipped
    runtime = build_runtime(square_mission, link, clock, plugs=[slow_ticks(0.25)], root=TicksThenSucceeds(400))
    at_the_square(square_mission, link)
    start = clock.now()
    runtime.run()
    elapsed = clock.now() - start
    pacer = runtime.pacer
    assert pacer.ticks == 400
    assert pacer.late == 399
    assert pacer.skipped == 399  # 2 periods behind after each tick: one skipped each time
    assert StatusSource().snapshot()["late_ticks"] == 399
    warnings = [r.getMessage() for r in caplog.records if r.name == "executive.pacing"]
    # 100 s of clock time in 5 s windows, each behind (4 ticks a second of 10): one warning a minute, the others counted
    assert elapsed == pytest.approx(100.0, abs=0.5)
    assert len(warnings) == 2
    assert warnings[0].startswith("the loop cannot keep up: 4.0 of its 10 ticks per second of clock time")
    assert "(11 more such window(s) since the last warning)" in warnings[1]
    summary = [r.getMessage() for r in caplog.records if r.name == "executive.runtime"]
    assert summary == ["the loop ran behind its 10 Hz: 399 late ticks of 400 (worst 0.15 s late), 399 skipped"]


def test_a_tick_a_little_late_is_not_late():
    clock = ManualClock(0.0)
    pacer = TickPacer(clock, 0.1)
    pacer.tick_started()
    clock.sleep_until(pacer.next_due() + 0.04)  # woke 40 ms late: under half a period
    pacer.tick_started()
    clock.sleep_until(pacer.next_due() + 0.06)
    pacer.tick_started()
    assert (pacer.ticks, pacer.late, pacer.skipped) == (3, 1, 0)


def test_the_listeners_hear_of_each_window_behind_with_how_many_in_a_row():
    clock = ManualClock(0.0)
    pacer = TickPacer(clock, 0.1, window_s=1.0)
    heard: list[Behind] = []
    pacer.listeners.append(heard.append)
    # on time 2 s, 0.25 s a tick for 4 s, on time 3 s, 0.25 s a tick for 3 s
    for cost in [0.0] * 20 + [0.25] * 16 + [0.0] * 30 + [0.25] * 12:
        pacer.tick_started()
        clock.advance(cost)
        clock.sleep_until(pacer.next_due())
    assert [b.in_a_row for b in heard] == [1, 2, 3, 4, 5, 1, 2]  # the windows on time in between start the count again
    assert [round(b.achieved_hz, 6) for b in heard[1:4]] == [4.0, 4.0, 4.0]  # the windows wholly slow: a tick every 0.25 s
    assert all(b.achieved_hz < 9.0 for b in heard)


def test_the_governor_caps_the_speedup_after_two_windows_behind_and_never_raises_it(caplog):
    caplog.set_level(logging.WARNING, logger="executive.pacing")
    clock = ScaledClock(100.0)
    governor = SpeedGovernor(clock)
    governor(Behind(5.0, 10.0, 10, 10, in_a_row=1))
    assert clock.speedup == 100.0  # one window may be a start-up hiccup
    before = clock.now()
    governor(Behind(5.0, 10.0, 10, 10, in_a_row=2))
    assert clock.speedup == pytest.approx(45.0)  # 100 x 5/10 x 0.9
    assert clock.now() >= before  # the time line goes on, slower
    governor(Behind(8.5, 10.0, 1, 0, in_a_row=3))
    assert clock.speedup == pytest.approx(45.0 * 0.85 * 0.9)
    governor(Behind(8.9, 10.0, 0, 0, in_a_row=4))
    governor(Behind(0.1, 10.0, 0, 0, in_a_row=5))
    assert clock.speedup >= 1.0  # never slower than real time
    assert len(governor.caps) == 4
    assert caps_logged(caplog.text) == [round(c, 1) for c in governor.caps]  # what tools read back from the log


def test_a_speedup_the_executive_cannot_follow_is_refused(minimal_mission, capsys):
    assert main(["run", str(minimal_mission), "--speedup", "1000", "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "--speedup 1000: the executive cannot follow it" in err
    assert "(--speedup below 200 at --rate 10)" in err  # 200 itself is refused: README
    assert main(["run", str(minimal_mission), "--speedup", "200", "--rate", "20", "--socket", "none"]) == 2
    assert "(--speedup below 100 at --rate 20)" in capsys.readouterr().err


@pytest.fixture
def switch_interval():
    before = sys.getswitchinterval()
    yield before
    sys.setswitchinterval(before)


def test_while_the_loop_runs_other_threads_hand_it_the_interpreter_within_a_tenth_of_its_margin(switch_interval):
    # 10 Hz at --speedup 20: a tick may start 50 ms of vehicle time late, 2.5 ms of wall time; CPython's default 5 ms is twice that
    margin_wall_s = TickPacer(ManualClock(), 0.1).late_after_s / 20.0
    with keeping_time(margin_wall_s) as interval:
        assert interval == pytest.approx(0.00025)
        assert sys.getswitchinterval() == pytest.approx(0.00025)
    assert sys.getswitchinterval() == switch_interval  # restored after the run


def test_the_interval_is_never_lengthened_nor_cut_below_its_floor(switch_interval):
    with keeping_time(1.0) as interval:  # real time on a slow loop: a margin far above the default
        assert interval == switch_interval
    with keeping_time(0.0001):
        assert sys.getswitchinterval() == pytest.approx(MIN_SWITCH_INTERVAL_S)


@pytest.fixture
def nothing_frozen() -> Iterator[None]:
    """The collector as a process that froze nothing finds it (the suite freezes what its collection made: tests/conftest.py)."""
    gc.unfreeze()
    yield
    gc.collect()
    gc.freeze()


def test_start_ups_objects_are_frozen_out_of_the_collectors_passes_while_the_loop_runs(switch_interval, nothing_frozen):
    kept = [[i] for i in range(1000)]
    with keeping_time(0.0025):
        assert gc.get_freeze_count() >= len(kept)
    assert gc.get_freeze_count() == 0  # collectable again after it


def test_what_was_frozen_before_the_loop_stays_frozen_after_it(switch_interval):
    gc.freeze()  # as filterpy's import in the background does (sensing/heading.py)
    frozen = gc.get_freeze_count()
    with keeping_time(0.0025):
        pass
    assert frozen > 0 and gc.get_freeze_count() >= frozen  # CPython unfreezes all or nothing: nothing
