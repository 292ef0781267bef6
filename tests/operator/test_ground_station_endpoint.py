"""Ground-station control: pause/continue and mission start from allow-listed systems, acked; reports at 1 Hz and on changes."""

from __future__ import annotations

import pytest

from executive.mission.lifecycle import MissionState, MissionStatus
from executive.operator import Operator
from executive.operator.ground_station import STATE_CODES, GroundStationControl
from executive.runtime.assembly import build_runtime, ground_stations
from executive.testing import GCS, FakeLink, ObedientAutopilot, Peer
from executive.world.dialect import mavlink

US = (1, 191)


@pytest.fixture
def control(square_mission, link, clock):
    state = MissionState()
    state.upload(square_mission)
    return GroundStationControl([link], clock, Operator(state, "rover"), allowed_systems=(255,))


def command(command_id: int, *params: float, sender: Peer = GCS, target: tuple[int, int] = US):
    padded = (*params, *([0.0] * (7 - len(params))))
    return sender.command_long(*target, command_id, 0, *padded)


def acks(link):
    return [(m.command, m.result, m.target_system) for m in link.take("COMMAND_ACK")]


def test_mission_start_then_pause_and_continue(control, link):
    state = control._operator.mission_state  # the operator's state, as ctl upload replaces it
    assert control.on_command(command(mavlink.MAV_CMD_MISSION_START), link)
    assert state.status is MissionStatus.RUNNING
    control.on_command(command(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, 0), link)
    assert state.status is MissionStatus.PAUSED and state.reason == "ground station 255: pause"
    control.on_command(command(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, 1), link)
    assert state.status is MissionStatus.RUNNING
    assert acks(link) == [
        (mavlink.MAV_CMD_MISSION_START, mavlink.MAV_RESULT_ACCEPTED, 255),
        (mavlink.MAV_CMD_DO_PAUSE_CONTINUE, mavlink.MAV_RESULT_ACCEPTED, 255),
        (mavlink.MAV_CMD_DO_PAUSE_CONTINUE, mavlink.MAV_RESULT_ACCEPTED, 255),
    ]


def test_a_request_the_lifecycle_refuses_is_temporarily_rejected_with_a_text(control, link):
    control.on_command(command(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, 0), link)  # READY: nothing to pause
    assert acks(link) == [(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, mavlink.MAV_RESULT_TEMPORARILY_REJECTED, 255)]
    control.service()
    (text,) = link.take("STATUSTEXT")
    assert text.text.startswith("executive: pause refused: cannot pause while READY")


def test_systems_not_allow_listed_are_denied(control, link):
    control.on_command(command(mavlink.MAV_CMD_MISSION_START, sender=Peer(42, 190)), link)
    assert acks(link) == [(mavlink.MAV_CMD_MISSION_START, mavlink.MAV_RESULT_DENIED, 42)]
    assert control._operator.mission_state.status is MissionStatus.READY


def test_other_commands_to_us_are_unsupported_and_commands_to_others_are_not_ours(control, link):
    assert control.on_command(command(mavlink.MAV_CMD_DO_SET_SERVO, 1, 1500), link)
    assert acks(link) == [(mavlink.MAV_CMD_DO_SET_SERVO, mavlink.MAV_RESULT_UNSUPPORTED, 255)]
    assert not control.on_command(command(mavlink.MAV_CMD_MISSION_START, target=(1, 1)), link)  # for the autopilot
    assert acks(link) == []


def test_reports_named_values_at_1_hz_and_text_on_changes(control, link, clock):
    sent = []
    for _ in range(25):  # 2.5 s
        control.service()
        sent += link.take("NAMED_VALUE_FLOAT")
        clock.advance(0.1)
    assert [m.name for m in sent] == ["MSN_STATE", "MSN_LEG", "WP_DIST"] * 3
    assert sent[0].value == STATE_CODES[MissionStatus.READY]
    control.on_command(command(mavlink.MAV_CMD_MISSION_START), link)
    control.service()
    (text,) = link.take("STATUSTEXT")
    assert text.text == "mission RUNNING: started from the first waypoint"


