"""The pymavlink link over real UDP sockets: signing and .tlog recording."""

from __future__ import annotations

import hashlib
import time

import pytest

from executive.io.mavlink.link import PymavlinkLink, load_signing_key
from executive.world.dialect import encoder, mavlink, mavutil

KEY = bytes(range(32))


def wait_for(recv, kind: str, timeout_s: float = 3.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = recv()
        if msg is not None and msg.get_type() == kind:
            return msg
        if msg is None:
            time.sleep(0.002)
    return None


@pytest.fixture
def vehicle():
    """A bare pymavlink endpoint standing in for the autopilot."""
    conn = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=1, source_component=1, dialect="ardupilotmega")
    yield conn
    conn.close()


def heartbeat(system_id: int = 1):
    return encoder(system_id, 1).heartbeat_encode(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 4, 3)


def test_signed_link_signs_what_it_sends_and_drops_unsigned_packets(vehicle):
    port = vehicle.port.getsockname()[1]
    link = PymavlinkLink(f"udpout:127.0.0.1:{port}", signing_key=KEY)
    try:
        vehicle.setup_signing(KEY, sign_outgoing=True)
        link.send(heartbeat(system_id=1))
        got = wait_for(vehicle.recv_msg, "HEARTBEAT")
        assert got is not None and got.get_signed()

        vehicle.mav.send(heartbeat())
        assert wait_for(link.recv, "HEARTBEAT") is not None
        assert link.unsigned_dropped == 0

        vehicle.disable_signing()
        vehicle.mav.send(heartbeat())
        assert wait_for(link.recv, "HEARTBEAT", timeout_s=0.5) is None
        assert link.unsigned_dropped == 1

        vehicle.setup_signing(bytes(32), sign_outgoing=True)  # the wrong key
        vehicle.mav.send(heartbeat())
        assert wait_for(link.recv, "HEARTBEAT", timeout_s=0.5) is None
        assert link.unsigned_dropped == 2
    finally:
        link.close()


def test_tlog_records_both_directions_readably_by_pymavlink(vehicle, tmp_path):
    tlog = tmp_path / "run.tlog"
    port = vehicle.port.getsockname()[1]
    link = PymavlinkLink(f"udpout:127.0.0.1:{port}", tlog=tlog)
    try:
        link.send(heartbeat(system_id=42))
        assert wait_for(vehicle.recv_msg, "HEARTBEAT") is not None
        vehicle.mav.statustext_send(6, b"hello from the vehicle")
        assert wait_for(link.recv, "STATUSTEXT") is not None
    finally:
        link.close()
    replay = mavutil.mavlink_connection(str(tlog), dialect="ardupilotmega")
    messages = []
    while (msg := replay.recv_match()) is not None:
        messages.append(msg)
    assert [m.get_type() for m in messages] == ["HEARTBEAT", "STATUSTEXT"]
    assert (messages[0].get_srcSystem(), messages[0].get_srcComponent()) == (1, 191)  # the link sends as itself
    assert messages[1].text == "hello from the vehicle"
    assert abs(messages[0]._timestamp - time.time()) < 60  # wall-clock µs stamps, as Mission Planner expects


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (KEY, KEY),
        (KEY.hex().encode() + b"\n", KEY),
        (b"my secret passphrase\n", hashlib.sha256(b"my secret passphrase").digest()),
    ],
    ids=["raw", "hex", "passphrase"],
)
def test_signing_key_files(tmp_path, content, expected):
    path = tmp_path / "key"
    path.write_bytes(content)
    assert load_signing_key(path) == expected


def test_empty_signing_key_file_is_refused(tmp_path):
    (tmp_path / "key").write_bytes(b"\n")
    with pytest.raises(ValueError, match="empty signing key"):
        load_signing_key(tmp_path / "key")
