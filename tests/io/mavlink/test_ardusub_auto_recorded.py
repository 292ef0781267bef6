"""drive: auto on the real ArduSub, recorded: our reading of its MISSION_CURRENT, MISSION_ITEM_REACHED and mission end.

tests/data/ardusub/auv_survey-auto*.tlog (README there): real ArduSub SITL (4.7-dev) flying missions/auv_survey.yaml with
``drive: auto`` (its altitude leg at 12 m), run to COMPLETED, and once with the executive ``kill -9``ed as leg 2 began
(horizon 1: ArduSub held waypoints 1-3). Read through the executive's own reader and mission transfer.
"""

from __future__ import annotations

import math
from pathlib import Path

from tlog_replay import Replay as ModeReplay
from tlog_replay import records, through_reader

from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.geo import distance
from executive.world.state import MISSION_STATE_COMPLETE

DATA = Path(__file__).parents[2] / "data" / "ardusub"
COMPLETED = DATA / "auv_survey-auto.tlog"
KILLED = DATA / "auv_survey-auto-killed.tlog"
DEEP = DATA / "auv_survey-auto-deep-paused.tlog"
END_WITHOUT_POSITION = DATA / "mission-end-without-position.tlog"
#: missions/auv_survey.yaml's waypoints, the altitude leg flown at 12 m: (lat, lon, depth)
ROUTE = [(44.0951350, 9.8630000, 0.0), (44.0951350, 9.8633122, 5.0), (44.0953150, 9.8633122, 12.0), (44.0953150, 9.8630000, 8.0)]


class Replay:
    """The recording's vehicle side through our reader and mission transfer: each change of (MISSION_CURRENT seq, state), each
    new highest item reached with where the sub was (metres from the point, depth), and the vehicle's last position and mode."""

    def __init__(self, path: Path) -> None:
        keys = ["/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/mode", "/vehicle/position"]
        blackboard.reset()
        bb = blackboard.reader("ardusub replay", keys)
        self.currents: list[tuple[int, int]] = []
        self.reached: list[tuple[int, float, float]] = []
        self.texts: list[str] = []
        for msg in through_reader(path, "sub"):
            if msg.get_type() == "STATUSTEXT":
                self.texts.append(msg.text)
            current, reached, position = bb.get("/vehicle/mission_current"), bb.get("/vehicle/mission_reached"), bb.get("/vehicle/position")
            if current is not None and (not self.currents or self.currents[-1] != (current.seq, current.state)):
                self.currents.append((current.seq, current.state))
            if reached is not None and (not self.reached or self.reached[-1][0] != reached.highest) and position is not None:
                lat, lon, _ = ROUTE[reached.highest - 1]
                self.reached.append((reached.highest, distance(position.lat, position.lon, lat, lon), -position.alt_rel_m))
        self.mode, self.position = bb.get("/vehicle/mode"), bb.get("/vehicle/position")
        self.positions = [msg for _, msg in records(path) if msg.get_type() == "GLOBAL_POSITION_INT" and msg.get_srcComponent() == 1]


def test_the_recordings_are_small() -> None:
    assert all(path.stat().st_size < 100_000 for path in (COMPLETED, KILLED, DEEP))


def test_each_waypoint_is_reported_reached_at_its_position_and_depth() -> None:
    """ArduSub counts a waypoint within WPNAV_RADIUS (2 m) in 3-D (AC_WPNav): its word is on position AND depth. Items 1-3 were
    reported 0.15-0.37 m from the point at their depths; the last one is the executive's to judge, then it surfaced."""
    replay = Replay(COMPLETED)
    assert [seq for seq, _, _ in replay.reached] == [1, 2, 3]
    for seq, metres, depth in replay.reached:
        assert metres < 0.5 and abs(depth - ROUTE[seq - 1][2]) < 0.2, (seq, metres, depth)
    driving = [seq for seq, state in replay.currents if state == mavlink.MISSION_STATE_ACTIVE]
    assert driving == [1, 2, 3, 4]  # MISSION_CURRENT only forward, to the last item
    assert "Flight plan received" in replay.texts and replay.mode == "POSHOLD"  # surfaced and held at the end (SURFACE -> ALT_HOLD -> POSHOLD)


