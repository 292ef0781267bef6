"""The simulated vehicle over real sockets, at 50x speed-up, bounded by wall-clock deadlines."""

from __future__ import annotations

import argparse
import logging
import math
import re
import socket
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

import pytest

from executive.cli import EXIT_BAD_INPUT, main
from executive.cli import sim as sim_cli
from executive.sim import SimServer
from executive.world.clock import ScaledClock
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Client

HOME = (47.397742, 8.545594, 90.0)


def booted(heartbeat: MAVLinkMessage) -> bool:
    """Past INITIALISING (16): the firmware handles commands from now on."""
    return heartbeat.custom_mode != 16


@pytest.fixture
def server() -> Iterator[SimServer]:
    with SimServer("rover", clock=ScaledClock(50.0), home=HOME, ekf_ready_after_s=2.0) as sim:
        yield sim


def test_drive_a_rover_over_udp(server: SimServer, client_for: Callable[[str], Client]) -> None:
    assert server.url_for_client == f"udpout:127.0.0.1:{server.port}"
    client = client_for(server.url_for_client)
    client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)  # udpin answers peers it has heard
    heartbeat = client.wait("HEARTBEAT", booted)
    assert (heartbeat.get_srcSystem(), heartbeat.get_srcComponent(), heartbeat.type) == (1, 1, m.MAV_TYPE_GROUND_ROVER)
    client.wait("GLOBAL_POSITION_INT")
    client.wait("EKF_STATUS_REPORT", lambda msg: msg.flags == 831)

    assert client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15).result == m.MAV_RESULT_ACCEPTED
    client.wait("HEARTBEAT", lambda msg: msg.custom_mode == 15)
    ack = client.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert (ack.result, ack.target_system, ack.target_component) == (m.MAV_RESULT_ACCEPTED, 255, 190)
    client.wait("HEARTBEAT", lambda msg: msg.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED)

    lat, lon = HOME[0] + 20 / 111_319.49, HOME[1]
    x, y = round(lat * 1e7), round(lon * 1e7)
    client.conn.mav.set_position_target_global_int_send(0, 1, 1, m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, x, y, 0, *[0.0] * 8)
    client.wait("POSITION_TARGET_GLOBAL_INT", lambda msg: msg.lat_int == round(lat * 1e7))
    client.wait("MISSION_ITEM_REACHED")  # the simulator says so once within 0.3 m; a position report may come before or after it
    position = client.wait("GLOBAL_POSITION_INT")
    assert math.hypot(position.lat / 1e7 - lat, position.lon / 1e7 - lon) * 111_319.49 < 0.5


def test_garbage_on_the_link_is_survived(server: SimServer, client_for: Callable[[str], Client]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw:
        raw.sendto(b"\xfd\x09\x00\x00\x00\xff\xbe\x00\x00\x00garbage-with-a-bad-crc", ("127.0.0.1", server.port))
        raw.sendto(bytes(range(256)), ("127.0.0.1", server.port))  # a header announcing 255 bytes: the parser waits for them
    client = client_for(server.url_for_client)
    client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    client.wait("HEARTBEAT", booted)
    for _ in range(20):  # as a commander does: retry until acknowledged
        try:
            ack = client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, timeout=0.5)
            break
        except AssertionError:
            continue
    else:
        pytest.fail("the vehicle never answered after the garbage")
    assert ack.result == m.MAV_RESULT_ACCEPTED


def test_a_ground_station_can_connect_over_tcp(client_for: Callable[[str], Client]) -> None:
    with SimServer("boat", "tcpin:127.0.0.1:0", clock=ScaledClock(50.0), home=HOME, ekf_ready_after_s=2.0) as sim:
        assert sim.url_for_client == f"tcp:127.0.0.1:{sim.port}"
        client = client_for(sim.url_for_client)
        assert client.wait("HEARTBEAT", booted).type == m.MAV_TYPE_SURFACE_BOAT
        assert client.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4).result == m.MAV_RESULT_ACCEPTED


def test_stop_is_clean_and_idempotent() -> None:
    sim = SimServer("rover", clock=ScaledClock(50.0)).start()
    sim.stop()
    sim.stop()


