"""drive: auto on the real ArduRover, recorded, and the simulated ArduRover against it.

tests/data/ardurover/*-supervised*.tlog: real ArduRover SITL (4.7-dev) driving the example missions with
``drive: auto`` (horizon 3, filled in bursts) under the executive, speed-up 2, the mission's home, SITL's
parameters; boat_survey's run with the executive killed (``kill -9``) mid leg 2, what the vehicle said
afterwards; and mission-writes-in-auto-rover.tlog, which writes restart the waypoint AUTO drives
(tests/data/ardurover/README.md). Read here through the executive's own MAVLink reader and mission
transfer, and the same missions run on the lock-step simulation.
"""

from __future__ import annotations

import pytest
from test_against_ardurover import from_recorded_start
from tlog_replay import records, through_reader

from benchmarks import recorded
from benchmarks.efficiency import MISSIONS, time_supervised_auto
from executive.mission.loader import load_mission
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.geo import distance
from executive.world.state import MISSION_STATE_COMPLETE

SUPERVISED = {
    "rover_square": recorded.DATA / "rover_square-rover-supervised.tlog",
    "boat_survey": recorded.DATA / "boat_survey-motorboat-supervised.tlog",
}
KILLED = recorded.DATA / "boat_survey-motorboat-supervised-killed.tlog"
RESTARTED = "Auto mission changed, restarted command"


def texts(path) -> list[str]:
    return [msg.text for _, msg in records(path) if msg.get_type() == "STATUSTEXT" and msg.get_srcComponent() == 1]


def read_through_the_executive(path, vehicle: str) -> tuple[list[tuple[int, int, bool]], list[int], str | None]:
    """The recording's vehicle side through our reader and mission transfer: each change of (MISSION_CURRENT seq, state, in AUTO),
    each new highest item reached, and the last mode."""
    blackboard.reset()
    bb = blackboard.reader("supervised replay", ["/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/mode"])
    currents: list[tuple[int, int, bool]] = []
    highest: list[int] = []
    for _ in through_reader(path, vehicle):
        current, reached = bb.get("/vehicle/mission_current"), bb.get("/vehicle/mission_reached")
        if current is not None and (not currents or currents[-1] != (current.seq, current.state, current.in_mission_mode)):
            currents.append((current.seq, current.state, current.in_mission_mode))
        if reached is not None and (not highest or highest[-1] != reached.highest):
            highest.append(reached.highest)
    return currents, highest, bb.get("/vehicle/mode")


def test_the_recordings_are_small() -> None:
    assert all(path.stat().st_size < 200_000 for path in [*SUPERVISED.values(), KILLED])


@pytest.mark.parametrize("name", sorted(SUPERVISED))
def test_each_waypoint_is_reported_reached_in_turn_and_the_mission_moves_on(name: str) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    currents, highest, _ = read_through_the_executive(SUPERVISED[name], mission.vehicle)
    n = len(mission.waypoints)
    # MISSION_ITEM_REACHED 1..n-1, what FollowAutoLeg counts; the last waypoint is ours to judge (the acceptance radius), and the
    # executive held the vehicle there before the firmware's own word
    assert highest == list(range(1, n))
    driving = [seq for seq, state, auto in currents if auto and seq > 0]
    assert driving == sorted(driving) and driving[-1] == n  # MISSION_CURRENT only forward, to the last item


def test_the_real_firmware_restarts_its_waypoint_at_any_write_even_past_the_commands_its_detector_compares() -> None:
    """AP_Mission_ChangeDetector compares the current and next two navigation commands (items 1-3 here), yet an identical
    rewrite of item 8, an append of item 9 and an identical rewrite of item 2, each while AUTO drove to item 1, restarted it."""
    path = recorded.DATA / "mission-writes-in-auto-rover.tlog"
    events = [(msg.get_type(), getattr(msg, "start_index", None) or getattr(msg, "text", "")) for _, msg in records(path)]
    writes = [(kind, what) for kind, what in events if kind == "MISSION_WRITE_PARTIAL_LIST" or what == RESTARTED]
    assert writes == [("MISSION_WRITE_PARTIAL_LIST", 8), ("STATUSTEXT", RESTARTED), ("MISSION_WRITE_PARTIAL_LIST", 9), ("STATUSTEXT", RESTARTED),
                      ("MISSION_WRITE_PARTIAL_LIST", 2), ("STATUSTEXT", RESTARTED)]  # fmt: skip
    driving = {msg.seq for _, msg in records(path) if msg.get_type() == "MISSION_CURRENT" and msg.mission_state == mavlink.MISSION_STATE_ACTIVE}
    assert driving == {1}


#: drive: auto, horizon 3: the waypoints appended in each burst, after the waypoint reached (none for rover_square: held whole).
BURSTS = {"rover_square": {}, "boat_survey": {2: [5, 6], 4: [7, 8]}}


@pytest.mark.parametrize("name", sorted(SUPERVISED))
def test_the_horizon_is_filled_in_bursts_and_each_write_restarts_the_waypoint(name: str) -> None:
    """The autopilot holding one waypoint past the current one, the executive appends up to the horizon at once: the real
    firmware restarts its waypoint at each write (Rover/mode_auto.cpp), so the writes come in one burst per H-1 legs."""
    bursts: dict[int, list[int]] = {}
    reached = 0
    for _, msg in records(SUPERVISED[name]):
        if msg.get_type() == "MISSION_ITEM_REACHED":
            reached = max(reached, msg.seq)
        elif msg.get_type() == "MISSION_WRITE_PARTIAL_LIST":
            bursts.setdefault(reached, []).append(msg.start_index)
    assert bursts == BURSTS[name]
    assert texts(SUPERVISED[name]).count(RESTARTED) == sum(len(items) for items in bursts.values())


