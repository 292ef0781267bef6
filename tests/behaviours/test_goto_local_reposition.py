"""GoToLocal by DO_REPOSITION (ArduPlane): the ENU point goes to NED, then to a latitude and longitude from home; tick by tick."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from py_trees.common import Status

from executive.behaviours import GoToLocal
from executive.testing import Harness
from executive.world.dialect import mavlink
from executive.world.frames import Enu, global_to_local, local_to_global
from executive.world.state import GlobalPosition, HomePosition

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
M = mavlink
HOME = (-35.363261, 149.165230)
TARGET = Enu(east=30.0, north=20.0, up=25.0)


def pos(north: float = 0.0, east: float = 0.0, alt: float = 0.0) -> GlobalPosition:
    return GlobalPosition(*local_to_global(*HOME, north, east), alt, 0.0, 0.0, 0.0, 0.0, 0.0)


def repositions(h) -> list[tuple[float, float, float, float]]:
    """Each DO_REPOSITION sent: metres north and east of home (0.01 m), altitude, and the change-mode flag."""
    out = []
    for sent in h.link.take("COMMAND_INT"):
        assert (sent.command, sent.frame) == (M.MAV_CMD_DO_REPOSITION, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        north, east = global_to_local(*HOME, sent.x / 1e7, sent.y / 1e7)
        out.append((round(north, 2), round(east, 2), sent.z, sent.param2))
    return out


@pytest.fixture
def home(vehicle) -> None:
    vehicle.set(vehicle__home=HomePosition(*HOME, 584.0, 0.0), vehicle__position=pos(alt=30.0))


def test_the_enu_point_goes_as_a_reposition_north_east_from_home_at_up_metres(harness, home) -> None:
    h = harness(GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=60.0, method="reposition"))
    assert h.tick() == R
    assert repositions(h) == [(20.0, 30.0, 25.0, M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)]  # ENU (E30, N20, U25) = NED (N20, E30, D-25)
    assert h.link.take("SET_POSITION_TARGET_LOCAL_NED") == []  # ArduPlane would take its z alone


def test_an_accepted_reposition_is_not_sent_again(harness, home) -> None:
    h = harness(GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=60.0, method="reposition"))
    h.tick()
    assert len(repositions(h)) == 1
    h.ack(M.MAV_CMD_DO_REPOSITION)
    assert [h.tick(0.5) for _ in range(10)] == [R] * 10
    assert repositions(h) == []  # the autopilot has the target


def answered_for_4_s(h: Harness, answer: Callable[[int], int]) -> tuple[list[Status], list[int]]:
    """Eight ticks of 0.5 s, each reposition sent answered by ``answer(how many asked so far)``: the statuses, the ticks it was sent on."""
    statuses: list[Status] = []
    sent_at: list[int] = []
    for i in range(8):
        statuses.append(h.tick(0.5))
        if repositions(h):
            sent_at.append(i)
            h.ack(M.MAV_CMD_DO_REPOSITION, answer(len(sent_at)))
    return statuses, sent_at


@pytest.mark.parametrize(("result", "why"), [(M.MAV_RESULT_FAILED, "refused: FAILED"), (M.MAV_RESULT_DENIED, "refused: DENIED")])
def test_a_refused_reposition_is_sent_again_each_second_and_named_when_it_times_out(harness, home, result: int, why: str) -> None:
    node = GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=3.0, method="reposition")
    statuses, sent_at = answered_for_4_s(harness(node), lambda _asked: result)
    assert statuses == [R] * 7 + [F]
    assert sent_at == [0, 2, 4, 6]
    assert node.feedback_message == f"timed out after 3 s: 36.4 m (DO_REPOSITION {why})"


def test_unanswered_is_left_to_the_commander_then_asked_again(harness, home) -> None:
    h = harness(GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=60.0, method="reposition"))
    sent_at = []
    for tick in range(1, 61):  # 0.125 s ticks, 7.5 s, never an answer
        h.tick(0.125)
        if repositions(h):
            sent_at.append(tick)
    # the commander resends on ticks 1, 13, 25, 37 (1.5 s ack time-out) and gives up on 49; GoToLocal asks again on 50
    assert sent_at == [1, 13, 25, 37, 50]


def test_refused_then_accepted_is_asked_no_more_and_not_named_at_the_timeout(harness, home) -> None:
    node = GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=3.0, method="reposition")
    statuses, sent_at = answered_for_4_s(harness(node), lambda asked: M.MAV_RESULT_FAILED if asked == 1 else M.MAV_RESULT_ACCEPTED)
    assert statuses == [R] * 7 + [F]
    assert sent_at == [0, 2]
    assert node.feedback_message == "timed out after 3 s: 36.4 m"


def test_nothing_is_sent_before_home_is_known(harness, vehicle) -> None:
    vehicle.set(vehicle__position=pos(alt=30.0))
    node = GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=60.0, method="reposition")
    h = harness(node)
    assert [h.tick() for _ in range(5)] == [R] * 5
    assert repositions(h) == [] and node.feedback_message == "no position or home"
    vehicle.set(vehicle__home=HomePosition(*HOME, 584.0, 0.0))
    assert h.tick() == R
    assert repositions(h) == [(20.0, 30.0, 25.0, M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)]


def test_reached_within_the_acceptance_radius_in_3d(harness, home, vehicle) -> None:
    h = harness(GoToLocal(TARGET, acceptance_radius_m=2.0, timeout_s=60.0, method="reposition"))
    statuses = []
    for north, east, alt in [(20.0, 30.0, 22.0), (20.5, 30.5, 24.0)]:  # over it but 3 m low; then 1.2 m off
        vehicle.set(vehicle__position=pos(north, east, alt))
        statuses.append(h.tick())
    assert statuses == [R, S]


def test_an_unknown_method_is_refused() -> None:
    with pytest.raises(ValueError, match="setpoint or reposition"):
        GoToLocal(TARGET, 2.0, 60.0, method="teleport")  # type: ignore[arg-type]
