"""drive: auto on the real PX4 (SIH standard_vtol, a70a558393), recorded: our reading of its mission protocol and AUTO.MISSION.

tests/data/px4/README.md says how each was made. The route: six waypoints 100 m apart at 30 m, flown as a multicopter.
"""

from __future__ import annotations

from pathlib import Path

from tlog_replay import PX4, Replay, records, through_reader

from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.geo import distance
from executive.world.state import MISSION_STATE_COMPLETE

AUTO = PX4 / "vtol-waypoints-auto.tlog"
FIRST_RUN = PX4 / "vtol-waypoints-auto-first-run.tlog"  # before the reader's fix: legs 2 and 4 counted done on an upload
KILLED = PX4 / "vtol-waypoints-auto-killed.tlog"
PAUSED = PX4 / "vtol-waypoints-auto-paused.tlog"
LINK_CUT = PX4 / "vtol-waypoints-auto-link-cut.tlog"
REFUSED = PX4 / "vtol-waypoints-auto-refused.tlog"
WINDOW = PX4 / "auto-mission-window.tlog"
LANDING_REQUIRED = PX4 / "auto-mission-landing-required.tlog"
ROUTE = [
    (-35.3623627, 149.1652300), (-35.3623627, 149.1663315), (-35.3632610, 149.1663315),
    (-35.3632610, 149.1674331), (-35.3623627, 149.1674331), (-35.3623627, 149.1685346),
]  # fmt: skip
HORIZON = 2  # limits.auto_horizon_legs of the recorded runs
PX4_SYSTEM = 7  # instance 6


def px4_side(path: Path, kind: str) -> list[tuple[float, object]]:
    return [(t, msg) for t, msg in records(path) if msg.get_type() == kind and msg.get_srcSystem() == PX4_SYSTEM]


def ours(path: Path, kind: str) -> list[tuple[float, object]]:
    return [(t, msg) for t, msg in records(path) if msg.get_type() == kind and msg.get_srcSystem() != PX4_SYSTEM]


def test_the_recordings_are_small() -> None:
    assert all(path.stat().st_size < 40_000 for path in (AUTO, FIRST_RUN, KILLED, PAUSED, LINK_CUT, REFUSED, WINDOW, LANDING_REQUIRED))


def test_each_item_is_followed_in_order_and_an_uploads_item_65535_is_not_read_as_past_the_leg() -> None:
    """PX4 says MISSION_CURRENT seq 65535 between a window's upload and its navigator's answer (mavlink_mission.cpp): read as the
    leg past, it counted legs 2 and 4 done on the first real run. Our reader follows 0..5 and each item is reported reached
    within NAV_ACC_RAD (10 m) of its waypoint, as the firmware counts it."""
    assert any(msg.seq == 0xFFFF for _, msg in px4_side(FIRST_RUN, "MISSION_CURRENT"))
    blackboard.reset()
    bb = blackboard.reader("px4 replay", ["/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/position"])
    seqs: list[int] = []
    reached_at: dict[int, float] = {}
    for _ in through_reader(FIRST_RUN, "vtol"):
        current, reached, position = bb.get("/vehicle/mission_current"), bb.get("/vehicle/mission_reached"), bb.get("/vehicle/position")
        if current is not None and (not seqs or seqs[-1] != current.seq):
            seqs.append(current.seq)
        if reached is not None and reached.highest not in reached_at and position is not None:
            reached_at[reached.highest] = distance(position.lat, position.lon, *ROUTE[reached.highest])
    assert seqs == [0, 1, 2, 3, 4, 5]
    assert sorted(reached_at) == [0, 1, 2, 3, 4] and max(reached_at.values()) < 12.0, reached_at


def test_px4_never_held_more_than_the_horizon_past_the_item_it_flew_to() -> None:
    current = 0
    for _, msg in sorted(px4_side(AUTO, "MISSION_CURRENT") + ours(AUTO, "MISSION_COUNT"), key=lambda r: r[0]):
        if msg.get_type() == "MISSION_CURRENT" and msg.seq != 0xFFFF:
            current = msg.seq
        elif msg.get_type() == "MISSION_COUNT":
            assert msg.count - 1 - current <= HORIZON, (msg.count, current)
    assert [msg.count for _, msg in ours(AUTO, "MISSION_COUNT")] == [3, 4, 5, 6]  # the window again, one more each leg