@pytest.mark.parametrize("name", sorted(SUPERVISED))
def test_the_simulated_firmware_takes_the_recorded_time_within_5_percent(name: str) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    real = recorded.read(SUPERVISED[name], "AUTO")
    waypoints, radius = [(w.lat, w.lon) for w in mission.waypoints], mission.limits.acceptance_radius_m
    real_s = recorded.arrival_s(real.track, waypoints, radius)
    ours = time_supervised_auto(from_recorded_start(mission, real.start))
    assert real_s is not None and abs(ours.seconds - real_s) / real_s <= 0.05, (ours.seconds, real_s)


def test_killed_mid_leg_2_the_real_boat_stops_at_the_end_of_the_horizon_and_goes_no_further() -> None:
    """The executive killed 6 s into leg 2 (horizon 3, before its first burst: waypoints 1-4 held): the firmware drove to waypoint 4, said
    "Mission Complete", and held there in AUTO (MIS_DONE_BEHAVE 0); waypoints 5-8 were never approached."""
    mission = load_mission(MISSIONS / "boat_survey.yaml")
    currents, highest, mode = read_through_the_executive(KILLED, "boat")
    assert highest == [1, 2, 3, 4] and mode == "AUTO"
    assert currents[-1] == (4, MISSION_STATE_COMPLETE, True)  # the autopilot's word for its mission's end
    assert "Mission Complete" in texts(KILLED)
    positions = [msg for _, msg in records(KILLED) if msg.get_type() == "GLOBAL_POSITION_INT"]
    last = positions[-1]
    fourth = mission.waypoints[3]
    assert distance(last.lat * 1e-7, last.lon * 1e-7, fourth.lat, fourth.lon) < 5.0
    assert (last.vx**2 + last.vy**2) ** 0.5 / 100.0 < 0.2
    nearest = [min(distance(p.lat * 1e-7, p.lon * 1e-7, w.lat, w.lon) for p in positions) for w in mission.waypoints[4:]]
    assert min(nearest) > 10.0, nearest  # waypoint 5 is 15 m from waypoint 4: never driven to


def test_a_cut_link_on_the_real_boat_the_mission_completed_at_the_horizon_and_the_route_resumed_after_it() -> None:
    """Horizon 3 (items 1-4 held on leg 2), the link cut both ways for 34 s of the vehicle's time from 3.2 s into leg 2, the
    executive alive: the firmware drove to waypoint 4, stopped there and said its mission COMPLETED (MISSION_CURRENT 4,
    state 5, in AUTO); with the link back the executive's link-loss failsafe loitered, caught legs 2-4 up from that,
    appended waypoints 5-8 and set the mission to item 5, not back to 2; the run COMPLETED."""
    path = recorded.DATA / "boat_survey-motorboat-supervised-link-cut.tlog"
    mission = load_mission(MISSIONS / "boat_survey.yaml")
    currents, highest, _ = read_through_the_executive(path, "boat")
    assert (4, MISSION_STATE_COMPLETE, True) in currents
    assert highest[:2] == [1, 5]  # items 2-4 reached unheard: their MISSION_ITEM_REACHED were lost in the cut
    sent = [(msg.get_type(), msg) for _, msg in records(path) if msg.get_srcComponent() == 191]
    assert [m.count for kind, m in sent if kind == "MISSION_COUNT" and m.target_component == 1] == [5]  # home + waypoints 1-4
    assert [m.seq for kind, m in sent if kind == "MISSION_SET_CURRENT"] == [1, 5]
    appended = [(m.start_index, m.end_index) for kind, m in sent if kind == "MISSION_WRITE_PARTIAL_LIST"]
    assert appended == [(5, 5), (6, 6), (7, 7), (8, 8)]  # only after the link was back: the autopilot never held past item 4 alone
    positions = [msg for _, msg in records(path) if msg.get_type() == "GLOBAL_POSITION_INT"]
    gap = max(range(1, len(positions)), key=lambda i: positions[i].time_boot_ms - positions[i - 1].time_boot_ms)
    before, back = positions[gap - 1], positions[gap]
    assert 30_000 < back.time_boot_ms - before.time_boot_ms < 40_000  # the cut, in the vehicle's time
    fourth, fifth = mission.waypoints[3], mission.waypoints[4]
    assert distance(back.lat * 1e-7, back.lon * 1e-7, fourth.lat, fourth.lon) < 1.0  # stopped at the end of its horizon
    assert (back.vx**2 + back.vy**2) ** 0.5 / 100.0 < 0.2
    assert distance(back.lat * 1e-7, back.lon * 1e-7, fifth.lat, fifth.lon) > 10.0
    said = [msg.text for _, msg in records(path) if msg.get_type() == "STATUSTEXT" and msg.get_srcComponent() == 191]
    assert said[-2:] == ["link_loss: in LOITER, confirmed", "failsafe link_loss recovered: leg 2/8"]
    assert "Mission: 8 WP" in texts(path)
