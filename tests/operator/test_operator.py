"""Operator requests follow the lifecycle: accepted ones change the state, refused ones say why and change nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.operator import Operator

S = MissionStatus
MISSIONS = Path(__file__).parents[2] / "missions"


@pytest.fixture
def operator(square_mission) -> Operator:
    state = MissionState()
    state.upload(square_mission)
    return Operator(state, "rover", status=lambda: {"state": str(state.status)})


@pytest.mark.parametrize(
    ("requests", "last_ok", "state"),
    [
        (["start"], True, S.RUNNING),
        (["start", "pause"], True, S.PAUSED),
        (["start", "pause", "resume"], True, S.RUNNING),
        (["start", "abort"], True, S.ABORTED),
        (["delete"], True, S.IDLE),
        (["pause"], False, S.READY),
        (["resume"], False, S.READY),
        (["start", "start"], False, S.RUNNING),
        (["delete", "start"], False, S.IDLE),
        (["abort"], False, S.READY),
        (["warp"], False, S.READY),
    ],
)
def test_requests_follow_the_lifecycle(operator, requests, last_ok, state):
    for op in requests:
        reply = operator.request(op, source="ctl")
    assert reply.ok is last_ok
    assert reply.state == str(state) == str(operator.mission_state.status)
    if not last_ok:
        assert reply.reason.startswith(("cannot", "unknown request"))


def test_pause_and_abort_name_who_asked(operator):
    operator.request("start")
    assert operator.request("pause", source="ground station 255").reason == "ground station 255: pause"
    assert operator.request("abort", source="ctl").reason == "ctl: abort"


def test_status_carries_the_snapshot(operator):
    reply = operator.request("status")
    assert reply.ok and reply.status == {"state": "READY"}
    assert "status" not in operator.request("start").to_dict()


def test_upload_validates_and_locates_errors(operator):
    reply = operator.request("upload", filename="bad.yaml", text="version: 1\nname: x\nvehicle: rover\nwaypoints:\n  - {lat: 95.0, lon: 8.5}\n")
    assert not reply.ok
    assert reply.reason.startswith("bad.yaml:5:11: waypoints[0].lat:")
    assert operator.mission_state.mission.name == "square"  # the loaded mission is untouched


def test_upload_of_another_vehicle_kind_is_refused(operator):
    text = (MISSIONS / "boat_survey.yaml").read_text()
    reply = operator.request("upload", filename="boat_survey.yaml", text=text)
    assert (reply.ok, reply.reason) == (False, "boat_survey.yaml: vehicle: this executive drives a rover, not a boat")


def test_upload_replaces_a_ready_mission_but_not_a_running_one(operator):
    text = (MISSIONS / "rover_square.yaml").read_text()
    assert operator.request("upload", filename="rover_square.yaml", text=text).ok
    assert operator.mission_state.mission.name == "rover-square"
    operator.request("start")
    reply = operator.request("upload", filename="rover_square.yaml", text=text)
    assert not reply.ok and reply.reason.startswith("cannot upload while RUNNING")


AUV = (MISSIONS / "auv_survey.yaml").read_text()


def test_an_auv_mission_out_of_reach_is_refused_at_upload(vehicle):
    """Issue 13: the AUV's 1 km rule was checked at start; the Zeno vehicle refuses such a mission at upload, READY never reached."""
    from executive.world.state import EkfFlags, EkfStatus, GlobalPosition

    state = MissionState()
    operator = Operator(state, "sub")
    first = next(line for line in AUV.splitlines() if "name: start" in line)
    lat = float(first.split("lat:")[1].split(",")[0])
    ekf = EkfStatus(EkfFlags(831), 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
    vehicle.set(vehicle__position=GlobalPosition(lat - 0.0135, 9.8630000, 0.0, 0, 0, 0, None, 0.0), vehicle__ekf=ekf)  # 1.5 km south
    reply = operator.request("upload", filename="auv_survey.yaml", text=AUV)
    assert not reply.ok and reply.state == "IDLE"
    assert reply.reason.startswith(
        "mission 'auv-survey' refused: waypoints[0] (start): 1500 m from the vehicle, over limits.max_goal_distance_m (1000 m)"
    )
    vehicle.set(vehicle__position=GlobalPosition(lat - 0.0045, 9.8630000, 0.0, 0, 0, 0, None, 0.0))  # 500 m south
    assert operator.request("upload", filename="auv_survey.yaml", text=AUV).ok
    assert state.status is S.READY


def test_every_limit_is_checked_at_upload(square_mission):
    """A mission built in code (never through the loader) breaking a limit is refused READY, with the reason."""
    fast = square_mission.model_copy(update={"waypoints": [square_mission.waypoints[0].model_copy(update={"speed_m_s": 9.0})]})
    state = MissionState()
    with pytest.raises(Refused, match=r"refused: waypoints\[0\]\.speed_m_s: 9.0 m/s is outside limits.speed_m_s \[0.1, 5.0\]"):
        state.upload(fast)
    assert state.status is S.IDLE and state.mission is None
