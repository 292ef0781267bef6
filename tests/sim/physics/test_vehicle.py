"""Kinematics of the simulated surface vehicle."""

from __future__ import annotations

import itertools

import pytest

from executive.sim.physics.vehicle import BOAT_LIMITS, ROVER_LIMITS, MotionLimits, SurfaceVehicle

HOME = (47.397742, 8.545594)


def north_of(lat: float, lon: float, metres: float) -> tuple[float, float]:
    return lat + metres / 111_319.49, lon


def powered(limits: MotionLimits = ROVER_LIMITS, heading_deg: float = 0.0) -> SurfaceVehicle:
    vehicle = SurfaceVehicle(HOME[0], HOME[1], heading_deg, limits)
    vehicle.powered = True
    return vehicle


def drive(vehicle: SurfaceVehicle, seconds: float, dt: float = 0.1) -> list[tuple[float, float]]:
    """Step for ``seconds``; returns (distance to target, speed) after each step."""
    target = vehicle.target
    trace = []
    for _ in range(round(seconds / dt)):
        vehicle.step(dt)
        trace.append((vehicle.distance_to(*target) if target else 0.0, vehicle.speed_m_s))
    return trace


@pytest.mark.parametrize("limits", [ROVER_LIMITS, BOAT_LIMITS], ids=["rover", "boat"])
def test_reaches_a_target_50_m_ahead_at_cruise_speed_and_stops_without_overshoot(limits: MotionLimits) -> None:
    vehicle = powered(limits)
    target = north_of(HOME[0], HOME[1], 50.0)
    vehicle.drive_to(*target)
    trace = drive(vehicle, 40.0)
    arrival = next(i for i, (distance, _) in enumerate(trace) if distance <= limits.arrive_m) * 0.1
    assert 25.0 <= arrival <= 32.0  # 50 m at 2 m/s, plus speeding up and slowing down
    assert max(speed for _, speed in trace) == pytest.approx(limits.cruise_m_s)
    approach = [d for d, _ in trace[: round(arrival / 0.1) + 1]]
    assert all(b < a for a, b in itertools.pairwise(approach))  # never goes past it
    assert vehicle.arrived and vehicle.speed_m_s == 0.0
    assert vehicle.distance_to(*target) <= limits.arrive_m + limits.drift_m_s * 15  # a boat drifts once stopped


def test_a_target_behind_is_reached_by_turning_first_not_by_circling() -> None:
    vehicle = powered(heading_deg=180.0)
    target = north_of(HOME[0], HOME[1], 10.0)
    vehicle.drive_to(*target)
    trace = drive(vehicle, 15.0)
    assert vehicle.arrived and vehicle.distance_to(*target) <= ROVER_LIMITS.arrive_m
    assert min(vehicle.heading_deg, 360.0 - vehicle.heading_deg) < 5.0
    assert max(d for d, _ in trace) <= 10.5  # turned about where it stood


def test_large_steps_are_integrated_in_substeps() -> None:
    fine, coarse = powered(heading_deg=90.0), powered(heading_deg=90.0)
    target = north_of(HOME[0], HOME[1], 30.0)
    fine.drive_to(*target)
    coarse.drive_to(*target)
    drive(fine, 12.0, dt=0.05)
    coarse.step(6.0)
    coarse.step(6.0)
    assert coarse.distance_to(fine.lat, fine.lon) < 1e-6
    assert coarse.heading_deg == pytest.approx(fine.heading_deg)


def test_speed_is_capped_at_the_maximum() -> None:
    vehicle = powered()
    vehicle.drive_to(*north_of(HOME[0], HOME[1], 100.0), speed_m_s=10.0)
    assert max(speed for _, speed in drive(vehicle, 20.0)) == pytest.approx(ROVER_LIMITS.max_m_s)


@pytest.mark.parametrize("limits", [ROVER_LIMITS, BOAT_LIMITS], ids=["rover", "boat"])
def test_an_unpowered_vehicle_never_moves(limits: MotionLimits) -> None:
    vehicle = SurfaceVehicle(HOME[0], HOME[1], 0.0, limits)
    vehicle.drive_to(*north_of(HOME[0], HOME[1], 50.0))
    drive(vehicle, 60.0)
    assert (vehicle.lat, vehicle.lon, vehicle.speed_m_s, vehicle.velocity_ned) == (HOME[0], HOME[1], 0.0, (0.0, 0.0, 0.0))


def test_hold_brakes_to_a_stop_and_stays() -> None:
    vehicle = powered()
    vehicle.drive_to(*north_of(HOME[0], HOME[1], 100.0))
    drive(vehicle, 10.0)
    where = (vehicle.lat, vehicle.lon)
    vehicle.hold()
    assert vehicle.target is None
    drive(vehicle, 30.0)
    assert vehicle.speed_m_s == 0.0
    braking = ROVER_LIMITS.cruise_m_s**2 / (2 * ROVER_LIMITS.decel_m_s2)
    assert vehicle.distance_to(*where) == pytest.approx(braking, abs=0.1)


def test_a_powered_boat_drifts_slowly_when_holding() -> None:
    boat = powered(BOAT_LIMITS)
    boat.hold()
    drive(boat, 100.0)
    assert boat.distance_to(HOME[0], HOME[1]) == pytest.approx(BOAT_LIMITS.drift_m_s * 100.0)
    assert boat.bearing_to(HOME[0], HOME[1]) == pytest.approx((BOAT_LIMITS.drift_toward_deg + 180.0) % 360.0)


def test_a_rover_under_way_keeps_its_least_turning_speed_through_a_sharp_turn() -> None:
    # AR_PosControl: not slower than sqrt(0.5 x ATC_TURN_MAX_G x TURN_RADIUS) = 1.63 m/s while it turns (it cannot pivot)
    vehicle = powered()
    vehicle.drive_to(*north_of(HOME[0], HOME[1], 100.0))
    drive(vehicle, 5.0)
    assert vehicle.speed_m_s == pytest.approx(ROVER_LIMITS.cruise_m_s)
    lat, lon = vehicle.lat, vehicle.lon
    vehicle.drive_to(lat, lon + 20.0 / (111_319.49 * 0.6764))  # 20 m east: a 90° turn
    speeds = [speed for _, speed in drive(vehicle, 2.0)]
    assert min(speeds) >= ROVER_LIMITS.turn_speed_min_m_s - 0.01
    assert ROVER_LIMITS.turn_speed_min_m_s == pytest.approx(1.63, abs=0.01)
