"""The simulated ArduPilot's side of the mission protocol, and AUTO, at the message level: no sockets, a manual clock."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Gcs

MakeGcs = Callable[..., "Gcs"]
M_PER_DEG_LAT = 111_319.49


def item(gcs: Gcs, seq: int, lat: float = 0.0, lon: float = 0.0, alt: float = 0.0, **fields: float) -> MAVLinkMessage:
    """A MISSION_ITEM_INT from the ground station: a NAV_WAYPOINT in the relative-altitude frame unless ``fields`` say otherwise."""
    f = {"frame": m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, "command": m.MAV_CMD_NAV_WAYPOINT, "param1": 0.0, "param2": 0.0, "mission_type": 0} | fields
    x, y = fields.get("x", round(lat * 1e7)), fields.get("y", round(lon * 1e7))
    return gcs.mav.mission_item_int_encode(
        1, 1, seq, f["frame"], f["command"], 0, 1, f["param1"], f["param2"], 0.0, 0.0, x, y, alt, f["mission_type"]
    )


def kinds(messages: list[MAVLinkMessage]) -> list[str]:
    return [msg.get_type() for msg in messages]


def upload(gcs: Gcs, items: list[MAVLinkMessage]) -> list[MAVLinkMessage]:
    """The ground station's side of an upload, answering each request; returns the vehicle's last replies."""
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    while replies and replies[-1].get_type() == "MISSION_REQUEST":
        replies = gcs.send(items[replies[-1].seq])
    return replies


def square(gcs: Gcs, side_m: float = 10.0) -> list[MAVLinkMessage]:
    """Home and three corners of a square north-east of the start."""
    lat0, lon0 = gcs.ap.start
    dlat, dlon = side_m / M_PER_DEG_LAT, side_m / (M_PER_DEG_LAT * math.cos(math.radians(lat0)))
    corners = [(lat0 + dlat, lon0), (lat0 + dlat, lon0 + dlon), (lat0, lon0 + dlon)]
    return [item(gcs, 0, lat0, lon0), *(item(gcs, seq, lat, lon) for seq, (lat, lon) in enumerate(corners, start=1))]


def test_upload_is_driven_by_the_vehicle_with_mission_request(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs)
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    for seq in range(len(items)):
        # ArduPilot asks with the float-era MISSION_REQUEST and takes MISSION_ITEM_INT for an answer
        assert kinds(replies) == ["MISSION_REQUEST"]
        assert (replies[0].seq, replies[0].target_system, replies[0].target_component) == (seq, 255, 190)
        replies = gcs.send(items[seq])
    assert kinds(replies) == ["STATUSTEXT", "MISSION_ACK"]
    assert gcs.texts(replies) == ["Flight plan received"]
    assert (replies[1].type, replies[1].target_system, replies[1].target_component) == (m.MAV_MISSION_ACCEPTED, 255, 190)
    assert gcs.ap.mission.count == 4 and not gcs.ap.mission.receiving


def test_an_item_out_of_sequence_is_refused_and_the_upload_goes_on(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs)
    gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    replies = gcs.send(items[1])
    assert (kinds(replies), replies[0].type) == (["MISSION_ACK"], m.MAV_MISSION_INVALID_SEQUENCE)
    assert [r.seq for r in gcs.send(items[0])] == [1]  # still wanted item 0; now item 1
    assert gcs.send(items[0])[0].type == m.MAV_MISSION_INVALID_SEQUENCE  # a duplicate changes nothing either
    assert upload(gcs, items)[-1].type == m.MAV_MISSION_ACCEPTED
    late = gcs.send(items[3])  # after the upload: the vehicle is no longer receiving
    assert (kinds(late), late[0].type) == (["MISSION_ACK"], m.MAV_MISSION_ERROR)


def test_the_vehicle_asks_again_then_cancels_a_stalled_upload(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs)
    gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    gcs.send(items[0])
    out = gcs.run(2.5)
    assert [r.seq for r in gcs.of_type(out, "MISSION_REQUEST")] == [1, 1]  # once a second
    out = gcs.run(6.0)
    acks = gcs.of_type(out, "MISSION_ACK")
    assert [a.type for a in acks] == [m.MAV_MISSION_OPERATION_CANCELLED]
    assert "Mission upload timeout" in gcs.texts(out)
    assert gcs.send(items[1])[0].type == m.MAV_MISSION_ERROR
    assert gcs.ap.mission.count == 1  # cut to the new count, then only item 0 arrived


def test_download_gives_home_as_item_0_and_items_as_stored(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    lat, lon = gcs.north(10.0)
    upload(gcs, [item(gcs, 0, 1.0, 2.0, 3.0), item(gcs, 1, lat, lon, 12.345, param1=2.7, param2=5.0)])
    count = gcs.send(gcs.mav.mission_request_list_encode(1, 1, 0))
    assert (kinds(count), count[0].count, count[0].target_system) == (["MISSION_COUNT"], 2, 255)
    home = gcs.send(gcs.mav.mission_request_int_encode(1, 1, 0, 0))[0]
    # item 0 is the vehicle's own home, whatever was uploaded there
    assert (home.x, home.y, home.z, home.frame, home.command) == (round(gcs.ap.home[0] * 1e7), round(gcs.ap.home[1] * 1e7), 0.0, 0, 16)
    wp = gcs.send(gcs.mav.mission_request_int_encode(1, 1, 1, 0))[0]
    assert (wp.get_type(), wp.seq, wp.x, wp.y, wp.frame, wp.autocontinue) == ("MISSION_ITEM_INT", 1, round(lat * 1e7), round(lon * 1e7), 3, 1)
    assert (wp.z, wp.param1, wp.param2) == (pytest.approx(12.34), 2.0, 0.0)  # cm, whole seconds, no acceptance radius kept
    beyond = gcs.send(gcs.mav.mission_request_int_encode(1, 1, 5, 0))
    assert kinds(beyond) == ["MISSION_COUNT", "MISSION_ACK"] and beyond[1].type == m.MAV_MISSION_ERROR


@pytest.mark.parametrize(
    ("fields", "result"),
    [
        ({"command": m.MAV_CMD_NAV_TAKEOFF}, m.MAV_MISSION_UNSUPPORTED),
        ({"x": 91 * 10**7}, m.MAV_MISSION_INVALID_PARAM5_X),
        ({"y": -181 * 10**7}, m.MAV_MISSION_INVALID_PARAM6_Y),
        ({"param1": math.nan}, m.MAV_MISSION_INVALID_PARAM1),
        ({"frame": m.MAV_FRAME_LOCAL_NED}, m.MAV_MISSION_UNSUPPORTED_FRAME),
    ],
)
def test_a_bad_item_ends_the_upload_with_its_reason(make_gcs: MakeGcs, fields: dict[str, float], result: int) -> None:
    gcs = make_gcs(ekf_ready=True)
    gcs.send(gcs.mav.mission_count_encode(1, 1, 3, 0))
    gcs.send(item(gcs, 0))
    replies = gcs.send(item(gcs, 1, *gcs.north(5.0), **fields))
    assert (kinds(replies), replies[0].type) == (["MISSION_ACK"], result)
    assert not gcs.ap.mission.receiving


def test_uploads_refused_whole(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, 701, 0))
    assert (replies[0].type, gcs.texts(replies)) == (m.MAV_MISSION_NO_SPACE, ["Only 700 items are supported"])
    assert gcs.send(gcs.mav.mission_count_encode(1, 1, 2, m.MAV_MISSION_TYPE_ALL))[0].type == m.MAV_MISSION_UNSUPPORTED
    gcs.send(gcs.mav.mission_count_encode(1, 1, 2, 0))
    other = gcs.mav.mission_count_encode(1, 1, 2, 0)
    other.pack(m.MAVLink(None, srcSystem=254, srcComponent=190))  # another ground station, while we upload
    replies = gcs.ap.handle(other)
    assert (replies[0].type, replies[0].target_system) == (m.MAV_MISSION_DENIED, 254)
    assert gcs.send(gcs.mav.mission_request_list_encode(1, 1, 0))[0].type == m.MAV_MISSION_DENIED  # no reading mid-upload


def test_clear_all(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, square(gcs))
    replies = gcs.send(gcs.mav.mission_clear_all_encode(1, 1, 0))
    assert (kinds(replies), replies[0].type) == (["MISSION_ACK"], m.MAV_MISSION_ACCEPTED)
    assert gcs.send(gcs.mav.mission_request_list_encode(1, 1, 0))[0].count == 0
    assert gcs.set_mode("AUTO") == m.MAV_RESULT_FAILED


def test_clear_is_refused_while_the_mission_runs_armed(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, square(gcs))
    gcs.arm()
    gcs.set_mode("AUTO")
    gcs.run(1.0)
    assert gcs.send(gcs.mav.mission_clear_all_encode(1, 1, 0))[0].type == m.MAV_MISSION_ERROR
    assert gcs.ap.mission.count == 4


def test_set_current(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, square(gcs))
    replies = gcs.send(gcs.mav.mission_set_current_encode(1, 1, 2))
    assert (kinds(replies), replies[0].seq, replies[0].total) == (["MISSION_CURRENT"], 2, 3)
    assert gcs.send(gcs.mav.mission_set_current_encode(1, 1, 9)) == []  # not held: ignored, no ack exists
    assert gcs.ap.mission.current_seq == 2
    replies = gcs.command(m.MAV_CMD_DO_SET_MISSION_CURRENT, 3)
    assert (kinds(replies), replies[0].result, replies[1].seq) == (["COMMAND_ACK", "MISSION_CURRENT"], m.MAV_RESULT_ACCEPTED, 3)
    assert gcs.ack(m.MAV_CMD_DO_SET_MISSION_CURRENT, 9).result == m.MAV_RESULT_FAILED


def test_mission_current_is_streamed(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    current = gcs.of_type(gcs.run(1.0), "MISSION_CURRENT")
    assert len(current) == 4 and (current[-1].seq, current[-1].total, current[-1].mission_state) == (0, 0, m.MISSION_STATE_NO_MISSION)
    upload(gcs, square(gcs))
    latest = gcs.of_type(gcs.run(0.5), "MISSION_CURRENT")[-1]
    assert (latest.total, latest.mission_state, latest.mission_mode) == (3, m.MISSION_STATE_NOT_STARTED, 0)


def test_auto_drives_the_mission_then_stops_and_stays_in_auto(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs)
    upload(gcs, items)
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    assert gcs.ack(m.MAV_CMD_MISSION_START).result == m.MAV_RESULT_ACCEPTED
    assert gcs.ap.mode == "AUTO"
    out = gcs.run(15.0)
    active = gcs.of_type(out, "MISSION_CURRENT")[-1]
    assert (active.mission_state, active.mission_mode) == (m.MISSION_STATE_ACTIVE, 1)
    out += gcs.run(45.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [1, 2, 3]
    texts = gcs.texts(out)
    assert [t for t in texts if t.startswith("Reached waypoint")] == ["Reached waypoint #1", "Reached waypoint #2", "Reached waypoint #3"]
    assert texts[-1] == "Mission Complete"
    last_corner = (items[3].x / 1e7, items[3].y / 1e7)
    assert gcs.ap.vehicle.distance_to(*last_corner) <= 1.0
    gcs.run(10.0)
    assert gcs.ap.mode == "AUTO" and gcs.ap.vehicle.distance_to(*last_corner) <= 1.0  # ArduRover holds in AUTO (MIS_DONE_BEHAVE=0)
    done = gcs.of_type(gcs.log, "MISSION_CURRENT")[-1]
    assert (done.seq, done.mission_state) == (3, m.MISSION_STATE_COMPLETE)


def test_leaving_auto_stops_the_mission_and_auto_resumes_it(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, square(gcs))
    gcs.arm()
    gcs.set_mode("AUTO")
    out = gcs.run(9.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [1]
    gcs.set_mode("HOLD")
    paused = gcs.of_type(gcs.run(1.0), "MISSION_CURRENT")[-1]
    assert (paused.seq, paused.mission_state, paused.mission_mode) == (2, m.MISSION_STATE_NOT_STARTED, 0)
    gcs.set_mode("AUTO")
    out = gcs.run(40.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [2, 3]


def _drive_auto(gcs: Gcs, items: list[MAVLinkMessage], seconds: float) -> list[tuple[float, float, float]]:
    """Upload, arm, AUTO; then (north m, east m, speed) of the vehicle every 0.1 s for ``seconds``."""
    upload(gcs, items)
    gcs.arm()
    gcs.set_mode("AUTO")
    track = []
    for _ in range(round(seconds / 0.1)):
        gcs.run(0.1)
        north, east = gcs.ap.vehicle.north_east_m
        track.append((north, east, gcs.ap.vehicle.speed_m_s))
    return track


def test_auto_drives_through_a_waypoint_followed_by_another_without_stopping(make_gcs: MakeGcs) -> None:
    # ModeAuto::do_nav_wp gives AR_WPNav the next waypoint: a "fast waypoint", its corner cut within WP_RADIUS
    gcs = make_gcs(ekf_ready=True)
    track = _drive_auto(gcs, square(gcs, side_m=30.0), 60.0)
    corners = [(30.0, 0.0), (30.0, 30.0)]
    for corner in corners:
        nearest = min(range(len(track)), key=lambda i: math.dist(track[i][:2], corner))
        assert math.dist(track[nearest][:2], corner) <= 2.0  # WP_RADIUS
        assert track[nearest][2] >= 1.2  # through the corner at speed (cruise 2 m/s), not stopped
    assert [t for t in gcs.texts(gcs.log) if t.startswith("Reached")] == ["Reached waypoint #1", "Reached waypoint #2", "Reached waypoint #3"]
    assert math.dist(track[-1][:2], (0.0, 30.0)) <= 1.0 and track[-1][2] < 1e-3  # the last one is a stop


def test_auto_stops_at_a_waypoint_with_a_hold_time_and_waits_it_out(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs, side_m=30.0)
    items[1] = item(gcs, 1, items[1].x / 1e7, items[1].y / 1e7, param1=5.0)  # hold 5 s at the first corner
    track = _drive_auto(gcs, items, 30.0)
    stopped_there = [i for i, (n, e, v) in enumerate(track) if math.dist((n, e), (30.0, 0.0)) <= 1.0 and v < 0.05]
    assert stopped_there and (stopped_there[-1] - stopped_there[0]) * 0.1 >= 4.5
    assert "Reached waypoint #1. Loiter for 5 seconds" in gcs.texts(gcs.log)
    reached = gcs.of_type(gcs.log, "MISSION_ITEM_REACHED")
    assert [msg.seq for msg in reached][:1] == [1]


def test_auto_stops_at_a_loiter_unlimited_and_stays_until_the_mission_is_set_on(make_gcs: MakeGcs) -> None:
    """Rover/mode_auto.cpp: NAV_LOITER_UNLIM is do_nav_wp(cmd, always_stop_at_destination) and verify_loiter_unlimited never
    completes: the waypoint before it is driven through toward it, no MISSION_ITEM_REACHED for it, the mission goes on only
    at a MISSION_SET_CURRENT."""
    gcs = make_gcs(ekf_ready=True)
    items = square(gcs, side_m=30.0)
    items[2] = item(gcs, 2, items[2].x / 1e7, items[2].y / 1e7, command=m.MAV_CMD_NAV_LOITER_UNLIM)
    track = _drive_auto(gcs, items, 90.0)
    first = min(range(len(track)), key=lambda i: math.dist(track[i][:2], (30.0, 0.0)))
    assert track[first][2] >= 1.2  # through the corner before it at speed
    assert math.dist(track[-1][:2], (30.0, 30.0)) <= 1.0 and track[-1][2] < 0.05  # stopped there, still after 90 s
    assert [msg.seq for msg in gcs.of_type(gcs.log, "MISSION_ITEM_REACHED")] == [1]
    assert "Reached waypoint #2" in gcs.texts(gcs.log) and gcs.ap.mode == "AUTO" and gcs.ap.mission.current_seq == 2
    gcs.send(gcs.mav.mission_set_current_encode(1, 1, 3))
    out = gcs.run(30.0)
    assert [msg.seq for msg in gcs.of_type(out, "MISSION_ITEM_REACHED")] == [3]
    assert gcs.ap.vehicle.distance_to(items[3].x / 1e7, items[3].y / 1e7) <= 1.0


def test_a_speed_change_in_auto_keeps_the_corner_driven_through(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, square(gcs, side_m=30.0))
    gcs.arm()
    gcs.set_mode("AUTO")
    gcs.run(3.0)
    assert gcs.ack(m.MAV_CMD_DO_CHANGE_SPEED, 1, 1.5).result == m.MAV_RESULT_ACCEPTED
    nearest = (math.inf, 0.0)
    for _ in range(300):
        gcs.run(0.1)
        north, east = gcs.ap.vehicle.north_east_m
        nearest = min(nearest, (math.dist((north, east), (30.0, 0.0)), gcs.ap.vehicle.speed_m_s))
    distance, speed = nearest
    assert distance <= 2.0 and speed >= 1.0  # through the first corner at the new speed, not stopped there


def test_a_skid_steered_vehicle_stops_to_pivot_at_a_sharp_corner_and_drives_through_a_gentle_one(make_gcs: MakeGcs) -> None:
    # AR_WPNav: no next destination when a pivot would activate there (the turn is sharper than WP_PIVOT_ANGLE, 60°)
    gcs = make_gcs("bunker", ekf_ready=True)
    lat0, lon0 = gcs.ap.start
    dlat, dlon = 1.0 / M_PER_DEG_LAT, 1.0 / (M_PER_DEG_LAT * math.cos(math.radians(lat0)))
    gentle = (20.0, 0.0), (30.0, 5.0)  # north 20 m, then 27° right
    sharp = (30.0, 5.0), (30.0, 25.0)  # then 63° further right: east
    points = [gentle[0], gentle[1], sharp[1]]
    items = [item(gcs, 0, lat0, lon0), *(item(gcs, seq, lat0 + n * dlat, lon0 + e * dlon) for seq, (n, e) in enumerate(points, start=1))]
    track = _drive_auto(gcs, items, 90.0)

    def slowest_near(corner: tuple[float, float]) -> float:
        return min(v for n, e, v in track if math.dist((n, e), corner) <= 1.0)

    assert slowest_near(gentle[0]) >= 0.5  # driven through (cruise 1 m/s)
    assert slowest_near(sharp[0]) <= 0.2  # braked to a stop point there (the next leg starts on arrival, within 0.3 m)
    assert min(math.dist((n, e), sharp[0]) for n, e, _ in track) <= 0.3


RESTARTED = "Auto mission changed, restarted command"


def line_north(gcs: Gcs, count: int, spacing_m: float = 30.0) -> list[MAVLinkMessage]:
    """Home and ``count`` waypoints every ``spacing_m`` north of the start."""
    lat0, lon0 = gcs.ap.start
    return [item(gcs, 0, lat0, lon0), *(item(gcs, seq, lat0 + seq * spacing_m / M_PER_DEG_LAT, lon0) for seq in range(1, count + 1))]


def write_partial(gcs: Gcs, seq: int, items: list[MAVLinkMessage]) -> list[MAVLinkMessage]:
    """MISSION_WRITE_PARTIAL_LIST seq..seq, answered with ``items[seq]``; the vehicle's last replies."""
    replies = gcs.send(gcs.mav.mission_write_partial_list_encode(1, 1, seq, seq, 0))
    assert kinds(replies) == ["MISSION_REQUEST"] and replies[0].seq == seq
    return gcs.send(items[seq])


