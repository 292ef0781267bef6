"""drive: auto on the real ArduRover, recorded, and the simulated ArduRover against it.

tests/data/ardurover/*-supervised*.tlog: real ArduRover SITL (4.7-dev) driving the example missions with
``drive: auto`` (horizon 2) under the executive, speed-up 2, the mission's home, SITL's parameters; and
boat_survey's run with the executive killed (``kill -9``) mid leg 2, what the vehicle said afterwards
(tests/data/ardurover/README.md). Read here through the executive's own MAVLink reader and mission
transfer, and the same missions run on the lock-step simulation.
"""

from __future__ import annotations

import pytest
from test_against_ardurover import from_recorded_start
from tlog_replay import records

from benchmarks import recorded
from benchmarks.efficiency import MISSIONS, time_supervised_auto
from executive import blackboard
from executive.clock import ManualClock
from executive.geo import distance
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.reader import MavlinkReader
from executive.mission.loader import load_mission
from executive.state import MISSION_STATE_COMPLETE
from executive.testing import FakeLink
from executive.vehicles import PROFILES

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
    clock, link = ManualClock(), FakeLink()
    transfer = MissionTransfer(link, clock)
    reader = MavlinkReader(link, clock, Commander(link, clock, PROFILES[vehicle]), mission=transfer, link_timeout_s=5.0)
    bb = blackboard.reader("supervised replay", ["/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/mode"])
    currents: list[tuple[int, int, bool]] = []
    highest: list[int] = []
    t0: float | None = None
    for t, msg in records(path):
        if msg.get_srcComponent() != 1:
            continue
        t0 = t if t0 is None else t0
        if t - t0 > clock.now():
            clock.advance(t - t0 - clock.now())
        link.incoming.append(msg)
        reader.drain()
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


@pytest.mark.parametrize("name", sorted(SUPERVISED))
def test_the_real_firmware_restarts_the_waypoint_at_each_append(name: str) -> None:
    """Rover/mode_auto.cpp: a mission changed in AUTO restarts the current waypoint (AP_Mission::restart_current_nav_cmd): each
    extension of the horizon costs a restarted leg. The simulated ArduRover does the same (its _restart_on_change)."""
    mission = load_mission(MISSIONS / f"{name}.yaml")
    appends = sum(1 for _, msg in records(SUPERVISED[name]) if msg.get_type() == "MISSION_WRITE_PARTIAL_LIST")
    assert appends == len(mission.waypoints) - 3  # held 3 at the start (horizon 2), one more per leg reached
    assert texts(SUPERVISED[name]).count(RESTARTED) == appends


@pytest.mark.parametrize("name", sorted(SUPERVISED))
def test_the_simulated_firmware_takes_the_recorded_time_within_5_percent(name: str) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    real = recorded.read(SUPERVISED[name], "AUTO")
    waypoints, radius = [(w.lat, w.lon) for w in mission.waypoints], mission.limits.acceptance_radius_m
    real_s = recorded.arrival_s(real.track, waypoints, radius)
    ours = time_supervised_auto(from_recorded_start(mission, real.start))
    assert real_s is not None and abs(ours.seconds - real_s) / real_s <= 0.05, (ours.seconds, real_s)


def test_killed_mid_leg_2_the_real_boat_stops_at_the_end_of_the_horizon_and_goes_no_further() -> None:
    """The executive killed 39 m short of waypoint 2 (horizon 2: waypoints 1-4 held): the firmware drove to waypoint 4, said
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
    """The link cut for 20 s (40 s of the vehicle's time) mid leg 2, the executive alive: the firmware drove to waypoint 4 and
    said its mission COMPLETED there (MISSION_CURRENT 4, state 5, in AUTO); with the link back the executive loitered, caught
    legs 2-4 up from that, and set the mission to item 5, not back to 2."""
    path = recorded.DATA / "boat_survey-motorboat-supervised-link-cut.tlog"
    currents, highest, _ = read_through_the_executive(path, "boat")
    assert (4, MISSION_STATE_COMPLETE, True) in currents
    assert highest[:2] == [1, 5]  # items 2-4 reached unheard: their MISSION_ITEM_REACHED were lost in the cut
    sets = [msg.seq for _, msg in records(path) if msg.get_type() == "MISSION_SET_CURRENT"]
    assert sets == [1, 5]
