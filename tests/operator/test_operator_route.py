"""The operator's route requests: applied to the mission state's route, at the vehicle's position when asked, refused with a reason."""

from __future__ import annotations

import pytest

from executive.mission.events import RouteChanged
from executive.mission.lifecycle import MissionState
from executive.mission.model import GeofenceConfig, Home, Mission
from executive.operator import Operator
from executive.testing import EKF_READY
from executive.world import geo
from executive.world.clock import ManualClock
from executive.world.state import EkfFlags, EkfStatus, GlobalPosition

EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
HERE = (47.3979, 8.5457)


@pytest.fixture
def state(square_mission: Mission) -> MissionState:
    state = MissionState()
    state.upload(square_mission)
    state.start()
    return state


@pytest.fixture
def operator(state: MissionState, clock: ManualClock, vehicle) -> Operator:
    vehicle.set(vehicle__position=GlobalPosition(*HERE, 0.0, 0.0, 0.0, 0.0, None, clock.now()), vehicle__ekf=EKF_READY)
    return Operator(state, "rover", clock=clock)


def test_an_offset_moves_the_route_tells_the_listeners_and_replies_with_the_route(operator: Operator, state: MissionState) -> None:
    before = state.legs.route
    heard = []
    state.events.subscribe(RouteChanged, lambda route, reason: heard.append(reason))
    reply = operator.request("route", source="ctl", operation="offset", distance_m=5, bearing_deg=90)
    assert (reply.ok, reply.state) == (True, "RUNNING")
    assert reply.reason == heard[0] == "ctl: 4 waypoints offset 5 m toward 090.0°"
    for old, new in zip(before.waypoints, state.legs.route.waypoints, strict=True):
        distance, bearing = geo.distance_bearing(old.lat, old.lon, new.lat, new.lon)
        assert distance == pytest.approx(5.0, rel=1e-6) and bearing == pytest.approx(90.0, abs=1e-3)
    assert reply.route is not None
    assert reply.route["waypoints"] == [[wp.lat, wp.lon, 0.0] for wp in state.legs.route.waypoints]
    assert (reply.route["current"], reply.route["on_autopilot"], reply.route["upload"]) == (1, False, None)  # nothing keeps it here


def test_add_and_set_home_take_the_vehicle_position(operator: Operator, state: MissionState) -> None:
    reply = operator.request("route", source="ctl", operation="add", after="current")
    assert reply.ok and reply.reason == "ctl: waypoint 2/5 added at 47.3979000, 8.5457000 (the vehicle's position)"
    assert (state.legs.route.waypoints[1].lat, state.legs.route.waypoints[1].lon) == HERE
    assert operator.request("route", operation="set_home").ok
    assert state.mission is not None and state.mission.home == Home(lat=HERE[0], lon=HERE[1])
    assert len(state.legs.route) == 5


@pytest.mark.parametrize(
    ("facts", "age_s", "why"),
    [
        ({"vehicle__position": None}, 0.0, "route add: no position"),
        ({"vehicle__ekf": EKF_LOST}, 0.0, "route add: the EKF has no position estimate"),
        ({}, 2.5, "route add: the last position is 2.5 s old"),
    ],
)
def test_the_vehicle_position_must_be_known_well(operator: Operator, state: MissionState, vehicle, clock, facts, age_s, why) -> None:
    vehicle.set(**facts)
    clock.advance(age_s)
    before = state.legs.route
    reply = operator.request("route", operation="add")
    assert (reply.ok, reply.reason) == (False, why)
    assert state.legs.route == before
    assert operator.request("route", operation="add", lat=47.3981, lon=8.5458).ok  # a position given needs none


@pytest.mark.parametrize(
    ("requests", "why"),
    [
        (["abort"], "cannot change the route while ABORTED (allowed while PAUSED, READY, RUNNING)"),
        (["abort", "delete"], "cannot change the route: no mission loaded"),
    ],
)
def test_a_route_edit_is_refused_outside_ready_running_and_paused(operator: Operator, requests: list[str], why: str) -> None:
    for op in requests:
        operator.request(op)
    reply = operator.request("route", operation="remove", waypoint="last")
    assert (reply.ok, reply.reason) == (False, why)
    shown = operator.request("route", operation="show")  # showing is always allowed
    assert shown.ok and shown.route is not None and len(shown.route["waypoints"]) == (4 if len(requests) == 1 else 0)


def test_an_edit_breaking_the_mission_rules_is_refused_and_changes_nothing(operator: Operator, state: MissionState) -> None:
    before = state.legs.route
    reply = operator.request("route", operation="clear")
    assert not reply.ok and reply.reason == "route clear: the edited mission breaks its rules: waypoints: at least one waypoint is needed"
    assert state.mission is not None
    state.legs.load(
        state.mission.model_copy(update={"geofence": GeofenceConfig(max_distance_from_home_m=500.0), "home": Home(lat=47.3977, lon=8.5456)}),
        state.legs.leg_index,
    )
    reply = operator.request("route", operation="offset", distance_m=600, bearing_deg=0, waypoint=2)
    assert not reply.ok and "waypoints[1]: outside the geofence" in reply.reason
    assert state.legs.route.waypoints == before.waypoints


@pytest.mark.parametrize(
    ("args", "why"),
    [
        ({"operation": "warp"}, "route warp: unknown route operation 'warp'"),
        ({}, "route None: unknown route operation None"),
        ({"operation": "offset", "distance_m": 5}, "route offset: bearing_deg is needed"),
        ({"operation": "remove", "waypoint": 9}, "route remove: no waypoint 9 to remove: the route has 4"),
    ],
)
def test_a_bad_route_request_says_why(operator: Operator, args: dict, why: str) -> None:
    reply = operator.request("route", **args)
    assert not reply.ok and reply.reason.startswith(why)
