"""The simulated autopilots' fence and rally stores: what each firmware takes, refuses and reads back (executive.sim.zone_stores)."""

from __future__ import annotations

import math
from collections.abc import Callable

from executive.sim.registry import make_autopilot
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage, mavlink
from sim_support import Gcs

M = mavlink
FENCE, RALLY = M.MAV_MISSION_TYPE_FENCE, M.MAV_MISSION_TYPE_RALLY
MakeGcs = Callable[..., Gcs]


def upload(gcs: Gcs, mission_type: int, items: list[tuple[int, float, float, float, float, int]]) -> list[MAVLinkMessage]:
    """MISSION_COUNT then each item asked for, (command, param1, lat, lon, alt, frame); every reply."""
    replies = gcs.send(gcs.mav.mission_count_encode(1, 1, len(items), mission_type))
    for seq, (command, p1, lat, lon, alt, frame) in enumerate(items):
        item = gcs.mav.mission_item_int_encode(1, 1, seq, frame, command, 0, 0, p1, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), alt, mission_type)
        replies += gcs.send(item)
    return replies


def read_back(gcs: Gcs, mission_type: int) -> list[MAVLinkMessage]:
    [count] = [m for m in gcs.send(gcs.mav.mission_request_list_encode(1, 1, mission_type)) if m.get_type() == "MISSION_COUNT"]
    return [gcs.send(gcs.mav.mission_request_int_encode(1, 1, seq, mission_type))[0] for seq in range(count.count)]


def square(command: int, count: int = 4) -> list[tuple[int, float, float, float, float, int]]:
    corners = [(-35.3631, 149.1649), (-35.3630, 149.1649), (-35.3630, 149.1650), (-35.3631, 149.1650)][:count]
    return [(command, float(count), lat, lon, 0.0, M.MAV_FRAME_GLOBAL) for lat, lon in corners]


def test_ardupilot_takes_a_fence_and_reads_it_back_with_frame_0_z_0_and_autocontinue_0(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    sent = [*square(5002), (5004, 8.0, -35.3628, 149.1650, 12.0, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)]
    assert upload(gcs, FENCE, sent)[-1].type == M.MAV_MISSION_ACCEPTED
    back = read_back(gcs, FENCE)
    assert [(m.command, m.param1, m.frame, m.z, m.autocontinue, m.mission_type) for m in back] == [
        *[(5002, 4.0, 0, 0.0, 0, FENCE)] * 4, (5004, 8.0, 0, 0.0, 0, FENCE)
    ]  # fmt: skip
    assert gcs.ap.mission.count == 0  # the flight plan untouched


def test_ardupilot_refuses_a_bad_fence_when_the_upload_ends_and_keeps_the_old_one(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    upload(gcs, FENCE, square(5001))
    replies = upload(gcs, FENCE, [*square(5002, 3), (5003, 0.0, -35.36, 149.16, 0.0, 0)])
    assert replies[-1].type == M.MAV_MISSION_ERROR  # AC_PolyFence_loader::validate_fence: a circle of radius 0
    assert [m.text for m in replies if m.get_type() == "STATUSTEXT"] == ["Non-positive circle radius", "Fence validation failed"]
    assert [m.command for m in read_back(gcs, FENCE)] == [5001] * 4


def test_ardupilot_keeps_a_rally_points_altitude_in_whole_metres(make_gcs: MakeGcs) -> None:
    gcs = make_gcs(ekf_ready=True)
    assert upload(gcs, RALLY, [(5100, 0.0, -35.3634, 149.1652, 30.7, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)])[-1].type == M.MAV_MISSION_ACCEPTED
    [back] = read_back(gcs, RALLY)
    assert (back.z, back.frame) == (30.0, M.MAV_FRAME_GLOBAL_RELATIVE_ALT)
    assert upload(gcs, RALLY, [(16, 0.0, -35.3634, 149.1652, 0.0, 3)])[-1].type == M.MAV_MISSION_UNSUPPORTED


def test_px4_refuses_a_polygon_of_two_corners_at_its_item_and_reads_back_in_int_frames() -> None:
    clock = ManualClock()
    gcs = Gcs(make_autopilot("rover", clock, autopilot="px4", ekf_ready_after_s=0.0), clock)
    clock.advance(2.0)  # booted
    gcs.update()
    replies = upload(gcs, FENCE, square(5001, 2))
    assert replies[-1].type == M.MAV_MISSION_ERROR and "Fence: too few vertices" in [m.text for m in replies if m.get_type() == "STATUSTEXT"]
    assert upload(gcs, FENCE, square(5001))[-1].type == M.MAV_MISSION_ACCEPTED
    assert {m.frame for m in read_back(gcs, FENCE)} == {M.MAV_FRAME_GLOBAL_INT}
    upload(gcs, RALLY, [(5100, 0.0, -35.3634, 149.1652, 30.5, M.MAV_FRAME_GLOBAL_RELATIVE_ALT)])
    [back] = read_back(gcs, RALLY)
    assert (back.frame, back.z) == (M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 30.5) and not math.isnan(back.z)
