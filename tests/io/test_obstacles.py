"""Camera obstacle distances: parsed strictly, put on the blackboard, forwarded once and fresh as OBSTACLE_DISTANCE."""

from __future__ import annotations

import json
import socket
from collections.abc import Iterator

import py_trees
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from executive.io.mavlink.link import MemoryLink
from executive.io.obstacles import (
    STALE_S,
    UNKNOWN_CM,
    ObstacleForwarder,
    ObstacleReceiver,
    ObstacleScan,
    ObstacleSpecError,
    ScanError,
    encode,
    open_endpoint,
    parse_endpoint,
    parse_scan,
)
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink


def scan_bytes(**fields: object) -> bytes:
    return json.dumps({"distances_cm": [400, 380], "increment_deg": 1.5, **fields}).encode()


def bb(key: str) -> object:
    return py_trees.blackboard.Blackboard.get(key)


def test_a_scan_with_defaults_is_centred_ahead():
    scan = parse_scan(b'{"distances_cm": [400, null, 2000, 0], "increment_deg": 2}', 12.5)
    assert scan == ObstacleScan((400, None, 2000, 0), 2.0, -3.0, 20, 1000, 12.5)
    assert scan.closest_m() == 4.0  # 0 cm is under min_cm (20), 2000 beyond max_cm: neither is an obstacle


def test_a_scan_says_where_and_how_far_it_sees():
    scan = parse_scan(scan_bytes(angle_offset_deg=-90, min_cm=50, max_cm=800, distances_cm=[49.6, 300.4, None]), 0.0)
    assert (scan.distances_cm, scan.angle_offset_deg, scan.min_cm, scan.max_cm) == ((50, 300, None), -90.0, 50, 800)


@pytest.mark.parametrize(
    ("data", "field", "why"),
    [
        (b"\xff\xfe", "datagram", "not JSON"),
        (b"{", "datagram", "not JSON"),
        (b"[1, 2]", "datagram", "expected a JSON object, got list"),
        (b"[" * 100_000, "datagram", "nested too deeply"),
        (scan_bytes(colour="red"), "colour", "unknown field"),
        (b'{"increment_deg": 1}', "distances_cm", "missing"),
        (b'{"distances_cm": [1]}', "increment_deg", "missing"),
        (scan_bytes(distances_cm=[]), "distances_cm", "1 to 72 distances, got 0 values"),
        (scan_bytes(distances_cm=[100] * 73), "distances_cm", "got 73 values"),
        (scan_bytes(distances_cm="400"), "distances_cm", "got str"),
        (scan_bytes(distances_cm=[100, -1]), "distances_cm[1]", "-1 cm is outside [0, 65534]"),
        (scan_bytes(distances_cm=[100, 65535]), "distances_cm[1]", "outside"),
        (scan_bytes(distances_cm=[100, "far"]), "distances_cm[1]", "expected a number, got str"),
        (scan_bytes(distances_cm=[True]), "distances_cm[0]", "expected a number, got bool"),
        (b'{"distances_cm": [NaN], "increment_deg": 1}', "distances_cm[0]", "nan is not a finite number"),
        (scan_bytes(increment_deg=0), "increment_deg", "must cover more than 0°"),
        (scan_bytes(increment_deg=-5), "increment_deg", "must cover more than 0°"),
        (scan_bytes(increment_deg=200), "increment_deg", "at most 360°"),
        (b'{"distances_cm": [1], "increment_deg": Infinity}', "increment_deg", "not a finite number"),
        (scan_bytes(angle_offset_deg=400), "angle_offset_deg", "outside [-360, 360]"),
        (scan_bytes(min_cm=500, max_cm=400), "max_cm", "must be above min_cm (500)"),
        (scan_bytes(max_cm=65534), "max_cm", "below 65534"),
    ],
)
def test_a_datagram_that_is_not_a_scan_is_refused_naming_the_field(data, field, why):
    with pytest.raises(ScanError) as caught:
        parse_scan(data, 0.0)
    assert caught.value.field == field
    assert str(caught.value).startswith(f"{field}: ") and why in str(caught.value)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=400))
def test_random_bytes_are_a_scan_or_a_scan_error(data):
    try:
        scan = parse_scan(data, 0.0)
    except ScanError:
        return
    assert 1 <= len(scan.distances_cm) <= 72


_json = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**6), 10**6) | st.floats(allow_nan=True) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=80) | st.dictionaries(st.sampled_from(["distances_cm", "increment_deg", "min_cm", "max_cm", "x"]), inner),
    max_leaves=100,
)


