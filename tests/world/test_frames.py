"""ENU (ROS) <-> NED (MAVLink) and local offsets <-> global positions."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from executive.world import geo
from executive.world.frames import Enu, Ned, enu_to_ned, global_to_local, local_to_global, ned_to_enu, yaw_enu_to_ned, yaw_ned_to_enu

metres = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False)
angles = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)


def test_a_point_east_north_and_up_is_north_east_and_negative_down():
    assert enu_to_ned(Enu(east=1.0, north=2.0, up=3.0)) == Ned(north=2.0, east=1.0, down=-3.0)
    assert ned_to_enu(Ned(north=2.0, east=1.0, down=-3.0)) == Enu(east=1.0, north=2.0, up=3.0)


def test_a_velocity_climbing_north_east():
    ned = enu_to_ned(Enu(0.5, 1.5, 0.25))
    assert (ned.north, ned.east, ned.down) == (1.5, 0.5, -0.25)


@given(metres, metres, metres)
def test_round_trips(a: float, b: float, c: float) -> None:
    assert ned_to_enu(enu_to_ned(Enu(a, b, c))) == Enu(a, b, c)
    assert enu_to_ned(ned_to_enu(Ned(a, b, c))) == Ned(a, b, c)


@pytest.mark.parametrize(
    ("enu_deg", "ned_deg"),
    [(0.0, 90.0), (90.0, 0.0), (180.0, -90.0), (-90.0, -180.0), (45.0, 45.0), (135.0, -45.0)],
    ids=["east", "north", "west", "south", "north-east", "north-west"],
)
def test_yaw_east_ccw_is_north_cw(enu_deg: float, ned_deg: float) -> None:
    assert math.degrees(yaw_enu_to_ned(math.radians(enu_deg))) == pytest.approx(ned_deg)
    back = math.degrees(yaw_ned_to_enu(math.radians(ned_deg)))
    assert (back - enu_deg + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-9)


@given(angles)
def test_yaw_round_trip_and_range(yaw: float) -> None:
    ned = yaw_enu_to_ned(yaw)
    assert -math.pi <= ned < math.pi
    assert math.cos(yaw_ned_to_enu(ned)) == pytest.approx(math.cos(yaw), abs=1e-9)
    assert math.sin(yaw_ned_to_enu(ned)) == pytest.approx(math.sin(yaw), abs=1e-9)


def test_local_to_global_and_back():
    origin = (47.397742, 8.545594)
    lat, lon = local_to_global(*origin, 30.0, -40.0)
    distance, bearing = geo.distance_bearing(*origin, lat, lon)
    assert distance == pytest.approx(50.0, abs=1e-6)
    assert bearing == pytest.approx(math.degrees(math.atan2(-40.0, 30.0)) % 360.0, abs=1e-6)
    assert global_to_local(*origin, lat, lon) == pytest.approx((30.0, -40.0), abs=1e-6)
    assert local_to_global(*origin, 0.0, 0.0) == origin


@given(metres, metres)
def test_local_global_round_trip(north: float, east: float) -> None:
    origin = (-35.363261, 149.165230)
    assert global_to_local(*origin, *local_to_global(*origin, north, east)) == pytest.approx((north, east), abs=1e-5)
