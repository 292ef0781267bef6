"""Hot reload's plan: which missions may replace a paused one, the leg it continues from, the samples it keeps."""

from __future__ import annotations

import pytest

from executive.mission.model import Mission
from executive.mission.reload import Incompatible, plan
from executive.world.state import SampleRecord

#: About 11 m north of the square's first corner: not the same place as any corner (radius 1.5 m).
ELSEWHERE = {"lat": 47.397842, "lon": 8.545594}


def changed(mission: Mission, **fields) -> Mission:
    return Mission.model_validate({**mission.model_dump(mode="json", exclude_none=True), **fields})


def waypoints(mission: Mission) -> list[dict]:
    return [wp.model_dump(mode="json", exclude_none=True) for wp in mission.waypoints]


def sample(leg: int) -> SampleRecord:
    return SampleRecord(leg, 0.0, 0.0, (), 1.0, 2.0)


def test_the_waypoint_headed_for_is_found_where_the_new_mission_has_it(square_mission):
    wps = waypoints(square_mission)
    new = changed(square_mission, name="detour", waypoints=[wps[0], ELSEWHERE, wps[1], wps[2], wps[3]])
    replacement = plan(square_mission, 2, [], new, autopilot="ardupilot")  # heading for corner 3, now waypoint 4
    assert replacement.leg_index == 3
    assert replacement.describe(square_mission) == "mission replaced: 'square' -> 'detour', at leg 4/5 (the waypoint of old leg 3)"


def test_of_several_waypoints_at_that_place_the_one_numbered_nearest_continues(square_mission):
    wps = waypoints(square_mission)
    there_and_back = changed(square_mission, waypoints=[wps[0], wps[1], wps[0], wps[1], wps[2]])
    assert plan(square_mission, 1, [], there_and_back, autopilot=None).leg_index == 1
    assert plan(square_mission, 0, [], there_and_back, autopilot=None).leg_index == 0


def test_a_waypoint_headed_for_that_is_gone_needs_the_operator_to_choose(square_mission):
    wps = waypoints(square_mission)
    moved = changed(square_mission, waypoints=[wps[0], ELSEWHERE, wps[2]])
    with pytest.raises(Incompatible, match=r"waypoint 2 at 47.3979220, 8.5455940\) is not in 'square': choose .* --leg N"):
        plan(square_mission, 1, [], moved, autopilot=None)
    chosen = plan(square_mission, 1, [], moved, autopilot=None, leg=2)
    assert (chosen.leg_index, chosen.leg_reason) == (1, "chosen by the operator")
    with pytest.raises(Incompatible, match=r"--leg 4: 'square' has 3 waypoints \(1-3\)"):
        plan(square_mission, 1, [], moved, autopilot=None, leg=4)


def test_a_finished_route_needs_the_operator_to_choose(square_mission):
    with pytest.raises(Incompatible, match="every waypoint of 'square' is done"):
        plan(square_mission, 4, [], square_mission, autopilot=None)
    assert plan(square_mission, 4, [], square_mission, autopilot=None, leg=4).leg_index == 3


def test_samples_follow_their_place_renumbered_and_those_without_one_are_left_out(square_mission):
    wps = waypoints(square_mission)
    new = changed(square_mission, waypoints=[ELSEWHERE, wps[2], wps[1], wps[3]])  # corner 1 gone, corners 2 and 3 swapped
    replacement = plan(square_mission, 3, [sample(0), sample(1), sample(2)], new, autopilot=None)
    assert [(s.leg_index, s.started) for s in replacement.samples] == [(2, 1.0), (1, 1.0)]  # corner 2 is now leg 3, corner 3 leg 2
    assert replacement.left_out == (0,)
    assert replacement.describe(square_mission).endswith("; 2 samples kept (leg 3, 2); not in the new mission: the sample of old leg 1")


@pytest.mark.parametrize(
    ("fields", "autopilot", "why"),
    [
        ({"vehicle": "boat"}, None, "vehicle: the running mission is for a rover, this one for a boat"),
        ({"autopilot": "px4"}, "ardupilot", "autopilot: the vehicle runs ardupilot, the mission is for px4"),
        ({"tree": "ugv_rc_route"}, "px4", "autopilot: tree ugv_rc_route needs ArduPilot"),
        ({"rc": {"takeover_channel": 7}}, None, "rc: differs from the running mission's"),
    ],
)
def test_another_vehicle_autopilot_or_rc_is_refused(square_mission, fields, autopilot, why):
    with pytest.raises(Incompatible, match=why.replace("(", r"\(").replace(")", r"\)")):
        plan(square_mission, 0, [], changed(square_mission, **fields), autopilot=autopilot)


def test_the_same_autopilot_named_or_none_named_is_compatible(square_mission):
    assert plan(square_mission, 0, [], changed(square_mission, autopilot="ardupilot"), autopilot="ardupilot").leg_index == 0
    assert plan(square_mission, 0, [], square_mission, autopilot="px4").leg_index == 0