@settings(max_examples=100, deadline=None)
@given(_json)
def test_random_json_is_a_scan_or_a_scan_error(obj):
    try:
        scan = parse_scan(json.dumps(obj).encode(), 0.0)
    except ScanError:
        return
    assert all(d is None or 0 <= d < UNKNOWN_CM for d in scan.distances_cm)
    assert 0.0 < scan.increment_deg * len(scan.distances_cm) <= 360.0 and scan.min_cm < scan.max_cm


def test_obstacle_distance_as_the_autopilot_receives_it():
    scan = ObstacleScan((400, None, 1500, 0), 1.5, -2.25, 20, 1000, 3.0)
    mav = mavlink.MAVLink(None)
    received = mavlink.MAVLink(None).parse_buffer(encode(mav, scan, mavlink.MAV_DISTANCE_SENSOR_LASER).pack(mav))
    assert received is not None and len(received) == 1
    msg = received[0]
    assert msg.get_type() == "OBSTACLE_DISTANCE"
    assert list(msg.distances) == [400, UNKNOWN_CM, 1001, 0] + [UNKNOWN_CM] * 68  # beyond range: max + 1, "no obstacle"
    assert (msg.increment, msg.increment_f, msg.angle_offset, msg.min_distance, msg.max_distance) == (0, 1.5, -2.25, 20, 1000)
    assert (msg.frame, msg.sensor_type, msg.time_usec) == (mavlink.MAV_FRAME_BODY_FRD, mavlink.MAV_DISTANCE_SENSOR_LASER, 3_000_000)
    whole = encode(mav, ObstacleScan((400,), 5.0, 0.0, 20, 1000, 0.0), 0)
    assert (whole.increment, whole.increment_f) == (5, 5.0)


@pytest.mark.parametrize("spec", ["udpin:0.0.0.0:14600", "udp:127.0.0.1:0"])
def test_an_endpoint_is_udpin_host_port(spec):
    host, port = parse_endpoint(spec)
    assert (host, str(port)) == tuple(spec.split(":")[1:])


@pytest.mark.parametrize("spec", ["14600", "udpin:14600", "tcp:0.0.0.0:14600", "udpin:0.0.0.0:port", "udpin:0.0.0.0:70000", "udpin::1"])
def test_anything_else_is_not_an_endpoint(spec):
    with pytest.raises(ObstacleSpecError, match="expected udpin:HOST:PORT"):
        parse_endpoint(spec)


@pytest.fixture
def camera_port() -> Iterator[tuple[socket.socket, socket.socket]]:
    """(the executive's bound socket, the camera's socket sending to it) over loopback UDP."""
    listening = open_endpoint("udpin:127.0.0.1:0")
    camera = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    camera.connect(listening.getsockname())
    yield listening, camera
    camera.close()
    listening.close()


def test_the_receiver_keeps_the_latest_valid_scan_and_counts_the_rest(camera_port, clock: ManualClock):
    listening, camera = camera_port
    receiver = ObstacleReceiver(listening, clock)
    assert receiver.drain() == 0  # nothing yet: returns at once
    for data in (scan_bytes(distances_cm=[300]), b"\x00garbage", scan_bytes(distances_cm=[250]), scan_bytes(max_cm=1e9)):
        camera.send(data)
    deadline = 200
    arrived = 0
    while arrived < 4 and deadline:
        arrived += receiver.drain()
        deadline -= 1
    assert arrived == 4
    scan = bb("/obstacles/scan")
    assert isinstance(scan, ObstacleScan) and scan.distances_cm == (250,) and scan.time == clock.now()
    assert (bb("/obstacles/received"), bb("/obstacles/rejected")) == (2, 2)
    assert bb("/obstacles/last_error") == "max_cm: 1e+09 cm is outside [0, 65534]"


def test_the_forwarder_sends_each_new_scan_once_and_never_a_stale_one(clock: ManualClock):
    link = MemoryLink()
    forwarder = ObstacleForwarder(link, clock)
    camera = blackboard.writer("test camera", ["/obstacles/scan"])
    forwarder.service()
    assert link.sent == []  # no scan yet
    first = ObstacleScan((400,), 5.0, 0.0, 20, 1000, clock.now())
    camera.set("/obstacles/scan", first)
    forwarder.service()
    forwarder.service()  # the same scan: not again
    assert [m.distances[0] for m in link.sent] == [400]
    clock.advance(STALE_S + 0.1)
    camera.set("/obstacles/scan", ObstacleScan((300,), 5.0, 0.0, 20, 1000, clock.now() - STALE_S - 0.01))
    forwarder.service()  # the camera's last word, too old to be the truth now: the autopilot times out instead
    assert len(link.sent) == 1
    camera.set("/obstacles/scan", ObstacleScan((200,), 5.0, 0.0, 20, 1000, clock.now()))
    forwarder.service()
    assert [m.distances[0] for m in link.sent] == [400, 200] and bb("/obstacles/forwarded") == 2
