"""The autopilot link on its own: connecting, the back end the heartbeat names taken by the port, streams and our heartbeat, a replacement mission."""

from __future__ import annotations

from executive.autopilot_link import AutopilotLink, SeveralAutopilots
from executive.io.mavlink.streams import rates_for
from executive.mission.lifecycle import MissionState
from executive.testing import ObedientAutopilot, Peer
from executive.world import blackboard
from executive.world.dialect import mavlink


def make_link(mission, link, clock, **options) -> AutopilotLink:
    blackboard.reset()
    state = MissionState()
    state.upload(mission)
    return AutopilotLink(link, clock, mission, state, **options)


def test_connect_waits_for_an_autopilot_heartbeat(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    assert ap.connect(timeout_s=1.0) is False
    assert [m.get_type() for m in link.take()][:1] == ["HEARTBEAT"]  # we announce ourselves meanwhile
    ObedientAutopilot(link).beat()
    assert ap.connect(timeout_s=1.0) is True
    assert ap.reader.autopilot == (1, 1)


def test_a_second_autopilot_heard_while_surveying_is_refused(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    ObedientAutopilot(link).beat()
    link.incoming.append(Peer(2, 1).heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, mavlink.MAV_STATE_STANDBY))
    try:
        ap.connect(timeout_s=1.0, survey_s=1.0)
    except SeveralAutopilots as several:
        assert several.systems == {1: mavlink.MAV_TYPE_GROUND_ROVER, 2: mavlink.MAV_TYPE_GROUND_ROVER}
    else:
        raise AssertionError("two autopilots on the link, none named: connect must refuse")


def test_a_px4_heartbeat_gives_the_port_its_back_end_and_the_streams_and_our_heartbeat_follow(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    assert ap.heartbeat.mav_type == mavlink.MAV_TYPE_ONBOARD_CONTROLLER
    link.incoming.append(Peer(1, 1).heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_PX4, 0, 0, mavlink.MAV_STATE_STANDBY))
    ap.pump()
    assert ap.autopilot.backend.name == "px4"
    assert ap.streams.rates == rates_for("rover", "px4")
    assert ap.heartbeat.mav_type == mavlink.MAV_TYPE_GCS  # PX4's commander counts only a GCS heartbeat as the ground link
    assert [m.type for m in link.take("HEARTBEAT")] == [mavlink.MAV_TYPE_GCS]  # the pump's heartbeat, after the drain, says so already


def test_a_ground_station_command_routed_by_the_autopilot_is_kept_for_the_operator_side(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    ObedientAutopilot(link).beat()
    start = Peer(255, 190).command_long(1, 191, mavlink.MAV_CMD_MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0)
    link.incoming.append(start)
    ap.pump()
    assert [m.command for m in ap.commands_for_us()] == [mavlink.MAV_CMD_MISSION_START]
    assert ap.commands_for_us() == []  # taken once
    assert link.take("COMMAND_ACK") == []  # the link answers nothing itself


def test_a_replacement_mission_brings_its_link_timeout(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    limits = square_mission.limits.model_copy(update={"link_timeout_s": 7.5})
    ap.use(square_mission.model_copy(update={"limits": limits}))
    assert ap.reader.link_timeout_s == 7.5


def test_the_links_signing_and_serial_device_counters_reach_the_blackboard_and_a_link_without_them_reads_as_none_lost(square_mission, link, clock):
    ap = make_link(square_mission, link, clock)
    ObedientAutopilot(link).beat()
    ap.pump()
    assert blackboard.value("/link/unsigned_dropped") == 0 and blackboard.value("/link/device_lost") is None
    link.unsigned_dropped, link.device_lost = 3, "serial device /dev/ttyACM0 gone: opening it again every 1 s"
    ap.pump()
    assert blackboard.value("/link/unsigned_dropped") == 3
    assert blackboard.value("/link/device_lost") == "serial device /dev/ttyACM0 gone: opening it again every 1 s"
