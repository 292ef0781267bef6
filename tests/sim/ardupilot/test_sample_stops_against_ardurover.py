"""goto_sample with drive: auto on the real ArduRover, recorded: a sample point is a NAV_LOITER_UNLIM stop.

tests/data/ardurover/asv_sampling-motorboat-supervised*.tlog: real ArduRover SITL (4.7-dev, motorboat) driving
missions/asv_sampling.yaml with ``drive: auto`` (horizon 2, a serial sonde stand-in) under the executive, speed-up 2;
the second run paused by ``ctl pause`` 1 s into the first sample and resumed ~9 s later; the third with the executive
``kill -9``ed 28 m short of the first sample point, recorded by a second client (tests/data/ardurover/README.md).
Read here through the executive's own reader (MISSION_CURRENT, MISSION_ITEM_REACHED) and mission items.
"""

from __future__ import annotations

import math

from test_supervised_against_ardurover import read_through_the_executive, texts
from tlog_replay import records

from benchmarks import recorded
from benchmarks.efficiency import MISSIONS, with_sitl_parameters
from executive.io.mavlink.mission_protocol import MissionItem, route_not_on_autopilot
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import SimulatorOptions
from executive.testing import Lockstep
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.geo import distance

SAMPLED = recorded.DATA / "asv_sampling-motorboat-supervised.tlog"
PAUSED = recorded.DATA / "asv_sampling-motorboat-supervised-pause.tlog"
KILLED = recorded.DATA / "asv_sampling-motorboat-supervised-killed.tlog"
MISSION = load_mission(MISSIONS / "asv_sampling.yaml")
AUTOPILOT = 1  # the firmware's component; the executive's messages are the others


def held_items(path) -> list[MissionItem]:
    """The mission the vehicle last read back: its MISSION_ITEM_INTs 1..n, the latest of each seq."""
    held: dict[int, MissionItem] = {}
    for _, msg in records(path):
        if msg.get_type() == "MISSION_ITEM_INT" and msg.get_srcComponent() == AUTOPILOT and msg.seq > 0:
            held[msg.seq] = MissionItem.from_message(msg)
    return [held[seq] for seq in sorted(held)]


def track(path) -> list[tuple[float, float, float, float, int | None]]:
    """(vehicle time s, lat, lon, ground speed m/s, MISSION_CURRENT seq) at each GLOBAL_POSITION_INT of the vehicle."""
    rows, current = [], None
    for _, msg in records(path):
        if msg.get_srcComponent() != AUTOPILOT:
            continue
        if msg.get_type() == "MISSION_CURRENT":
            current = msg.seq
        elif msg.get_type() == "GLOBAL_POSITION_INT":
            rows.append((msg.time_boot_ms / 1000.0, msg.lat * 1e-7, msg.lon * 1e-7, math.hypot(msg.vx, msg.vy) / 100.0, current))
    return rows


def set_currents(path) -> list[int]:
    return [msg.seq for _, msg in records(path) if msg.get_type() == "MISSION_SET_CURRENT"]


def test_the_recordings_are_small() -> None:
    assert all(path.stat().st_size < 60_000 for path in (SAMPLED, PAUSED, KILLED))


def test_the_real_firmware_holds_each_sample_point_as_a_loiter_unlimited_and_our_reading_is_the_route() -> None:
    held = held_items(SAMPLED)
    assert [item.command for item in held] == [
        mavlink.MAV_CMD_NAV_LOITER_UNLIM if wp.sample else mavlink.MAV_CMD_NAV_WAYPOINT for wp in MISSION.waypoints
    ]
    assert route_not_on_autopilot(MISSION.waypoints, held) is None  # as the executive compares what the vehicle read back


def test_the_real_firmware_never_reports_a_sample_point_reached_and_stays_on_it_until_moved_on() -> None:
    """Rover/mode_auto.cpp verify_loiter_unlimited never completes: MISSION_ITEM_REACHED only for the waypoints between (1, 3);
    at sample point 2 MISSION_CURRENT stayed 2 until the executive's MISSION_SET_CURRENT 3, after the sample."""
    _, highest, _ = read_through_the_executive(SAMPLED, "boat")
    assert highest == [1, 3]
    assert "Mission: 2 LoitUnlim" in texts(SAMPLED) and "Mission: 4 LoitUnlim" in texts(SAMPLED)
    assert set_currents(SAMPLED) == [1, 3]
    inlet, radius = MISSION.waypoints[1], MISSION.limits.acceptance_radius_m
    rows = track(SAMPLED)
    there = [(t, distance(lat, lon, inlet.lat, inlet.lon), seq) for t, lat, lon, _, seq in rows]
    arrived = next(t for t, d, _ in there if d <= radius)
    moved_on = next(t for t, _, seq in there if t > arrived and seq == 3)
    stay = [(d, seq) for t, d, seq in there if arrived <= t < moved_on]
    assert moved_on - arrived >= MISSION.sampling.duration_s  # held the whole sample (10.9 s in the recording)
    assert all(seq == 2 for _, seq in stay) and max(d for d, _ in stay) <= radius  # item 2 all along, within 1.5 m (0.94 m)


