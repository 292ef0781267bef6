"""The simulated ArduRover drives as the firmware's navigation does: GUIDED's shaped stop points, AUTO's S-curves, pivots.

Expected figures come from the firmware's parameters (SITL's rover.parm: WP_SPEED 5, WP_RADIUS 3; defaults
ATC_ACCEL_MAX 1, WP_JERK 0 = 1 m/s^3, ATC_TURN_MAX_G 0.6, WP_PIVOT_ANGLE 60, WP_PIVOT_RATE 60) and the
sources cited in executive/sim/ardupilot/rover_nav.py, worked out by hand, not read back from the model.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.autopilot.rover_motion import RoverMotion, SCurveLeg, ShapedTarget, auto_corner_cut_m, sqrt_controller, stopping_distance
from executive.sim.ardupilot.rover import SITL_PARAMS
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Gcs

MakeGcs = Callable[..., "Gcs"]
STEP_S = 0.1


class VehicleAt:
    def __init__(self, t: float, gcs: Gcs, out: list[MAVLinkMessage]) -> None:
        self.t = t
        self.ne = gcs.ap.vehicle.north_east_m  # type: ignore[attr-defined]
        self.speed = gcs.ap.vehicle.speed_m_s
        self.yaw_rate = gcs.ap.vehicle.yaw_rate_rad_s
        self.heading = gcs.ap.vehicle.heading_deg
        self.texts = gcs.texts(out)
        self.reached = bool(gcs.of_type(out, "MISSION_ITEM_REACHED"))


def drive(gcs: Gcs, seconds: float) -> list[VehicleAt]:
    samples = []
    for i in range(round(seconds / STEP_S)):
        samples.append(VehicleAt((i + 1) * STEP_S, gcs, gcs.run(STEP_S)))
    return samples


def armed_in(make_gcs: MakeGcs, mode: str, kind: str = "rover", **options: object) -> Gcs:
    gcs = make_gcs(kind, ekf_ready=True, **options)
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    if mode == "GUIDED":
        assert gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
    return gcs


def fly_auto(gcs: Gcs, points: list[tuple[float, float]]) -> None:
    """Upload NAV_WAYPOINTs (item 0 home) and switch to AUTO."""
    items = [(gcs.ap.start[0], gcs.ap.start[1]), *points]
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    while replies and replies[-1].get_type() == "MISSION_REQUEST":
        lat, lon = items[replies[-1].seq]
        x, y, seq = round(lat * 1e7), round(lon * 1e7), replies[-1].seq
        replies = gcs.send(
            gcs.mav.mission_item_int_encode(1, 1, seq, m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, m.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, x, y, 0, 0)
        )
    assert gcs.set_mode("AUTO") == m.MAV_RESULT_ACCEPTED


def at(gcs: Gcs, north: float, east: float) -> tuple[float, float]:
    lat, _ = gcs.north(north)
    _, lon = gcs.east(east)
    return lat, lon


def decelerations(samples: list[VehicleAt], window_s: float = 1.0) -> list[float]:
    """Speed lost per second over each window of ``window_s``."""
    n = round(window_s / STEP_S)
    return [(a.speed - b.speed) / window_s for a, b in zip(samples, samples[n:], strict=False)]


# -- the kinematics, from the firmware's formulas ----------------------------------------------------


def test_sqrt_controller_is_linear_near_zero_then_the_braking_curve() -> None:
    # gain 0.5, limit 0.5: linear within 0.5 / 0.25 = 2 m, then sqrt(2 * 0.5 * (e - 1))
    assert sqrt_controller(1.0, 0.5, 0.5) == pytest.approx(0.5)
    assert sqrt_controller(20.0, 0.5, 0.5) == pytest.approx(math.sqrt(19.0))
    assert sqrt_controller(-20.0, 0.5, 0.5) == pytest.approx(-math.sqrt(19.0))
    assert sqrt_controller(20.0, 0.5, 0.5, dt=0.1) == pytest.approx(math.sqrt(19.0))
    assert sqrt_controller(0.01, 50.0, 5.0, dt=0.1) == pytest.approx(0.01 / 0.1)  # never past the target within a step
    for speed in (0.2, 1.0, 3.0, 7.0):
        assert sqrt_controller(stopping_distance(speed, 0.5, 0.5), 0.5, 0.5) == pytest.approx(speed)


def test_an_s_curve_leg_of_30_m_at_5_m_s_accelerates_within_1_m_s2_and_reaches_5_m_s() -> None:
    # constant jerk 1 and acceleration 1: speeding up to v covers v (v + 1) / 2 m, so 15 m (half the leg) is exactly v = 5,
    # in 6 s; the raised-cosine jerk (snap 15: ramps of pi / 30 s) makes it a little longer and a little slower
    leg = SCurveLeg((0.0, 0.0), (30.0, 0.0), 5.0, 1.0, 1.0)
    assert 12.0 <= leg.end_s <= 12.3
    states = [leg.along(i * 0.01) for i in range(round(leg.end_s * 100) + 2)]
    assert max(v for _, v, _ in states) == pytest.approx(5.0, abs=0.1)
    assert max(abs(a) for _, _, a in states) <= 1.0 + 1e-6
    assert states[-1][:2] == (30.0, 0.0)
    assert all(b[0] >= a[0] for a, b in itertools.pairwise(states))
    assert leg.along(leg.end_s / 2)[0] == pytest.approx(15.0, abs=1e-6)  # symmetric
    long = SCurveLeg((0.0, 0.0), (0.0, 300.0), 5.0, 1.0, 1.0)
    assert long.speed_max_m_s == pytest.approx(5.0)
    assert long.state(long.end_s / 2)[1] == pytest.approx((0.0, 5.0))


def test_a_shaped_guided_target_speeds_up_at_1_and_brakes_at_half() -> None:
    target = ShapedTarget(5.0, 1.0, 1.0)
    t, trace = 0.0, []
    while math.dist(target.pos, (30.0, 0.0)) > 0.01 and t < 60:
        target.step((30.0, 0.0), 0.02)
        t += 0.02
        trace.append((t, target.pos[0], target.vel[0], target.acc[0]))
    assert max(p for _, p, _, _ in trace) <= 30.0 + 1e-6  # it gets there (1 cm) before it could pass it
    assert max(abs(a) for *_, a in trace) <= 1.0 + 1e-6  # the acceleration limit, both ways
    peak_t, _, peak, _ = max(trace, key=lambda row: row[2])
    assert 4.0 <= peak <= 4.5  # where the 1 m/s/s rise meets sqrt(distance left - 1): WP_SPEED 5 is never reached
    assert 0.5 <= peak / (t - peak_t) <= 0.65  # the approach's square-root curve is half the acceleration (1 m/s/s)
    assert 11.5 <= t <= 13.5


def test_auto_s_corner_between_long_legs_reaches_out_to_wp_radius_and_no_farther() -> None:
    # a fast waypoint's turn mid point lies within WP_RADIUS (3 m) of it: for 90 degrees, 3 sin 45 = 2.12 m off each leg
    motion = RoverMotion.from_params(SITL_PARAMS["rover"])
    cut = auto_corner_cut_m(motion, 30.0, 30.0, math.pi / 2)
    assert cut is not None and 1.8 <= cut <= 3.0 * math.sin(math.pi / 4) + 0.02
    short = auto_corner_cut_m(motion, 10.0, 10.0, math.pi / 2)
    assert short is not None and short < cut  # short legs come slower: the turn fits sooner
    assert auto_corner_cut_m(motion, 30.0, 30.0, 0.0) == 0.0  # straight on: driven through, no cut


def test_the_parameters_give_the_firmware_s_derived_limits() -> None:
    motion = RoverMotion.from_params(SITL_PARAMS["rover"])
    assert (motion.speed_m_s, motion.radius_m, motion.path_accel_m_s2, motion.jerk_m_s3) == (5.0, 3.0, 1.0, 1.0)
    assert motion.lat_accel_m_s2 == pytest.approx(0.6 * 9.80665)
    assert motion.turn_speed_min_m_s == pytest.approx(math.sqrt(0.5 * 0.6 * 9.80665 * 0.9))
    assert motion.approach_speed_m_s(20.0) == pytest.approx(math.sqrt(19.0))
    assert set(motion.defaulted) == {"WP_ACCEL", "WP_JERK", "WP_PIVOT_ANGLE", "WP_PIVOT_RATE", "ATC_ACCEL_MAX", "ATC_DECEL_MAX",
                                     "ATC_TURN_MAX_G", "ATC_STR_RAT_MAX", "ATC_STR_ACC_MAX", "TURN_RADIUS", "PSC_POS_P", "PSC_VEL_P"}  # fmt: skip
    slow = RoverMotion.from_params({"ATC_ACCEL_MAX": 2.0, "ATC_DECEL_MAX": 3.0, "WP_ACCEL": 1.5})
    assert (slow.path_accel_m_s2, slow.jerk_m_s3, slow.decel_m_s2) == (1.5, 1.5, 3.0)
    skid = RoverMotion.from_params({}, skid_steering=True)
    assert (skid.turn_radius_m, skid.pivots, skid.corner_radius_m) == (0.0, True, 2.0)


# -- the simulated vehicle ---------------------------------------------------------------------------


def test_a_30_m_guided_leg_from_rest_peaks_near_4_4_m_s_and_brakes_at_half_atc_accel_max(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED", params=SITL_PARAMS["rover"])
    gcs.goto(*gcs.north(30.0))
    samples = drive(gcs, 25.0)
    assert 4.0 <= max(s.speed for s in samples) <= 4.6  # not WP_SPEED (5): the stop point is too near
    peak = max(samples, key=lambda s: s.speed)
    stopped = next(s for s in samples if s.t > peak.t and s.speed < 0.05)
    assert peak.speed / (stopped.t - peak.t) <= 0.65  # AR_PosControl's approach: about half of ATC_ACCEL_MAX (1 m/s/s)
    reached = next(s.t for s in samples if s.reached)
    assert 12.0 <= reached <= 14.5
    assert math.dist(samples[-1].ne, (30.0, 0.0)) <= 3.0  # stopped within WP_RADIUS of the point


def test_a_30_m_auto_leg_is_an_s_curve_to_wp_speed_and_back(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "AUTO", params=SITL_PARAMS["rover"])
    fly_auto(gcs, [gcs.north(30.0)])
    samples = drive(gcs, 25.0)
    assert 4.7 <= max(s.speed for s in samples) <= 5.1  # WP_SPEED, half-way
    assert max(decelerations(samples)) <= 1.15  # ATC_ACCEL_MAX both ways
    reached = next(s.t for s in samples if "Reached waypoint #1" in s.texts)
    assert 12.0 <= reached <= 14.0
    assert math.dist(samples[-1].ne, (30.0, 0.0)) <= 3.0


def test_auto_drives_through_intermediate_corners_within_wp_radius_and_stops_at_the_last(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "AUTO", params=SITL_PARAMS["rover"])
    corners = [(30.0, 0.0), (30.0, 30.0), (0.0, 30.0)]
    fly_auto(gcs, [at(gcs, n, e) for n, e in corners])
    samples = drive(gcs, 60.0)
    for n, e in corners[:-1]:
        nearest = min(samples, key=lambda s: math.dist(s.ne, (n, e)))
        assert math.dist(nearest.ne, (n, e)) <= 3.0  # the turn's mid point within WP_RADIUS
        assert nearest.speed >= 1.0  # a fast waypoint: no stop
    assert samples[-1].speed < 1e-3 and math.dist(samples[-1].ne, corners[-1]) <= 3.0
    assert [text for s in samples for text in s.texts if text.startswith("Reached")] == [f"Reached waypoint #{i}" for i in (1, 2, 3)]


def test_a_new_guided_target_swings_the_shaped_velocity_round_without_a_stop(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED", params=SITL_PARAMS["rover"])
    gcs.goto(*gcs.north(30.0))
    drive(gcs, 6.0)
    gcs.goto(*at(gcs, 30.0, 40.0))
    samples = drive(gcs, 15.0)
    assert min(s.speed for s in samples[:40]) >= 2.0  # it turns under way


def test_a_skid_steered_vehicle_stops_and_pivots_at_a_sharp_auto_corner(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "AUTO", kind="bunker")
    fly_auto(gcs, [gcs.north(10.0), at(gcs, 10.0, 10.0)])  # a 90 degree corner: more than WP_PIVOT_ANGLE (60)
    samples = drive(gcs, 40.0)
    turning = [s for s in samples if abs(s.yaw_rate) > math.radians(20.0)]
    assert turning and all(abs(s.speed) < 0.05 for s in turning)  # it turns on the spot, stopped
    assert max(abs(s.yaw_rate) for s in turning) <= math.radians(60.0) + 1e-6  # WP_PIVOT_RATE
    assert min(math.dist(s.ne, (10.0, 0.0)) for s in turning) <= 2.0
    assert math.dist(samples[-1].ne, (10.0, 10.0)) <= 2.0
    assert samples[-1].heading == pytest.approx(90.0, abs=6.0)