def test_killed_the_real_sub_holds_position_and_depth_at_the_end_of_its_horizon() -> None:
    """The executive killed as leg 2 began (horizon 1: items 1-3 held): ArduSub flew to waypoint 3 at 12 m and its mission
    COMPLETED there (MISSION_CURRENT 3, state 5: no STATUSTEXT, Sub::exit_mission says nothing), then held it in AUTO
    (ModeAuto::auto_loiter_start): under 0.1 m/s within 0.5 m of the point and 0.1 m of its depth; waypoint 4 never approached."""
    replay = Replay(KILLED)
    assert [seq for seq, _, _ in replay.reached] == [1, 2, 3]
    assert replay.currents[-1] == (3, MISSION_STATE_COMPLETE) and replay.mode == "AUTO"
    assert not any("Complete" in text for text in replay.texts)
    lat, lon, depth = ROUTE[2]
    last = replay.positions[-1]
    assert distance(last.lat * 1e-7, last.lon * 1e-7, lat, lon) < 0.5 and abs(-last.relative_alt / 1000 - depth) < 0.1
    assert math.hypot(last.vx, last.vy) / 100 < 0.1
    fourth = ROUTE[3]
    assert min(distance(p.lat * 1e-7, p.lon * 1e-7, fourth[0], fourth[1]) for p in replay.positions) > 19.0  # 25 m from waypoint 3


def test_paused_and_resumed_the_real_sub_goes_on_with_the_leg_and_dives_past_its_sonar_under_the_floor() -> None:
    """Waypoint 3 at 45 m over SITL's 50 m seabed, beyond the 30 m sonar from the surface; ``ctl pause`` on leg 2, ``ctl resume``
    40 s later. ArduSub held POSHOLD; the executive set its mission to item 2 (MISSION_SET_CURRENT, echoed by MISSION_CURRENT)
    before AUTO, and it reached item 2, not item 1. Item 3 was written no deeper than the floor when written (the sub's depth
    plus the sonar's 30 m, less 2 m), deepened as the sub went down, the leg started again after each write (MISSION_SET_CURRENT
    3), and reached at 45 m."""
    replay = Replay(DEEP)
    assert [seq for seq, _, _ in replay.reached] == [1, 2, 3, 4]  # item 4 too, here before the executive's own judgement
    assert abs(replay.reached[2][2] - 45.0) < 0.2 and replay.reached[2][1] < 0.5
    sent = [(t, msg) for t, msg in records(DEEP) if msg.get_srcComponent() != 1]
    sets = [msg.seq for _, msg in sent if msg.get_type() == "MISSION_SET_CURRENT"]
    assert sets[:2] == [1, 2] and set(sets[2:]) == {3} and len(sets) >= 5  # the start, the resume, leg 3 restarted
    third: list[tuple[float, float]] = []  # (item 3's depth written, the sub's depth when that write began)
    depth = began = 0.0
    for _, msg in records(DEEP):
        ours = msg.get_srcComponent() != 1
        if msg.get_type() == "GLOBAL_POSITION_INT" and not ours:
            depth = -msg.relative_alt / 1000
        elif msg.get_type() == "MISSION_COUNT" and ours:
            began = depth
        elif msg.get_type() == "MISSION_ITEM_INT" and ours and msg.seq == 3:
            third.append((-msg.z, began))
    assert third[0][0] == 28.0 and max(given for given, _ in third) == 45.0
    # the depth as recorded (GLOBAL_POSITION_INT at up to 10 Hz) a little after the executive's reading, the sub going down at 1.1 m/s
    assert all(given <= sub + 30.0 - 2.0 + 0.2 for given, sub in third), third


def test_arduSub_ends_its_mission_in_alt_hold_without_a_position_and_the_executive_judges_it_the_autopilots() -> None:
    """Sub::exit_mission on the real ArduSub: its GPS off during a 60 s hold at its last item, the EKF lost its position (flags
    0xa7: CONST_POS_MODE) 8.7 s before the hold ended; then ALT_HOLD. Its heartbeat showed ALT_HOLD first, MISSION_ITEM_REACHED
    with it, MISSION_CURRENT COMPLETE 0.35 s later: judged once those came, the autopilot's (a person's before this work)."""
    replay = ModeReplay(vehicle="sub").play(END_WITHOUT_POSITION)
    assert replay.values("/vehicle/mode")[-2:] == ["AUTO", "ALT_HOLD"]
    assert replay.values("/vehicle/mode_set_by")[-1] == "autopilot"
    kinds = [msg.get_type() for _, msg in records(END_WITHOUT_POSITION)]
    first_alt_hold = next(
        i
        for i, (_, msg) in enumerate(records(END_WITHOUT_POSITION))
        if msg.get_type() == "HEARTBEAT" and msg.custom_mode == 2 and msg.base_mode & 128
    )
    assert kinds[first_alt_hold + 1] == "MISSION_ITEM_REACHED"  # after the heartbeat: judging at the heartbeat alone would miss it
