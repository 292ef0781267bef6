"""``upload`` while PAUSED replaces the mission (hot reload), or is refused with the reason and nothing changed."""

from __future__ import annotations

from typing import Any

import pytest
import yaml

from executive.mission.events import Replaced
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.operator import Operator
from executive.world.state import SampleRecord

ELSEWHERE = {"lat": 47.397842, "lon": 8.545594}


def mission_text(mission: Mission, **fields: Any) -> str:
    return yaml.safe_dump({**mission.model_dump(mode="json", exclude_none=True), **fields}, sort_keys=False)


def corners(mission: Mission) -> list[dict[str, Any]]:
    return [wp.model_dump(mode="json", exclude_none=True) for wp in mission.waypoints]


@pytest.fixture
def state(square_mission: Mission) -> MissionState:
    """The square paused heading for corner 3, corner 2's sample taken."""
    state = MissionState()
    state.upload(square_mission)
    state.start()
    state.advance_leg()
    state.record_sample(SampleRecord(1, 47.397922, 8.545594, (), 10.0, 20.0))
    state.advance_leg()
    state.pause("ctl: pause")
    return state


@pytest.fixture
def operator(state: MissionState) -> Operator:
    return Operator(state, "rover", autopilot_name=lambda: "ardupilot")


def unchanged(state: MissionState, mission: Mission) -> bool:
    return (state.status, state.mission, state.legs.leg_index, [s.leg_index for s in state.sample_log.taken]) == (
        MissionStatus.PAUSED,
        mission,
        2,
        [1],
    )


def test_a_paused_mission_is_replaced_at_the_same_waypoint_with_its_samples_and_stays_paused(operator, state, square_mission):
    wps = corners(square_mission)
    told: list[tuple[str, str]] = []
    state.events.subscribe(Replaced, lambda mission, reason: told.append((mission.name, reason)))
    text = mission_text(square_mission, name="detour", waypoints=[wps[0], ELSEWHERE, wps[1], wps[2], wps[3]])
    reply = operator.request("upload", source="ctl", filename="detour.yaml", text=text)
    assert (reply.ok, reply.state) == (True, "PAUSED")
    assert reply.reason == (
        "mission replaced: 'square' -> 'detour', at leg 4/5 (the waypoint of old leg 3); 1 sample kept (leg 3) "
        "(ctl: detour.yaml); paused until resumed"
    )
    assert (state.mission.name, state.legs.leg_index, [s.leg_index for s in state.sample_log.taken]) == ("detour", 3, [2])
    assert state.sample_log.sampled(2) and not state.sample_log.sampled(1)  # corner 2's sample went with corner 2, now waypoint 3
    assert told == [("detour", reply.reason)]
    assert reply.route is not None and (len(reply.route["waypoints"]), reply.route["current"]) == (5, 4)


def test_the_operator_may_choose_the_leg(operator, state, square_mission):
    wps = corners(square_mission)
    text = mission_text(square_mission, waypoints=[wps[0], ELSEWHERE])  # corner 3, headed for, is gone
    refused = operator.request("upload", filename="short.yaml", text=text)
    assert not refused.ok and "choose the leg to continue from (ctl upload MISSION --leg N)" in refused.reason
    assert unchanged(state, square_mission)
    reply = operator.request("upload", filename="short.yaml", text=text, leg=2)
    assert reply.ok and "at leg 2/2 (chosen by the operator)" in reply.reason
    assert state.legs.leg_index == 1


@pytest.mark.parametrize(
    ("fields", "why"),
    [
        ({"rc": {"takeover_channel": 7}}, "short.yaml: cannot replace 'square': rc: differs from the running mission's"),
        ({"autopilot": "px4"}, "short.yaml: cannot replace 'square': autopilot: the vehicle runs ardupilot, the mission is for px4"),
        ({"vehicle": "boat"}, "short.yaml: vehicle: this executive drives a rover, not a boat"),
        ({"waypoints": [{"lat": 95.0, "lon": 8.5}]}, "short.yaml:"),
    ],
)
def test_an_incompatible_or_bad_mission_is_refused_and_nothing_changes(operator, state, square_mission, fields, why):
    told: list[str] = []
    state.events.subscribe(Replaced, lambda mission, reason: told.append(reason))
    reply = operator.request("upload", filename="short.yaml", text=mission_text(square_mission, **fields))
    assert not reply.ok and reply.reason.startswith(why)
    assert unchanged(state, square_mission) and told == []


def test_a_bad_file_is_refused_with_its_line_and_column(operator, state, square_mission):
    text = mission_text(square_mission).replace("lat: 47.397922", "lat: 95.0", 1)
    reply = operator.request("upload", filename="bad.yaml", text=text)
    line = next(n for n, row in enumerate(text.splitlines(), start=1) if "95.0" in row)
    assert not reply.ok and reply.reason.startswith(f"bad.yaml:{line}:")
    assert unchanged(state, square_mission)


def test_a_replace_check_refuses_and_nothing_changes(operator, state, square_mission):
    state.replace_checks.append(lambda mission: "tree: cannot be built: ValueError: no")
    reply = operator.request("upload", filename="same.yaml", text=mission_text(square_mission, name="same"))
    assert (reply.ok, reply.reason) == (False, "mission 'same' refused: tree: cannot be built: ValueError: no")
    assert unchanged(state, square_mission)


def test_a_leg_is_only_for_a_replacement_and_running_missions_are_paused_first(square_mission):
    state = MissionState()
    state.upload(square_mission)
    operator = Operator(state, "rover")
    text = mission_text(square_mission)
    assert operator.request("upload", filename="m.yaml", text=text, leg=2).reason.startswith("leg: a leg is chosen only when replacing a PAUSED")
    for bad in (0, -1, True, "2", 2.0):  # over the control socket, a leg is any JSON value
        assert operator.request("upload", filename="m.yaml", text=text, leg=bad).reason == f"leg: {bad!r} is not a waypoint number (1, 2, ...)"
    state.start()
    reply = operator.request("upload", filename="m.yaml", text=text)
    assert reply.reason == "cannot upload while RUNNING: pause it first (ctl pause), then upload to replace the mission"
