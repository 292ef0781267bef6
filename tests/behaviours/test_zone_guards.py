"""The keep-out guard: inside a zone, or heading into one closer than the vehicle can stop (failsafe keep_out)."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.behaviours.zone_guards import OutsideKeepOut, stopping_m
from executive.mission.model import Mission
from executive.world import geo
from executive.world.state import GlobalPosition

HOME = (44.0, 9.0)
PIER = geo.destination(*HOME, 0.0, 20.0)  # a 5 m circle 20 m north of home


def mission() -> Mission:
    pier = {"name": "pier", "circle": {"lat": PIER[0], "lon": PIER[1], "radius_m": 5.0}}
    return Mission.model_validate(
        {"version": 1, "name": "pier", "vehicle": "boat", "geofence": {"keep_out": [pier]}, "waypoints": [{"lat": HOME[0], "lon": HOME[1]}]}
    )


def moving(north_m: float, vn_m_s: float, ve_m_s: float = 0.0) -> GlobalPosition:
    lat, lon = geo.destination(*HOME, 0.0, north_m)
    return GlobalPosition(lat, lon, 0.0, vn_m_s, ve_m_s, 0.0, 0.0, 0.0)


def test_the_horizon_is_a_second_of_reaction_and_the_braking_distance():
    assert stopping_m(2.0) == pytest.approx(6.0)  # 4 s at 2 m/s
    assert stopping_m(5.0) == pytest.approx(30.0)  # 7 s at 5 m/s


@pytest.mark.parametrize(
    ("north_m", "vn", "ve", "expected", "why"),
    [
        (20.0, 0.0, 0.0, Status.FAILURE, "inside keep-out zone 'pier'"),
        (10.0, 2.0, 0.0, Status.FAILURE, "heading into keep-out zone 'pier': 5.0 m ahead at 2.0 m/s (stops in 6.0 m)"),
        (8.0, 2.0, 0.0, Status.SUCCESS, ""),  # 7 m ahead: it stops in 6 m
        (0.0, 5.0, 0.0, Status.FAILURE, "15.0 m ahead at 5.0 m/s (stops in 30.0 m)"),  # faster: seen further ahead
        (10.0, 0.0, 2.0, Status.SUCCESS, ""),  # beside it, heading east: passes it by
        (10.0, -2.0, 0.0, Status.SUCCESS, ""),  # turning away
    ],
)
def test_a_vehicle_in_or_heading_into_a_zone_before_it_could_stop_fails(harness, vehicle, north_m, vn, ve, expected, why):
    vehicle.set(vehicle__position=moving(north_m, vn, ve))
    node = OutsideKeepOut(mission())
    h = harness(node)
    assert h.tick() == expected
    assert why in node.feedback_message
