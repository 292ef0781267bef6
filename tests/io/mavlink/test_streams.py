"""Stream set-up: one SET_MESSAGE_INTERVAL at a time, every stream, again after a reconnect."""

from __future__ import annotations

import pytest

from executive.io.mavlink.streams import StreamRequester
from executive.testing import ack
from executive.world.dialect import mavlink

RATES = {"GLOBAL_POSITION_INT": 5.0, "ATTITUDE": 10.0, "HOME_POSITION": 0.2}


def run(streams: StreamRequester, commander, link, result=mavlink.MAV_RESULT_ACCEPTED, ticks: int = 10):
    sent = []
    for _ in range(ticks):
        streams.service()
        commander.flush()
        for msg in link.take("COMMAND_LONG"):
            sent.append((int(msg.param1), msg.param2))
            commander.on_ack(ack(msg.command, result))
    return sent


def test_requests_each_stream_once_in_turn(commander, link):
    streams = StreamRequester(commander, RATES)
    streams.restart()
    assert run(streams, commander, link) == [
        (mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 200_000.0),
        (mavlink.MAVLINK_MSG_ID_ATTITUDE, 100_000.0),
        (mavlink.MAVLINK_MSG_ID_HOME_POSITION, 5_000_000.0),
    ]
    assert streams.done and not streams.refused


def test_nothing_is_requested_before_the_autopilot_is_found(commander, link):
    streams = StreamRequester(commander, RATES)
    assert run(streams, commander, link) == []


def test_refusals_are_remembered_and_skipped(commander, link):
    streams = StreamRequester(commander, RATES)
    streams.restart()
    assert len(run(streams, commander, link, result=mavlink.MAV_RESULT_UNSUPPORTED)) == 3
    assert streams.refused == set(RATES)


def test_restart_after_a_reconnect_asks_again(commander, link):
    streams = StreamRequester(commander, RATES)
    streams.restart()
    run(streams, commander, link)
    streams.restart()
    assert len(run(streams, commander, link)) == 3


@pytest.mark.parametrize("rate", [0.5, 50.0])
def test_interval_is_the_inverse_rate(commander, link, rate):
    streams = StreamRequester(commander, {"VFR_HUD": rate})
    streams.restart()
    assert run(streams, commander, link) == [(mavlink.MAVLINK_MSG_ID_VFR_HUD, 1e6 / rate)]


def test_only_aircraft_are_asked_for_vtol_and_landed_state():
    from executive.io.mavlink.streams import rates_for

    assert "EXTENDED_SYS_STATE" in rates_for("vtol")
    assert "EXTENDED_SYS_STATE" not in rates_for("rover")
    assert set(rates_for("boat")) | {"EXTENDED_SYS_STATE"} == set(rates_for("vtol"))


def test_subs_are_asked_for_their_sonar():
    from executive.io.mavlink.streams import rates_for

    assert rates_for("sub")["DISTANCE_SENSOR"] == 5.0
    assert "DISTANCE_SENSOR" not in rates_for("boat")