def test_killed_px4_flies_what_it_holds_then_hovers_in_auto_loiter_and_the_executive_judges_it_the_autopilots() -> None:
    """kill -9 on leg 2 (55 m from waypoint 2), PX4 holding waypoints 1-4: COMPLETE at item 3, Commander's AUTO.LOITER
    (Commander.cpp), a hover within 10 m of waypoint 4 for 100 s; never within 90 m of waypoint 5."""
    held = max(msg.count for _, msg in ours(KILLED, "MISSION_COUNT"))
    assert held == 4
    end = [msg for _, msg in px4_side(KILLED, "MISSION_CURRENT") if msg.mission_state == MISSION_STATE_COMPLETE]
    assert end and end[0].seq == held - 1
    positions = [msg for _, msg in px4_side(KILLED, "GLOBAL_POSITION_INT")]
    assert min(distance(p.lat * 1e-7, p.lon * 1e-7, *ROUTE[held]) for p in positions) > 90.0
    after = positions[-150:]  # the last 75 s
    assert all(distance(p.lat * 1e-7, p.lon * 1e-7, *ROUTE[held - 1]) < 10.5 for p in after)
    replay = Replay(vehicle="vtol").play(KILLED)
    assert replay.values("/vehicle/mode")[-2:] == ["AUTO.MISSION", "AUTO.LOITER"]
    assert replay.values("/vehicle/mode_set_by")[-1] == "autopilot"


def test_mis_tko_land_req_is_read_as_px4_sends_it_and_the_refused_run_sent_nothing() -> None:
    blackboard.reset()
    bb = blackboard.reader("px4 replay", ["/vehicle/params"])
    for _ in through_reader(REFUSED, "vtol"):
        pass
    assert bb.get("/vehicle/params")["MIS_TKO_LAND_REQ"] == 2.0  # an INT32's bytes in the float (mavlink_parameters.cpp)
    assert not ours(REFUSED, "MISSION_COUNT")
    assert not [msg for _, msg in ours(REFUSED, "COMMAND_LONG") if msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM]


def test_px4_refuses_auto_mission_for_a_mission_without_the_landing_its_vtol_default_asks_for() -> None:
    """MIS_TKO_LAND_REQ 2 (rc.vtol_defaults): two waypoints ACCEPTED as an upload, MISSION_CURRENT NO_MISSION, AUTO.MISSION
    TEMPORARILY_REJECTED (FeasibilityChecker.cpp checkTakeoffLandAvailable): what the pre-flight check spares the vehicle."""
    assert [msg.type for _, msg in px4_side(LANDING_REQUIRED, "MISSION_ACK")] == [mavlink.MAV_MISSION_ACCEPTED]
    last = px4_side(LANDING_REQUIRED, "MISSION_CURRENT")[-1][1]
    assert (last.total, last.mission_state) == (2, mavlink.MISSION_STATE_NO_MISSION)
    acks = [msg.result for _, msg in px4_side(LANDING_REQUIRED, "COMMAND_ACK") if msg.command == mavlink.MAV_CMD_DO_SET_MODE]
    assert acks == [mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_TEMPORARILY_REJECTED]


def test_in_auto_mission_a_whole_upload_keeps_the_item_set_current_is_honoured_and_a_partial_write_gets_no_answer() -> None:
    partial = ours(WINDOW, "MISSION_WRITE_PARTIAL_LIST")[0][0]
    answers = [r for r in records(WINDOW) if r[1].get_srcSystem() == PX4_SYSTEM and partial < r[0] < partial + 2.0]
    assert not [msg for _, msg in answers if msg.get_type().startswith("MISSION_") and msg.get_type() != "MISSION_CURRENT"]
    timeline = sorted(px4_side(WINDOW, "MISSION_CURRENT") + ours(WINDOW, "MISSION_COUNT") + ours(WINDOW, "MISSION_SET_CURRENT"), key=lambda r: r[0])
    seen: list[tuple[str, int]] = []
    for _, msg in timeline:
        kind = msg.get_type()
        if kind == "MISSION_CURRENT" and msg.seq != 0xFFFF and msg.mission_state == mavlink.MISSION_STATE_ACTIVE:
            if not seen or seen[-1] != ("current", msg.seq):
                seen.append(("current", msg.seq))
        elif kind == "MISSION_COUNT":
            seen.append(("upload", msg.count))
        elif kind == "MISSION_SET_CURRENT":
            seen.append(("set", msg.seq))
    # in flight: item 1 kept through a 4-item upload; SET_CURRENT 2 taken; item 3 kept through a 5-item upload
    assert seen[seen.index(("upload", 4)) - 1 : seen.index(("upload", 4)) + 2] == [("current", 1), ("upload", 4), ("current", 1)]
    assert seen[seen.index(("set", 2)) + 1] == ("current", 2)
    assert seen[seen.index(("upload", 5)) - 1 : seen.index(("upload", 5)) + 2] == [("current", 3), ("upload", 5), ("current", 3)]