def test_any_write_to_the_mission_in_auto_restarts_the_waypoint_wherever_the_item_lies(make_gcs: MakeGcs) -> None:
    """As the real ArduRover did (tests/data/ardurover/mission-writes-in-auto-rover.tlog): driving to item 1, an identical
    rewrite of item 6 and an append of item 7, both past the three commands AP_Mission_ChangeDetector compares, each restart it."""
    gcs = make_gcs(ekf_ready=True)
    items = line_north(gcs, 6)
    upload(gcs, items)
    gcs.arm()
    gcs.set_mode("AUTO")
    gcs.run(2.0)
    write_partial(gcs, 6, items)
    gcs.run(0.5)
    assert gcs.texts(gcs.log).count(RESTARTED) == 1
    items.append(item(gcs, 7, items[6].x / 1e7 + 30.0 / M_PER_DEG_LAT, items[6].y / 1e7))
    write_partial(gcs, 7, items)
    gcs.run(0.5)
    assert gcs.texts(gcs.log).count(RESTARTED) == 2
    assert gcs.ap.mission.current_seq == 1  # the same waypoint, driven again from where the vehicle can stop


def test_each_item_written_restarts_the_waypoint_not_the_upload_as_a_whole(make_gcs: MakeGcs) -> None:
    """AP_Mission::write_cmd_to_storage moves the mission's change time at every item (home aside), and ModeAuto checks at
    every loop: the same 6 waypoints uploaded again in AUTO, an item per update, restart it 6 times."""
    gcs = make_gcs(ekf_ready=True)
    items = line_north(gcs, 6)
    upload(gcs, items)
    gcs.arm()
    gcs.set_mode("AUTO")
    gcs.run(2.0)
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), 0))
    while replies and replies[-1].get_type() == "MISSION_REQUEST":
        replies = gcs.send(items[replies[-1].seq])
        gcs.run(0.1)
    assert gcs.texts(gcs.log).count(RESTARTED) == 6


def test_a_write_noticed_with_a_new_current_command_is_taken_silently() -> None:
    """AP_Mission_ChangeDetector::check_for_mission_change returns ``cmds_changed && !curr_cmd_idx_changed``."""
    from executive.sim.ardupilot.mission_change import MissionChangeDetector

    detector = MissionChangeDetector()
    detector.start(changes=7, current=1)
    assert not detector.check(changes=7, current=1)  # nothing written
    assert detector.check(changes=8, current=1)  # written, the same command: restart
    assert not detector.check(changes=9, current=2)  # written as the mission moved on: taken in
    assert not detector.check(changes=9, current=3)  # the mission moved on alone