def test_unknown_vehicle_kind() -> None:
    with pytest.raises(ValueError, match="no simulated vehicle of kind 'tank'"):
        SimServer("tank")


def parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="executive")
    sim_cli.register(parser.add_subparsers())
    return parser.parse_args(["sim", *argv])


def test_cli_runs_for_a_duration_and_says_where_it_listens(capsys: pytest.CaptureFixture[str]) -> None:
    args = parse("--vehicle", "boat", "--mavlink", "udpin:127.0.0.1:0", "--speedup", "50", "--duration", "2", "--home", "-35.4,149.1,90")
    assert (args.home, args.ekf_ready_after, args.speedup) == ((-35.4, 149.1, 90.0), None, 50.0)  # None: the firmware's own
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "ArduRover boat listening on udpin:127.0.0.1:0 (connect to udpout:127.0.0.1:" in out


def test_cli_simulates_px4_on_the_vtol_and_the_rover_only(capsys: pytest.CaptureFixture[str]) -> None:
    args = parse("--vehicle", "vtol", "--autopilot", "px4", "--mavlink", "udpin:127.0.0.1:0", "--speedup", "50", "--duration", "1")
    assert args.func(args) == 0
    assert "PX4 vtol listening on udpin:127.0.0.1:0" in capsys.readouterr().out
    assert main(["sim", "--vehicle", "boat", "--autopilot", "px4", "--duration", "1"]) == EXIT_BAD_INPUT
    assert capsys.readouterr().err == "executive: sim: no simulated px4 boat (known: vtol, rover)\n"


def test_cli_defaults_and_bad_values(capsys: pytest.CaptureFixture[str]) -> None:
    args = parse()
    assert (args.vehicle, args.mavlink, args.duration) == ("rover", "tcpin:127.0.0.1:5760", None)
    for bad in (["--home", "north"], ["--home", "95,8"], ["--speedup", "0"], ["--vehicle", "tank"]):
        with pytest.raises(SystemExit):
            parse(*bad)
    assert "LAT,LON[,HEADING]" in capsys.readouterr().err


def _until(condition: Callable[[], bool], timeout: float = 10.0) -> None:
    """Wait for ``condition`` (the server's thread acts on its own time); ``timeout`` only bounds a hung server."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "the server never got there"
        time.sleep(0.005)


@pytest.mark.parametrize("scheme", ["tcpin", "udpin"])
def test_several_clients_at_once_each_hear_the_vehicle_and_each_command_it_comings_and_goings_logged(
    scheme: str, client_for: Callable[[str], Client], caplog: pytest.LogCaptureFixture
) -> None:
    """An executive and a ground station beside it (issue 43: the second client heard nothing and exited 3 after 30 s)."""
    caplog.set_level(logging.INFO, logger="executive.sim.clients")
    with SimServer("rover", f"{scheme}:127.0.0.1:0", clock=ScaledClock(50.0), home=HOME, ekf_ready_after_s=2.0) as sim:
        executive, ground_station = client_for(sim.url_for_client), client_for(sim.url_for_client)
        for client in (executive, ground_station):
            client.conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)  # udpin: a client is one that has spoken
            client.wait("HEARTBEAT", booted)
        said = lambda: [r.getMessage() for r in caplog.records]  # noqa: E731
        _until(lambda: any("connected (2 clients)" in text for text in said()))
        assert ground_station.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4).result == m.MAV_RESULT_ACCEPTED
        executive.wait("HEARTBEAT", lambda msg: msg.custom_mode == 4)  # what one commands, the other sees
        assert executive.command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15).result == m.MAV_RESULT_ACCEPTED
        ground_station.wait("HEARTBEAT", lambda msg: msg.custom_mode == 15)
        if scheme == "tcpin":  # a TCP client says it leaves; a UDP one is let go after a silence
            ground_station.close()
            _until(lambda: any(re.search(r"MAVLink client 127\.0\.0\.1:\d+ left: disconnected \(1 client\)", t) for t in said()))
            executive.wait("HEARTBEAT")  # the one left is still served
