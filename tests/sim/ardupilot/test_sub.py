"""The simulated AUV (ArduSub): depth, the seabed under it, its modes."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest
from test_mission_store import item, upload

from executive.sim import SimServer
from executive.sim.physics.underwater import SUB_LIMITS, Seabed, UnderwaterVehicle
from executive.world.clock import ScaledClock
from executive.world.dialect import mavlink as m
from executive.world.vehicles import profile_for_mav_type

if TYPE_CHECKING:
    from sim_support import Client, Gcs

MakeGcs = Callable[..., "Gcs"]
TERRAIN_POS_VEL = 0x0DC0  # position and velocity used, acceleration/yaw ignored


def armed_in(make_gcs: MakeGcs, mode: str, **options: float) -> Gcs:
    gcs = make_gcs("sub", ekf_ready=True, **options)
    assert gcs.set_mode(mode) == m.MAV_RESULT_ACCEPTED
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    return gcs


def depth(gcs: Gcs) -> float:
    """The depth GLOBAL_POSITION_INT reports (m, positive down)."""
    return -gcs.last("GLOBAL_POSITION_INT").relative_alt / 1000


def dive_to(gcs: Gcs, metres: float, north_m: float = 0.0, seconds: float = 40.0) -> None:
    gcs.goto(*gcs.north(north_m), alt=-metres)  # GUIDED: altitude above home, negative below the surface
    gcs.run(seconds, step=0.5)


def test_an_ardusub_boots_in_manual(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("sub", run_s=0.5)
    heartbeat = gcs.last("HEARTBEAT")
    assert (heartbeat.type, heartbeat.custom_mode, heartbeat.system_status) == (m.MAV_TYPE_SUBMARINE, 19, m.MAV_STATE_BOOT)
    assert profile_for_mav_type(heartbeat.type).kind == "sub"
    gcs.run(1.0)
    heartbeat = gcs.last("HEARTBEAT")
    flags = m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_STABILIZE_ENABLED | m.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
    assert (heartbeat.custom_mode, heartbeat.base_mode, heartbeat.system_status) == (19, flags, m.MAV_STATE_STANDBY)
    assert gcs.texts(gcs.log)[:2] == ["ArduSub V4.7.0-dev (sim)", "Frame: VECTORED_6DOF"]


def test_position_modes_need_a_position_even_disarmed(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("sub")
    for mode in ("GUIDED", "POSHOLD"):
        replies = gcs.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, gcs.ap.profile.modes[mode])
        assert (replies[0].result, gcs.texts(replies)) == (m.MAV_RESULT_FAILED, [f"Mode change failed: {mode} requires position"])
    assert gcs.set_mode("ALT_HOLD") == m.MAV_RESULT_ACCEPTED
    gcs.run(10.0)
    assert gcs.set_mode("POSHOLD") == m.MAV_RESULT_ACCEPTED


@pytest.mark.parametrize("mode", ["MANUAL", "STABILIZE", "ALT_HOLD", "POSHOLD", "GUIDED", "SURFACE"])
def test_ardusub_arms_in_any_mode(make_gcs: MakeGcs, mode: str) -> None:
    gcs = armed_in(make_gcs, mode)
    gcs.run(1.0)
    heartbeat = gcs.last("HEARTBEAT")
    assert heartbeat.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED and heartbeat.system_status == m.MAV_STATE_ACTIVE
    guided = m.MAV_MODE_FLAG_GUIDED_ENABLED if mode in ("POSHOLD", "GUIDED") else 0
    assert heartbeat.base_mode & m.MAV_MODE_FLAG_GUIDED_ENABLED == guided


def test_guided_goes_to_a_depth_and_holds_it(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED")
    target = gcs.north(15.0)
    gcs.goto(*target, alt=-10.0)
    out = gcs.run(10.0, step=0.5)
    climb_rates = [msg.vz for msg in gcs.of_type(out, "GLOBAL_POSITION_INT")]
    assert 0 < max(climb_rates) <= SUB_LIMITS.descend_m_s * 100  # NED: descending is positive vz, never over the limit
    assert 2.0 < depth(gcs) < 6.0
    reported = gcs.last("POSITION_TARGET_GLOBAL_INT")
    assert (reported.lat_int, reported.alt) == (round(target[0] * 1e7), pytest.approx(-10.0))
    gcs.run(40.0, step=0.5)
    assert depth(gcs) == pytest.approx(10.0, abs=0.05)
    assert gcs.ap.vehicle.distance_to(*target) <= 0.3
    assert gcs.last("NAV_CONTROLLER_OUTPUT").wp_dist == 0


def test_guided_ignores_the_absolute_frames(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED")
    gcs.goto(*gcs.north(15.0), alt=-10.0, frame=m.MAV_FRAME_GLOBAL_INT)  # ArduSub: "not supported"
    gcs.run(20.0, step=0.5)
    assert depth(gcs) < 0.05 and gcs.ap.vehicle.distance_to(*gcs.ap.start) < 0.01


def test_alt_hold_holds_the_depth_that_manual_does_not(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED")
    dive_to(gcs, 8.0)
    assert gcs.set_mode("ALT_HOLD") == m.MAV_RESULT_ACCEPTED
    gcs.run(60.0, step=0.5)
    assert depth(gcs) == pytest.approx(8.0, abs=0.05)
    gcs.goto(0.0, 0.0, alt=-12.0)  # in ALT_HOLD the message sets the depth only
    gcs.run(30.0, step=0.5)
    assert depth(gcs) == pytest.approx(12.0, abs=0.05)
    assert gcs.ap.vehicle.distance_to(*gcs.ap.start) < 0.5
    assert gcs.set_mode("MANUAL") == m.MAV_RESULT_ACCEPTED  # no pilot, no depth hold: it floats up
    gcs.run(60.0, step=0.5)
    assert depth(gcs) == pytest.approx(12.0 - 60 * SUB_LIMITS.buoyancy_m_s, abs=0.3)


def test_surface_climbs_to_the_surface_then_holds_there_in_alt_hold(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED")
    dive_to(gcs, 10.0)
    assert gcs.ack(m.MAV_CMD_NAV_LAND).result == m.MAV_RESULT_ACCEPTED  # ArduSub's NAV_LAND is SURFACE
    assert gcs.ap.mode == "SURFACE"
    out = gcs.run(10.0, step=0.5)
    assert min(msg.vz for msg in gcs.of_type(out, "GLOBAL_POSITION_INT")) >= -SUB_LIMITS.climb_m_s * 100  # climbs no faster
    assert 4.0 < depth(gcs) < 8.0
    out = gcs.run(30.0, step=0.5)
    assert [msg.custom_mode for msg in gcs.of_type(out, "HEARTBEAT")][-1] == 2  # SURFACE complete: ALT_HOLD
    assert depth(gcs) < 0.2
    gcs.run(30.0, step=0.5)
    assert gcs.ap.mode == "ALT_HOLD" and depth(gcs) == pytest.approx(0.15, abs=0.02)  # SURFACE_DEPTH less 5 cm


def test_the_rangefinder_reads_the_height_above_the_seabed(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED")
    seabed = gcs.ap.vehicle.seabed
    sensor = gcs.last("DISTANCE_SENSOR")  # streamed unasked, like GLOBAL_POSITION_INT
    assert (sensor.orientation, sensor.min_distance, sensor.max_distance) == (m.MAV_SENSOR_ROTATION_PITCH_270, 50, 3000)  # RNGFND1_MIN/MAX
    assert sensor.current_distance == round(seabed.depth_at(0.0, 0.0) * 100) == 3000
    gcs.goto(*gcs.east(60.0), alt=-5.0)  # the default seabed deepens toward the east
    gcs.run(90.0, step=0.5)
    north, east = gcs.ap.vehicle.north_east_m
    assert east == pytest.approx(60.0, abs=0.3)
    expected = seabed.depth_at(north, east) - depth(gcs)
    assert gcs.last("DISTANCE_SENSOR").current_distance == pytest.approx(expected * 100, abs=1)
    assert expected == pytest.approx(30.0 + 0.02 * 60.0 - 5.0, abs=0.05)
    replies = gcs.command(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_RANGEFINDER)  # not streamed since ArduPilot 4.7
    assert replies[1].distance == pytest.approx(expected, abs=0.01)


def test_beyond_its_maximum_the_rangefinder_reports_the_raw_distance_and_its_range(make_gcs: MakeGcs) -> None:
    """ArduSub's SITL: the seabed 50 m down, the sonar to 30 m: 45 m at 5 m deep, in DISTANCE_SENSOR beyond its max_distance
    (invalid) and in RANGEFINDER without a range (as issue 14 saw it: 45 m and 45.2 m); SURFTRAK waits for a good reading."""
    gcs = armed_in(make_gcs, "GUIDED", seabed_depth_m=50.0)
    dive_to(gcs, 5.0)
    sensor = gcs.last("DISTANCE_SENSOR")
    assert sensor.max_distance == 3000 and sensor.current_distance == pytest.approx(4500, abs=2)  # beyond its max: invalid
    assert gcs.ap.rangefinder_m is None  # not a height: RangeFinder::Status OutOfRangeHigh
    replies = gcs.command(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_RANGEFINDER)
    assert replies[1].distance == pytest.approx(45.0, abs=0.05)
    assert gcs.set_mode("SURFTRAK") == m.MAV_RESULT_ACCEPTED  # entered all the same ("waiting for a rangefinder reading")
    gcs.run(10.0, step=0.5)
    assert depth(gcs) == pytest.approx(5.0, abs=0.1)  # it holds the depth meanwhile


def test_the_rangefinder_maximum_is_an_option(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED", seabed_depth_m=50.0, rangefinder_max_m=60.0)
    assert gcs.last("DISTANCE_SENSOR").max_distance == 6000 and gcs.ap.rangefinder_m == pytest.approx(50.0, abs=0.05)


def test_guided_drops_a_terrain_frame_target_silently(make_gcs: MakeGcs) -> None:
    """ArduSub/GCS_MAVLink_Sub.cpp: no terrain data under water, the conversion fails and the handler breaks: no ack, no move."""
    gcs = armed_in(make_gcs, "GUIDED")
    dive_to(gcs, 4.9)
    replies = gcs.goto(*gcs.east(80.0), type_mask=TERRAIN_POS_VEL, frame=m.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT, alt=24.0)  # as issue 14 sent it
    said = gcs.run(60.0, step=0.5)
    assert depth(gcs) == pytest.approx(4.9, abs=0.05) and gcs.ap.vehicle.north_east_m[1] == pytest.approx(0.0, abs=0.3)
    assert replies == [] and gcs.texts(said) == []


def test_surftrak_keeps_the_height_of_its_first_good_reading(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "GUIDED", seabed_depth_m=20.0)
    dive_to(gcs, 6.0)
    assert gcs.set_mode("SURFTRAK") == m.MAV_RESULT_ACCEPTED
    gcs.run(5.0, step=0.5)
    assert gcs.ap.vehicle.holding_altitude and gcs.ap.rangefinder_m == pytest.approx(14.0, abs=0.1)


def test_do_reposition(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "POSHOLD")
    lat, lon = gcs.north(5.0)
    assert gcs.reposition(lat, lon, -3.0).result == m.MAV_RESULT_DENIED  # not in GUIDED, no change-mode flag
    assert gcs.reposition(lat, lon, 0.0, m.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE).result == m.MAV_RESULT_DENIED  # zero altitude
    assert gcs.reposition(lat, lon, -3.0, m.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE).result == m.MAV_RESULT_ACCEPTED
    assert gcs.ap.mode == "GUIDED"
    gcs.run(30.0, step=0.5)
    assert depth(gcs) == pytest.approx(3.0, abs=0.05) and gcs.ap.vehicle.distance_to(lat, lon) <= 0.3


def test_a_disarmed_sub_floats_up_and_an_armed_one_holds_where_it_was_armed(make_gcs: MakeGcs) -> None:
    gcs = armed_in(make_gcs, "ALT_HOLD")
    gcs.goto(0.0, 0.0, alt=-6.0)
    gcs.run(30.0, step=0.5)
    gcs.ack(m.MAV_CMD_COMPONENT_ARM_DISARM, 0)
    gcs.run(40.0, step=0.5)
    assert depth(gcs) == pytest.approx(6.0 - 40 * SUB_LIMITS.buoyancy_m_s, abs=0.3)
    held = gcs.ap.vehicle.depth_m
    gcs.arm()
    gcs.run(30.0, step=0.5)
    assert gcs.ap.vehicle.depth_m == pytest.approx(held, abs=0.05)


def test_the_vehicle_stops_at_the_seabed() -> None:
    vehicle = UnderwaterVehicle(47.0, 8.0, seabed=Seabed(depth_m=12.0, slope=0.0))
    vehicle.powered = True
    vehicle.hold_depth_at(50.0)
    assert vehicle.depth_target_m == pytest.approx(12.0 - SUB_LIMITS.hull_m)
    for _ in range(600):
        vehicle.step(0.1)
        assert vehicle.depth_m <= 12.0 - SUB_LIMITS.hull_m + 1e-9
    assert vehicle.altitude_m == pytest.approx(SUB_LIMITS.hull_m)


def test_a_sub_over_tcp(client_for: Callable[[str], Client]) -> None:
    with SimServer("sub", "tcpin:127.0.0.1:0", clock=ScaledClock(50.0), ekf_ready_after_s=1.0) as server:
        client = client_for(server.url_for_client)
        client.wait("EKF_STATUS_REPORT", lambda msg: msg.flags == 831)
        assert client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4).result == m.MAV_RESULT_ACCEPTED
        assert client.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == m.MAV_RESULT_ACCEPTED
        x, y = round(server.autopilot.start[0] * 1e7), round(server.autopilot.start[1] * 1e7)
        client.conn.mav.set_position_target_global_int_send(0, 1, 1, m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, x, y, -3.0, *[0.0] * 8)
        client.wait("GLOBAL_POSITION_INT", lambda msg: msg.relative_alt < -2900)
        sensor = client.wait("DISTANCE_SENSOR")
        assert 2650 < sensor.current_distance < 2750


def test_auto_flies_each_waypoint_at_its_depth_and_holds_the_last_in_auto(make_gcs: MakeGcs) -> None:
    """ArduSub's AUTO (mode_auto.cpp, commands_logic.cpp): each NAV_WAYPOINT at its altitude above home (minus the depth), reached
    within WPNAV_RADIUS in 3-D ("Reached command #N", MISSION_ITEM_REACHED); after the last, the point and its depth held in AUTO,
    its end said only by MISSION_CURRENT (COMPLETE)."""
    gcs = armed_in(make_gcs, "ALT_HOLD")
    lat, lon = gcs.north(10.0)
    assert upload(gcs, [item(gcs, 0), item(gcs, 1, lat, lon, -3.0), item(gcs, 2, *gcs.north(20.0), -6.0)])[-1].type == m.MAV_MISSION_ACCEPTED
    assert gcs.set_mode("AUTO") == m.MAV_RESULT_ACCEPTED
    gcs.run(120.0, step=0.5)
    said = gcs.log
    assert [r.seq for r in said if r.get_type() == "MISSION_ITEM_REACHED"] == [1, 2]
    assert [t for t in gcs.texts(said) if "command" in t or "Complete" in t] == ["Reached command #1", "Reached command #2"]
    current = gcs.last("MISSION_CURRENT")
    assert (current.seq, current.mission_state, gcs.ap.mode) == (2, m.MISSION_STATE_COMPLETE, "AUTO")
    assert abs(depth(gcs) - 6.0) < 0.2 and gcs.ap.vehicle.distance_to(*gcs.north(20.0)) < 1.0 and gcs.ap.vehicle.speed_m_s < 0.05


def test_an_item_rewritten_in_auto_is_flown_as_it_began_until_mission_set_current(make_gcs: MakeGcs) -> None:
    """ArduSub has no mission change detection: AP_Mission runs its cached command, so a partial write of the item being flown
    changes nothing until MISSION_SET_CURRENT starts it again (AP_Mission::set_current_cmd)."""
    gcs = armed_in(make_gcs, "ALT_HOLD")
    far = gcs.north(60.0)
    assert upload(gcs, [item(gcs, 0), item(gcs, 1, *far, -10.0)])[-1].type == m.MAV_MISSION_ACCEPTED
    assert gcs.set_mode("AUTO") == m.MAV_RESULT_ACCEPTED
    gcs.run(5.0, step=0.5)
    gcs.send(gcs.mav.mission_write_partial_list_encode(1, 1, 1, 1, 0))
    gcs.send(item(gcs, 1, *far, -4.0))
    gcs.run(30.0, step=0.5)
    assert depth(gcs) > 8.0  # still diving to the 10 m it began with
    gcs.send(gcs.mav.mission_set_current_encode(1, 1, 1))
    gcs.run(30.0, step=0.5)
    assert abs(depth(gcs) - 4.0) < 0.3
