"""Each guard, tick by tick: the status it returns for the blackboard it sees, and why."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.behaviours import Armed, DepthWithin, EkfOk, LinkAlive, ModeIs, RcNotTakingOver
from executive.mission.model import Range
from executive.world.state import EkfFlags, EkfStatus, GlobalPosition

READY = EkfFlags(831)  # what ArduRover reports once its EKF uses GPS
CONST_POS = EkfFlags.ATTITUDE | EkfFlags.VELOCITY_HORIZ | EkfFlags.CONST_POS_MODE


def position(depth_m: float) -> GlobalPosition:
    return GlobalPosition(44.0, 9.0, -depth_m, 0.0, 0.0, 0.0, 0.0, 0.0)


def ekf(flags: EkfFlags, velocity: float = 0.1, position: float = 0.1, compass: float = 0.1) -> EkfStatus:
    return EkfStatus(flags, velocity, position, 0.1, compass, 0.0, 0.0)


CASES = [
    # guard, blackboard facts, expected status, words in the feedback
    (LinkAlive, {"link__up": True}, Status.SUCCESS, "ok"),
    (LinkAlive, {"link__up": False}, Status.FAILURE, "no heartbeat"),
    (EkfOk, {}, Status.FAILURE, "no EKF status"),
    (EkfOk, {"vehicle__ekf": ekf(READY)}, Status.SUCCESS, "ok"),
    (EkfOk, {"vehicle__ekf": ekf(EkfFlags.ATTITUDE | EkfFlags.POS_HORIZ_REL)}, Status.SUCCESS, "ok"),
    (EkfOk, {"vehicle__ekf": ekf(CONST_POS)}, Status.FAILURE, "no position estimate (flags 0x83)"),
    (EkfOk, {"vehicle__ekf": ekf(READY | EkfFlags.CONST_POS_MODE)}, Status.FAILURE, "no position estimate"),
    (EkfOk, {"vehicle__ekf": ekf(READY, velocity=0.9, compass=0.9)}, Status.FAILURE, "variances over 0.8"),
    (EkfOk, {"vehicle__ekf": ekf(READY, compass=0.9)}, Status.SUCCESS, "ok"),  # one variance alone is not a failsafe
    # the autopilot's own EKF failsafe acted (its HOLD may come before the report that shows why): the EKF is not ok
    (EkfOk, {"vehicle__ekf": ekf(READY), "vehicle__ekf_failsafe": True}, Status.FAILURE, "the autopilot's EKF failsafe is on"),
    (Armed, {"vehicle__armed": True}, Status.SUCCESS, "ok"),
    (Armed, {"vehicle__armed": False}, Status.FAILURE, "disarmed"),
]


@pytest.mark.parametrize(("guard", "facts", "expected", "why"), CASES, ids=lambda v: getattr(v, "__name__", None))
def test_guard(harness, vehicle, guard, facts, expected, why):
    vehicle.set(**facts)
    node = guard()
    h = harness(node)
    assert h.tick() == expected
    assert why in node.feedback_message
    assert h.link.take() == []  # a guard never sends anything


def test_a_guard_never_passed_fails_and_passes_at_once(harness, vehicle):
    """Before the condition has held once there is nothing to hold: the raw verdict (pre-flight waits on it)."""
    h = harness(EkfOk())
    assert h.tick() == Status.FAILURE  # no EKF report yet
    vehicle.set(vehicle__ekf=ekf(READY))
    assert h.tick() == Status.SUCCESS


def test_a_guard_fails_at_once_and_passes_after_its_resume_time(harness, vehicle):
    """LinkAlive: the link timeout is its bad spell (it fails at once); back after 2 s of heartbeats, not before."""
    node = LinkAlive()
    h = harness(node)
    vehicle.set(link__up=True)
    assert h.tick() == Status.SUCCESS
    vehicle.set(link__up=False)
    assert h.tick() == Status.FAILURE
    vehicle.set(link__up=True)
    statuses = [h.tick(0.5) for _ in range(6)]  # the first tick that sees it back is 0 s, then 0.5 s ... 2.5 s
    assert statuses == [Status.FAILURE] * 4 + [Status.SUCCESS] * 2
    assert h.tick() == Status.SUCCESS


def test_a_bad_spell_resets_the_resume_time(harness, vehicle):
    """Heartbeats back for 1.5 s, lost for one tick, back again: 2 s more from the last return."""
    h = harness(LinkAlive())
    for up, dt, expected in [
        (True, 0.1, Status.SUCCESS),
        (False, 0.1, Status.FAILURE),
        (True, 0.1, Status.FAILURE),  # back at t0
        (True, 1.5, Status.FAILURE),
        (False, 0.1, Status.FAILURE),
        (True, 0.1, Status.FAILURE),  # back again at t1
        (True, 1.8, Status.FAILURE),
        (True, 0.2, Status.SUCCESS),  # t1 + 2 s
    ]:
        vehicle.set(link__up=up)
        assert h.tick(dt) == expected


def test_a_limit_guard_passes_a_short_bad_spell_with_a_note(harness, vehicle):
    """DepthWithin holds after 1 s outside: 0.5 s outside passes (the feedback says so), 1 s outside fails."""
    node = DepthWithin(Range(min=0.0, max=10.0))
    h = harness(node)
    vehicle.set(vehicle__position=position(depth_m=5.0))
    assert h.tick() == Status.SUCCESS
    vehicle.set(vehicle__position=position(depth_m=12.0))
    assert h.tick(0.1) == Status.SUCCESS  # bad since now
    assert h.tick(0.5) == Status.SUCCESS
    assert "not yet" in node.feedback_message and "depth 12.0 m" in node.feedback_message
    vehicle.set(vehicle__position=position(depth_m=5.0))  # the spell ends: it starts again from zero
    assert h.tick(0.1) == Status.SUCCESS
    vehicle.set(vehicle__position=position(depth_m=12.0))
    assert h.tick(0.1) == Status.SUCCESS
    assert h.tick(0.9) == Status.SUCCESS
    assert h.tick(0.1) == Status.FAILURE  # 1 s outside


def test_judging_twice_at_the_same_time_gives_the_same_verdict(harness, vehicle, clock):
    """The tree's sequence and the failsafe both judge a guard in one tick."""
    node = LinkAlive()
    harness(node)
    vehicle.set(link__up=True)
    assert node.judge() is None
    vehicle.set(link__up=False)
    assert node.judge() == node.judge() == "no heartbeat from the autopilot"
    vehicle.set(link__up=True)
    clock.advance(2.0)
    assert node.judge() == node.judge() is not None  # the resume time starts now
    clock.advance(2.0)
    assert node.judge() is None and node.judge() is None


