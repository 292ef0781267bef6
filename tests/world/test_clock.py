"""Clocks: the tick clock holds one time per tick."""

from __future__ import annotations

from executive.world.clock import ManualClock, TickClock


def test_a_tick_clock_stands_still_between_latches():
    clock = ManualClock(start=10.0)
    tick = TickClock(clock)
    clock.advance(0.3)
    assert tick.now() == 10.0
    assert tick.latch() == 10.3
    clock.advance(0.3)
    assert tick.now() == 10.3


def test_a_tick_clock_that_waits_reads_the_time_it_woke_at():
    clock = ManualClock(start=0.0)
    tick = TickClock(clock)
    tick.sleep_until(2.5)
    assert (clock.now(), tick.now()) == (2.5, 2.5)