def route_time(path: Path, mode: tuple[int, int], radius_m: float = 70.0) -> float:
    """Vehicle time (time_boot_ms) from the first heartbeat in ``mode`` (main, sub) to within ``radius_m`` of the last waypoint."""
    start, last_boot = None, 0.0
    for _, msg in records(path):
        if msg.get_srcSystem() != PX4_SYSTEM:
            continue
        if msg.get_type() == "HEARTBEAT" and start is None and (msg.custom_mode >> 16 & 0xFF, msg.custom_mode >> 24 & 0xFF) == mode:
            start = last_boot
        if msg.get_type() == "GLOBAL_POSITION_INT":
            last_boot = msg.time_boot_ms / 1000.0
            if start is not None and distance(msg.lat * 1e-7, msg.lon * 1e-7, *ROUTE[-1]) <= radius_m:
                return last_boot - start
    raise AssertionError(f"{path.name}: never within {radius_m} m of the last waypoint")


def test_drive_auto_is_as_fast_as_px4s_own_auto_mission_over_the_route() -> None:
    """From AUTO.MISSION to within the acceptance radius (70 m) of the last waypoint: 134.2 s supervised (4 uploads of the window),
    135.2 s for PX4's own mission of the whole route; GUIDED (OFFBOARD) 60.0 s, on a shorter path (each leg ends 70 m short)."""
    supervised, own = route_time(AUTO, (4, 4)), route_time(PX4 / "vtol-waypoints-px4-own-auto.tlog", (4, 4))
    guided = route_time(PX4 / "vtol-waypoints-guided.tlog", (6, 0))
    assert supervised / own <= 1.02, (supervised, own)
    assert guided < supervised, (guided, supervised)


def test_paused_px4_hovers_and_resumed_goes_on_with_the_leg() -> None:
    """ctl pause on leg 3: AUTO.LOITER (a hover, 35 s); ctl resume: MISSION_SET_CURRENT 2, AUTO.MISSION 1 s later, item 2 next."""
    replay = Replay(vehicle="vtol").play(PAUSED)
    assert replay.values("/vehicle/mode")[-4:] == ["AUTO.MISSION", "AUTO.LOITER", "AUTO.MISSION", "AUTO.LOITER"]
    assert set(replay.values("/vehicle/mode_set_by")) <= {None, "us", "autopilot"}  # no mode change a person's
    resumed = ours(PAUSED, "MISSION_SET_CURRENT")[-1]
    assert resumed[1].seq == 2
    after = [msg.seq for t, msg in px4_side(PAUSED, "MISSION_ITEM_REACHED") if t > resumed[0]]
    assert after[0] == 2


def test_after_a_link_cut_px4_says_complete_with_the_item_set_until_auto_mission_runs_and_the_route_goes_on_there() -> None:
    """Back from a 67 s cut on leg 2: PX4 had finished its horizon (COMPLETE at item 3, hovering 9 m from waypoint 4); the
    window uploaded, MISSION_SET_CURRENT 4 answered (4, COMPLETE) (mission_result.finished stays until AUTO.MISSION runs),
    then (4, ACTIVE) in AUTO.MISSION, and item 4 was flown to, not skipped (it was, before the fix: the simulated PX4 models it)."""
    set_at, seq = ours(LINK_CUT, "MISSION_SET_CURRENT")[-1][0], ours(LINK_CUT, "MISSION_SET_CURRENT")[-1][1].seq
    assert seq == 4
    after = [(msg.seq, msg.mission_state) for t, msg in px4_side(LINK_CUT, "MISSION_CURRENT") if t > set_at]
    assert after[0] == (4, MISSION_STATE_COMPLETE) and (4, mavlink.MISSION_STATE_ACTIVE) in after
    assert next(msg.seq for t, msg in px4_side(LINK_CUT, "MISSION_ITEM_REACHED") if t > set_at) == 4