@pytest.mark.parametrize(
    ("mode", "expected"),
    [("GUIDED", Status.SUCCESS), ("HOLD", Status.FAILURE), (None, Status.FAILURE)],
)
def test_mode_is(harness, vehicle, mode, expected):
    vehicle.set(vehicle__mode=mode)
    node = ModeIs("guided")
    assert harness(node).tick() == expected
    if expected == Status.FAILURE:
        assert f"mode is {mode}, not GUIDED" == node.feedback_message


@pytest.mark.parametrize(
    ("channels", "expected", "why"),
    [
        ((), Status.SUCCESS, "ok"),  # no RC report yet
        ((1500,) * 8, Status.SUCCESS, "ok"),
        ((1500,) * 5 + (1000, 1500, 1500), Status.SUCCESS, "ok"),
        ((1500,) * 5 + (1700, 1500, 1500), Status.SUCCESS, "ok"),  # at the threshold is not above it
        ((1500,) * 5 + (1900, 1500, 1500), Status.FAILURE, "RC channel 6 high (1900 µs)"),
        ((0,) * 8, Status.SUCCESS, "ok"),  # transmitter gone: not a take-over
        ((1500,) * 4, Status.SUCCESS, "ok"),  # fewer channels than the take-over channel
    ],
)
def test_rc_not_taking_over(harness, vehicle, channels, expected, why):
    vehicle.set(rc__channels=channels)
    node = RcNotTakingOver(channel=6, above_us=1700)
    assert harness(node).tick() == expected
    assert why in node.feedback_message
