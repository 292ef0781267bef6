"""A standalone ``executive sim`` serves a ground station as a real ArduPilot vehicle would.

The ground station here is pymavlink's own GCS side (what MAVProxy is built on): it connects
over TCP, follows the heartbeat, changes mode, arms, uploads a mission and downloads it again.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from pymavlink import mavwp

from executive.world.dialect import mavlink, mavutil

ROOT = Path(__file__).parents[2]
HOME = (-35.363261, 149.165230)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def until(gcs, predicate: Callable[[object], bool], timeout_s: float = 10.0, kinds: list[str] | None = None):
    """Read messages until one satisfies ``predicate`` (bounded by a wall deadline)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = gcs.recv_match(type=kinds, blocking=True, timeout=0.2)
        if msg is not None and predicate(msg):
            return msg
    pytest.fail(f"timed out waiting for {kinds}")


@pytest.fixture
def gcs() -> Iterator[mavutil.mavfile]:
    port = free_port()
    sim = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "executive",
            "sim",
            "--vehicle",
            "rover",
            "--mavlink",
            f"tcpin:127.0.0.1:{port}",
            "--speedup",
            "10",
            "--ekf-ready-after",
            "3",
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert sim.stdout is not None and "listening" in sim.stdout.readline()
        conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=255, source_component=190, dialect="ardupilotmega")
        yield conn
        conn.close()
    finally:
        sim.terminate()
        sim.wait(timeout=10)


def test_a_ground_station_connects_arms_changes_mode_and_round_trips_a_mission(gcs):
    heartbeat = gcs.wait_heartbeat(timeout=10)
    assert heartbeat is not None and heartbeat.autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert heartbeat.type == mavlink.MAV_TYPE_GROUND_ROVER
    until(gcs, lambda m: m.flags & 0x10 and not m.flags & 0x80, kinds=["EKF_STATUS_REPORT"])  # EKF uses GPS

    gcs.set_mode("GUIDED")
    until(gcs, lambda m: m.get_srcComponent() == 1 and m.custom_mode == 15, kinds=["HEARTBEAT"])
    assert gcs.flightmode == "GUIDED"

    gcs.arducopter_arm()
    until(gcs, lambda m: m.get_srcComponent() == 1 and m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED, kinds=["HEARTBEAT"])

    loader = mavwp.MAVWPLoader()
    for seq, (dlat, dlon) in enumerate([(0, 0), (0.0002, 0), (0.0002, 0.0002), (0, 0.0002)]):
        loader.add(
            mavlink.MAVLink_mission_item_int_message(
                1, 1, seq, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mavlink.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0,
                round((HOME[0] + dlat) * 1e7), round((HOME[1] + dlon) * 1e7), 0, 0,
            )
        )  # fmt: skip
    gcs.waypoint_count_send(loader.count())
    while True:
        msg = until(gcs, lambda m: True, kinds=["MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"])
        if msg.get_type() == "MISSION_ACK":
            assert msg.type == mavlink.MAV_MISSION_ACCEPTED
            break
        gcs.mav.send(loader.wp(msg.seq))

    gcs.waypoint_request_list_send()
    count = until(gcs, lambda m: True, kinds=["MISSION_COUNT"]).count
    assert count == 4
    held = []
    for seq in range(count):
        gcs.mav.mission_request_int_send(1, 1, seq)
        held.append(until(gcs, lambda m, seq=seq: m.seq == seq, kinds=["MISSION_ITEM_INT"]))
    for sent, got in zip(loader.wpoints[1:], held[1:], strict=True):  # item 0 is home on ArduPilot
        assert (got.x, got.y, got.command) == (sent.x, sent.y, sent.command)
    assert abs(held[0].x / 1e7 - HOME[0]) < 1e-5  # home, wherever the upload put item 0
