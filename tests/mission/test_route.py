"""Route operations (pure) and the mission state keeping the route an operator edits."""

from __future__ import annotations

import py_trees
import pytest

from executive.mission.events import RouteChanged
from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.mission.model import Mission, Waypoint
from executive.mission.route import Route, RouteError, add_at_end, clear, current_index, remove, remove_current

A, B, C, D = (Waypoint(lat=-35.0 - i * 1e-4, lon=149.0) for i in range(4))
S = MissionStatus


def test_add_at_end_keeps_the_current_waypoint_and_leaves_the_argument_alone() -> None:
    route = Route((A, B), 1)
    assert add_at_end(route, C) == Route((A, B, C), 1)
    assert route == Route((A, B), 1)
    assert add_at_end(Route((A,), 1), B) == Route((A, B), 1)  # a finished route gets a leg to drive again


@pytest.mark.parametrize(
    ("route", "index", "expected"),
    [
        (Route((A, B, C), 1), 0, Route((B, C), 0)),  # before the current one: still heading for B
        (Route((A, B, C), 1), 1, Route((A, C), 1)),  # the current one: heading for the next, C
        (Route((A, B, C), 1), 2, Route((A, B), 1)),  # after it
        (Route((A, B, C), 2), 2, Route((A, B), 2)),  # the last, current: the route is finished
        (Route((A, B, C), 3), 2, Route((A, B), 2)),  # a finished route stays finished
        (Route((A,), 0), 0, Route((), 0)),
    ],
)
def test_remove_keeps_heading_for_the_same_waypoint_or_the_next(route: Route, index: int, expected: Route) -> None:
    assert remove(route, index) == expected


@pytest.mark.parametrize(("route", "index"), [(Route((A, B)), 2), (Route((A, B)), -1), (Route(), 0)])
def test_remove_outside_the_route_is_refused(route: Route, index: int) -> None:
    with pytest.raises(RouteError, match="no waypoint"):
        remove(route, index)


@pytest.mark.parametrize(
    ("route", "current", "expected"),
    [
        (Route((A, B, C), 0), 0, Route((B, C), 0)),
        (Route((A, B, C), 1), 1, Route((A, C), 1)),
        (Route((A, B, C), 3), 2, Route((A, B), 2)),  # finished: "current" is the last waypoint (the thesis's rule)
    ],
)
def test_remove_current(route: Route, current: int, expected: Route) -> None:
    assert current_index(route) == current
    assert remove_current(route) == expected


def test_remove_current_of_an_empty_route_is_refused() -> None:
    assert current_index(Route()) is None
    with pytest.raises(RouteError, match="the route is empty"):
        remove_current(Route())


def test_clear() -> None:
    assert clear(Route((A, B), 2)) == Route()


def test_a_route_cannot_point_outside_itself() -> None:
    with pytest.raises(ValueError, match="outside"):
        Route((A,), 2)
    assert Route((A,), 1).finished and not Route((A,), 0).finished


# -- the mission state ---------------------------------------------------------------------------


@pytest.fixture
def mission() -> Mission:
    return Mission.model_validate(
        {"version": 1, "name": "r", "vehicle": "rover", "tree": "ugv_rc_route", "waypoints": [{"lat": -35.0, "lon": 149.0}]}
    )


def state_in(status: MissionStatus, mission: Mission) -> MissionState:
    state = MissionState()
    steps = {S.IDLE: [], S.READY: ["upload"], S.RUNNING: ["upload", "start"], S.PAUSED: ["upload", "start", "pause"],
             S.COMPLETED: ["upload", "start", "complete"], S.ABORTED: ["upload", "start", "abort"]}  # fmt: skip
    for step in steps[status]:
        {"upload": lambda: state.upload(mission), "abort": lambda: state.abort("test")}.get(step, getattr(state, step))()
    return state


@pytest.mark.parametrize(("status", "allowed"), [(S.IDLE, False), (S.READY, True), (S.RUNNING, True), (S.PAUSED, True),
                                                 (S.COMPLETED, False), (S.ABORTED, False)])  # fmt: skip
def test_set_route_is_allowed_while_ready_running_or_paused(mission: Mission, status: MissionStatus, allowed: bool) -> None:
    state = state_in(status, mission)
    heard: list[tuple[Route, str]] = []
    state.events.subscribe(RouteChanged, lambda route, reason: heard.append((route, reason)))
    if not allowed:
        with pytest.raises(Refused, match="cannot change the route"):
            state.set_route([A, B], "test")
        assert heard == []
        return
    state.set_route([A, B], "two recorded")
    assert state.status is status  # a route change is no transition
    assert state.mission is not None and state.mission.waypoints == [A, B]
    assert heard == [(Route((A, B), 0), "two recorded")]
    assert py_trees.blackboard.Blackboard.get("/mission/leg_count") == 2


def test_set_route_keeps_the_leg_inside_the_route_and_publishes_the_target(mission: Mission) -> None:
    state = state_in(S.RUNNING, mission)
    state.set_route([A, B, C], "three")
    state.advance_leg()
    state.advance_leg()
    assert state.legs.route == Route((A, B, C), 2)
    state.set_route([A], "cut")  # no leg index given: the current one, kept inside the route (finished)
    assert state.legs.route == Route((A,), 1)
    assert py_trees.blackboard.Blackboard.get("/mission/target") is None
    state.set_route([A, D], "one more, heading for it", leg_index=1)
    assert py_trees.blackboard.Blackboard.get("/mission/target") == D
    assert py_trees.blackboard.Blackboard.get("/mission/leg_index") == 1
    with pytest.raises(Refused, match="outside a route"):
        state.set_route([A], "bad", leg_index=2)
    assert state.legs.route == Route((A, D), 1)  # a refusal changes nothing