def test_a_pause_during_the_real_sample_resumes_at_the_sample_points_item_then_goes_on() -> None:
    """ctl pause 1 s into the sample at item 2, resume ~9 s later (18 s of the vehicle's time): MISSION_SET_CURRENT 2 and AUTO
    (the boat 0.8 m from the point), the sample taken again, then MISSION_SET_CURRENT 3; MISSION_ITEM_REACHED only 1 and 3."""
    _, highest, _ = read_through_the_executive(PAUSED, "boat")
    assert highest == [1, 3]
    assert set_currents(PAUSED) == [1, 2, 3]
    said = [msg.text for _, msg in records(PAUSED) if msg.get_type() == "STATUSTEXT" and msg.get_srcComponent() != AUTOPILOT]
    assert said[:2] == ["mission PAUSED: ctl: pause", "mission RUNNING: resumed at leg 2"]


def test_killed_on_the_way_to_a_sample_point_the_real_boat_stops_there_and_never_drives_on() -> None:
    """The executive killed 28 m short of sample point 2, the autopilot holding items 1-3 (MISSION_CURRENT total 3): the firmware
    drove to item 2, said "Reached waypoint #2" and stayed on it in AUTO (never reported reached, never moved on) for the
    2.5 minutes recorded; waypoint 3, held beyond it, never approached."""
    currents, highest, mode = read_through_the_executive(KILLED, "boat")
    assert highest == [1] and mode == "AUTO"
    assert currents[-1][0] == 2 and "Reached waypoint #2" in texts(KILLED)
    totals = {msg.total for _, msg in records(KILLED) if msg.get_type() == "MISSION_CURRENT" and msg.seq == 2}
    assert totals == {3}  # waypoint 3 was on the autopilot all along
    inlet, beyond = MISSION.waypoints[1], MISSION.waypoints[2]
    rows = track(KILLED)
    stopped = next(t for t, lat, lon, speed, _ in rows if distance(lat, lon, inlet.lat, inlet.lon) < 3.0 and speed < 0.2)
    after = [(distance(lat, lon, inlet.lat, inlet.lon), speed) for t, lat, lon, speed, _ in rows if t >= stopped]
    assert rows[-1][0] - stopped > 150.0
    assert max(d for d, _ in after) < 3.0 and max(v for _, v in after) < 0.5  # loitering on the point (LOIT_RADIUS 2, waves)
    assert min(distance(lat, lon, beyond.lat, beyond.lon) for _, lat, lon, _, _ in rows) > 25.0


def test_the_simulated_ardurover_says_what_the_real_one_said(lockstep) -> None:
    """The same mission on the lock-step simulated motorboat (SITL's parameters, no faults): the same mission items read back,
    MISSION_ITEM_REACHED for the waypoints between only, the same MISSION_SET_CURRENTs, and each sample point on the autopilot's
    item while it is sampled, begun within the acceptance radius, as in the recording."""
    options = SimulatorOptions(ekf_ready_after_s=2.0)
    mission = with_sitl_parameters(MISSION.model_copy(update={"drive": "auto", "simulator": options}))
    sim: Lockstep = lockstep(mission)
    sent: list[int] = []
    send = sim.link.send
    sim.link.send = lambda msg: (sent.append(msg.seq) if msg.get_type() == "MISSION_SET_CURRENT" else None, send(msg))[1]  # type: ignore[method-assign]
    reached = blackboard.reader("replay test", ["/vehicle/mission_reached"])
    highest: list[int] = []
    held_at_sample: list[tuple[int | None, float]] = []

    def watch(s: Lockstep) -> None:
        now = reached.get("/vehicle/mission_reached")
        if now is not None and (not highest or highest[-1] != now.highest):
            highest.append(now.highest)
        sampler = s.runtime.sampler
        if sampler is not None and sampler.sampling:
            wp = MISSION.waypoints[s.runtime.mission_state.legs.leg_index]
            held_at_sample.append((s.autopilot.mission.current_seq, s.autopilot.vehicle.distance_to(wp.lat, wp.lon)))

    sim.observers.append(watch)
    assert sim.run_to_end(limit_s=600).status is MissionStatus.COMPLETED
    _, recorded_highest, _ = read_through_the_executive(SAMPLED, "boat")
    assert [item.command for item in sim.autopilot.mission._commands[1:]] == [item.command for item in held_items(SAMPLED)]
    assert highest == recorded_highest == [1, 3]
    assert sent == set_currents(SAMPLED) == [1, 3]
    assert {seq for seq, _ in held_at_sample} == {2, 4}  # while sampling, the autopilot's mission stood on the sample point's item
    began = {seq: next(d for q, d in held_at_sample if q == seq) for seq in (2, 4)}
    assert max(began.values()) <= MISSION.limits.acceptance_radius_m, began  # real: 0.94 m and 0.97 m
    # the simulated LOITER brakes more gently than the real one: the boat coasts up to ~2.1 m past the point (real: 0.97 m at most)
    assert max(d for _, d in held_at_sample) <= MISSION.limits.acceptance_radius_m + 1.0
