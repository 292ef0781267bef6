"""Whose is the target the autopilot reports (executive.autopilot.target_watch): ours once reported, a person's after that, the mode unchanged."""

from __future__ import annotations

from executive.autopilot.target_watch import TargetWatch
from executive.io.mavlink.commander import Commander
from executive.testing import FakeLink
from executive.world import geo
from executive.world.clock import ManualClock
from executive.world.state import GlobalPosition, PositionTarget, TargetAsk
from executive.world.vehicles import PROFILES

OURS = (-35.3605570, 149.1679807)
HERE = (-35.3611875, 149.1654574)


def report(lat: float, lon: float, t: float = 0.0) -> PositionTarget:
    return PositionTarget(lat, lon, 624.0, t)


def at(lat: float, lon: float, speed_m_s: float = 0.0) -> GlobalPosition:
    return GlobalPosition(lat, lon, 40.0, speed_m_s, 0.0, 0.0, 90.0, 0.0)


ASK = TargetAsk(*OURS, "AUTO.LOITER", 0.0)


def test_a_report_of_our_point_is_ours_and_another_after_it_is_a_persons_said_once() -> None:
    watch = TargetWatch()
    assert watch.judge("AUTO.LOITER", report(*OURS), ASK, at(*HERE)) is None and watch.set_by == "us"
    there = geo.destination(*HERE, 180.0, 400.0)
    person = watch.judge("AUTO.LOITER", report(*there), ASK, at(*HERE))
    assert person is not None and watch.set_by == "others"
    assert person.what == f"sent it to {there[0]:.5f}, {there[1]:.5f}"
    assert watch.judge("AUTO.LOITER", report(*there), ASK, at(*HERE)) is None  # the same report: said once
    assert watch.judge("AUTO.LOITER", report(*there, t=0.2), ASK, at(*HERE)) is None  # a new report of it: said once too


def test_a_pause_is_a_point_within_reach_of_the_vehicle() -> None:
    """PX4's reposition to its position (a fixed wing: where it is; a multicopter: its stopping point, farther at speed)."""
    watch = TargetWatch()
    watch.judge("AUTO.LOITER", report(*OURS), ASK, None)
    ahead = geo.destination(*HERE, 90.0, 40.0)
    person = watch.judge("AUTO.LOITER", report(*ahead), ASK, at(*HERE, speed_m_s=17.0))
    assert person is not None and person.what == "held the vehicle (reposition to its position)"
    watch = TargetWatch()
    watch.judge("AUTO.LOITER", report(*OURS), ASK, None)
    person = watch.judge("AUTO.LOITER", report(*ahead), ASK, at(*HERE, speed_m_s=1.0))  # 40 m at 1 m/s is a go-to
    assert person is not None and person.what.startswith("sent it to")


def test_nothing_is_judged_before_the_autopilot_reported_our_point() -> None:
    """The report of the previous leg's target, still on its way after our new ask, is not a person's."""
    watch = TargetWatch()
    previous = geo.destination(*OURS, 270.0, 250.0)
    assert watch.judge("AUTO.LOITER", report(*previous), ASK, at(*HERE)) is None and watch.set_by is None
    assert watch.judge("AUTO.LOITER", report(*OURS, t=0.1), ASK, at(*HERE)) is None and watch.set_by == "us"


def test_a_mode_change_starts_again_the_new_modes_own_target_is_the_autopilots() -> None:
    watch = TargetWatch()
    watch.judge("GUIDED", report(*OURS), TargetAsk(*OURS, "GUIDED", 0.0), at(*HERE))
    assert watch.judge("HOLD", report(*HERE, t=0.1), TargetAsk(*OURS, "GUIDED", 0.0), at(*HERE)) is None
    assert watch.set_by is None
    # back in GUIDED (a person's HOLD undone by the person): the stop point GUIDED starts with is not judged either
    assert watch.judge("GUIDED", report(*HERE, t=0.2), TargetAsk(*OURS, "GUIDED", 0.0), at(*HERE)) is None


def test_a_local_frame_setpoint_or_no_ask_judges_nothing() -> None:
    watch = TargetWatch()
    watch.judge("GUIDED", report(*OURS), TargetAsk(*OURS, "GUIDED", 0.0), None)
    assert watch.judge("GUIDED", report(*HERE, t=0.1), TargetAsk(None, None, "GUIDED", 1.0), None) is None
    assert watch.judge("GUIDED", report(*OURS, t=0.2), None, None) is None and watch.set_by is None


def test_our_ask_of_another_mode_ends_our_point() -> None:
    """Real PX4: AUTO.RTL sets its own setpoint (the climb where it is) before the heartbeat shows AUTO.RTL."""
    clock = ManualClock()
    commander = Commander(FakeLink(), clock, PROFILES["vtol"])
    commander.note_mode_asked("AUTO.LOITER")
    commander.note_target_asked(*OURS)
    assert commander.target_asked == TargetAsk(*OURS, "AUTO.LOITER", 0.0)
    commander.note_mode_asked("AUTO.LOITER")  # the same mode again (a hold where it loiters): the point holds
    assert commander.target_asked is not None
    commander.note_mode_asked("AUTO.RTL")
    assert commander.target_asked is None
    watch = TargetWatch()
    watch.judge("AUTO.LOITER", report(*OURS), ASK, None)
    assert watch.judge("AUTO.LOITER", report(*HERE, t=0.1), commander.target_asked, at(*HERE)) is None


def test_a_setpoint_sent_again_is_the_same_ask_a_new_point_or_mode_a_new_one() -> None:
    clock = ManualClock()
    commander = Commander(FakeLink(), clock, PROFILES["rover"])
    commander.note_mode_asked("GUIDED")
    commander.goto(*OURS)
    first = commander.target_asked
    clock.advance(1.0)
    commander.goto(*OURS)
    assert commander.target_asked is first
    commander.goto(*HERE)
    assert commander.target_asked == TargetAsk(*HERE, "GUIDED", 1.0)
    commander.goto(*HERE, mode="OFFBOARD")
    assert commander.target_asked == TargetAsk(*HERE, "OFFBOARD", 1.0)


def test_a_new_ask_is_not_ours_until_reported_even_with_no_new_report() -> None:
    """GoTo sends a setpoint again while it is not reported: a new leg's first send lost must not pass for reported."""
    watch = TargetWatch()
    watch.judge("GUIDED", report(*OURS), TargetAsk(*OURS, "GUIDED", 0.0), None)
    assert watch.set_by == "us"
    next_leg = TargetAsk(*HERE, "GUIDED", 1.0)
    assert watch.judge("GUIDED", None, next_leg, None) is None and watch.set_by is None
