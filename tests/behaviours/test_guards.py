"""Each guard, tick by tick: the status it returns for the blackboard it sees, and why."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.behaviours import Armed, EkfOk, LinkAlive, ModeIs, RcNotTakingOver
from executive.state import EkfFlags, EkfStatus

READY = EkfFlags(831)  # what ArduRover reports once its EKF uses GPS
CONST_POS = EkfFlags.ATTITUDE | EkfFlags.VELOCITY_HORIZ | EkfFlags.CONST_POS_MODE


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


def test_guard_follows_the_blackboard_tick_by_tick(harness, vehicle):
    h = harness(LinkAlive())
    statuses = []
    for up in (False, True, True, False, True):
        vehicle.set(link__up=up)
        statuses.append(h.tick())
    assert statuses == [Status.FAILURE, Status.SUCCESS, Status.SUCCESS, Status.FAILURE, Status.SUCCESS]


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