def test_a_mission_replaced_while_paused_is_told_in_a_text(link, clock, square_mission):
    state = MissionState()
    state.upload(square_mission)
    control = GroundStationControl([link], clock, Operator(state, "rover"))
    state.start()
    state.pause("ctl: pause")
    control.service()
    link.take("STATUSTEXT")
    state.replace(square_mission.model_copy(update={"name": "square-v2"}), 1, (), "mission replaced: 'square' -> 'square-v2', ...")
    control.service()
    assert [(m.severity, m.text) for m in link.take("STATUSTEXT")] == [(mavlink.MAV_SEVERITY_NOTICE, "mission replaced: square-v2")]


def test_a_command_routed_by_the_autopilot_is_answered_before_the_tree_ticks(square_mission, link, clock):
    runtime = build_runtime(square_mission, link, clock)
    first = square_mission.waypoints[0]
    ObedientAutopilot(link, start=(first.lat, first.lon)).beat()
    runtime.tick()
    link.take()
    link.incoming.append(command(mavlink.MAV_CMD_MISSION_START))  # a ground station's, routed by the autopilot onto our link
    runtime.tick()
    assert runtime.mission_state.status is MissionStatus.RUNNING and runtime.tree is not None  # started in that tick
    assert acks(link) == [(mavlink.MAV_CMD_MISSION_START, mavlink.MAV_RESULT_ACCEPTED, 255)]
    link.incoming.append(command(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, 0))
    runtime.make_safe()  # made safe meanwhile: the ground station is answered too
    assert acks(link) == [(mavlink.MAV_CMD_DO_PAUSE_CONTINUE, mavlink.MAV_RESULT_ACCEPTED, 255)]
    assert runtime.mission_state.status is MissionStatus.PAUSED


def test_ground_stations_on_an_endpoint_of_their_own_are_answered_and_reported_to(square_mission, link, clock):
    endpoint = FakeLink()
    runtime = build_runtime(square_mission, link, clock, plugs=[ground_stations(endpoint, allowed_systems=(42,))])
    first = square_mission.waypoints[0]
    ObedientAutopilot(link, start=(first.lat, first.lon)).beat()
    endpoint.incoming.append(command(mavlink.MAV_CMD_MISSION_START))  # from 255: not allow-listed there
    endpoint.incoming.append(GCS.heartbeat(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0))  # passed over
    endpoint.incoming.append(command(mavlink.MAV_CMD_MISSION_START, sender=Peer(42, 190)))
    runtime.tick()
    assert acks(endpoint) == [
        (mavlink.MAV_CMD_MISSION_START, mavlink.MAV_RESULT_DENIED, 255),
        (mavlink.MAV_CMD_MISSION_START, mavlink.MAV_RESULT_ACCEPTED, 42),
    ]
    assert runtime.mission_state.status is MissionStatus.RUNNING
    assert [m.name for m in endpoint.take("NAMED_VALUE_FLOAT")] == ["MSN_STATE", "MSN_LEG", "WP_DIST"]  # reported there too
    assert [m.get_type() for m in endpoint.take("HEARTBEAT")] == ["HEARTBEAT"]  # we announce ourselves there


def test_the_energy_estimate_is_reported_as_named_values_once_there_is_one(control, link, clock):
    from executive.sensing.energy import EnergyEstimate
    from executive.testing import Vehicle

    Vehicle().set(energy__estimate=EnergyEstimate(38.0, 41.0, 9.0, 6.0, 100.0, 20.0, 0.0, 6.0, 0.5, 0, 0.0))
    control.service()
    values = {m.name: m.value for m in link.take("NAMED_VALUE_FLOAT")}
    assert (values["EN_LEFT"], values["EN_NEED"], values["EN_MARGIN"]) == (38.0, 50.0, -18.0)
