"""Hostile bytes on the MAVLink line: noise, truncated and corrupted packets, absurd values, other systems.

The bytes go through pymavlink's own parser exactly as a serial line's would (``mavfile.recv_msg``,
robust parsing on, as mavutil sets it), so the reader sees what a noisy line gives it: BAD_DATA and
now and then a packet whose CRC happens to check out. The reader must never raise, the blackboard
must never hold a non-finite number or an impossible fact, and nobody but the autopilot may change
what the blackboard says about the vehicle.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import struct
from collections.abc import Iterator
from typing import Any

import py_trees
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer, waypoint_items
from executive.io.mavlink.reader import MavlinkReader
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage, encoder, mavlink, mavutil
from executive.world.vehicles import PROFILES

FUZZ = settings(derandomize=True, deadline=None, max_examples=60, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
AUTOPILOT = (1, 1)
READER_KEYS = [k for k in blackboard.KEYS if k.startswith(("/link/", "/vehicle/", "/rc/"))]
VEHICLE_KEYS = [
    k for k in READER_KEYS if k.startswith(("/vehicle/", "/rc/")) or k in ("/link/system_id", "/link/component_id", "/link/last_heartbeat")
]
HANDLED = [
    "HEARTBEAT", "GLOBAL_POSITION_INT", "ATTITUDE", "EKF_STATUS_REPORT", "SYS_STATUS", "RC_CHANNELS", "COMMAND_ACK", "STATUSTEXT", "HOME_POSITION",
    "VFR_HUD", "GPS_RAW_INT", "SERVO_OUTPUT_RAW", "EXTENDED_SYS_STATE", "DISTANCE_SENSOR", "RANGEFINDER", "MISSION_REQUEST_INT", "MISSION_REQUEST",
    "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_CURRENT", "MISSION_ITEM_REACHED", "COMMAND_LONG",
]  # fmt: skip
CLASSES = {cls.msgname: cls for cls in mavlink.mavlink_map.values()}
HANDLED_IDS = [CLASSES[name].id for name in HANDLED]


class NoisyLine(mavutil.mavfile):
    """A serial line as pymavlink reads it: bytes are queued, ``recv(n)`` hands out at most ``n`` (and at most ``chunk``) at a time."""

    def __init__(self) -> None:
        super().__init__(None, "noise", source_system=1, source_component=191)
        self.pending = bytearray()
        self.chunk = 1 << 16
        self.written: list[bytes] = []

    def recv(self, n: int | None = None) -> bytes:
        size = min(n or 1, self.chunk, len(self.pending))
        data = bytes(self.pending[:size])
        del self.pending[:size]
        return data

    def write(self, buf: bytes) -> int:
        self.written.append(bytes(buf))
        return len(buf)

    def close(self) -> None:
        pass


class NoisyLink:
    """The executive's Link over a :class:`NoisyLine`: what PymavlinkLink does with a serial port."""

    def __init__(self) -> None:
        self.line = NoisyLine()

    def recv(self) -> MAVLinkMessage | None:
        return self.line.recv_msg()

    def send(self, msg: MAVLinkMessage) -> None:
        self.line.mav.send(msg)

    def close(self) -> None:
        pass


class ReaderOnNoisyLine:
    """The MAVLink reader (with a commander and a mission transfer) over a :class:`NoisyLink`, on a clean blackboard, ticked by hand."""

    def __init__(self) -> None:
        blackboard.reset()
        self.clock = ManualClock(start=100.0)
        self.link = NoisyLink()
        self.commander = Commander(self.link, self.clock, PROFILES["rover"])
        self.mission = MissionTransfer(self.link, self.clock)
        self.reader = MavlinkReader(self.link, self.clock, self.commander, mission=self.mission)
        self.reconnects = 0
        self.reader.on_reconnect = self._reconnected

    def _reconnected(self) -> None:
        self.reconnects += 1

    def tick(self, data: bytes = b"", chunk: int = 1 << 16) -> int:
        """Put ``data`` on the line, then drain it as one runtime tick would (0.1 s later)."""
        self.link.line.pending += data
        self.link.line.chunk = chunk
        self.clock.advance(0.1)
        return self.reader.drain()

    def flush(self, chunk: int = 1 << 16) -> None:
        """Tick until the line is empty."""
        while self.link.line.pending:
            self.tick(chunk=chunk)


def pack(msg: Any, system: int = 1, component: int = 1, seq: int = 0) -> bytes:
    """``msg`` (an encoded message) as the bytes ``system``/``component`` would put on the wire."""
    mav = encoder(system, component)
    mav.seq = seq
    return bytes(msg.pack(mav))


def heartbeat(custom_mode: int = 4, system: int = 1, component: int = 1) -> bytes:
    mav = encoder(system, component)
    msg = mav.heartbeat_encode(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, custom_mode, mavlink.MAV_STATE_ACTIVE)
    return pack(msg, system, component)


def frame(msg_id: int, payload: bytes, system: int = 1, component: int = 1, seq: int = 0, incompat: int = 0) -> bytes:
    """A MAVLink 2 frame with a correct CRC around any payload: a packet the parser accepts as far as the CRC goes."""
    cls = mavlink.mavlink_map.get(msg_id)
    header = struct.pack("<BBBBBBBHB", 0xFD, len(payload), incompat, 0, seq, system, component, msg_id & 0xFFFF, msg_id >> 16)
    crc = mavlink.x25crc(header[1:] + payload)
    crc.accumulate(bytes([cls.crc_extra if cls else 0]))
    return header + payload + struct.pack("<H", crc.crc)


def bb(key: str) -> Any:
    return py_trees.blackboard.Blackboard.get(key)


def facts(keys: list[str]) -> dict[str, Any]:
    return {key: bb(key) for key in keys}


def _numbers(value: Any, path: str) -> Iterator[tuple[str, Any]]:
    """Every number inside a blackboard value (dataclasses, tuples), with where it is."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            yield from _numbers(getattr(value, f.name), f"{path}.{f.name}")
    elif isinstance(value, tuple | list):
        for i, v in enumerate(value):
            yield from _numbers(v, f"{path}[{i}]")
    elif isinstance(value, int | float) and not isinstance(value, bool):
        yield path, value


def assert_sane() -> None:
    """What the reader may write: finite numbers, coordinates on the globe, values inside the ranges MAVLink defines."""
    for key in READER_KEYS:
        for where, number in _numbers(bb(key), key):
            assert math.isfinite(number), f"{where} = {number}"
    for key in ("/vehicle/position", "/vehicle/home"):
        if (p := bb(key)) is not None:
            assert -90.0 <= p.lat <= 90.0 and -180.0 <= p.lon <= 180.0 and (p.lat, p.lon) != (0.0, 0.0), f"{key}: {p}"
    if (p := bb("/vehicle/position")) is not None:
        assert p.heading_deg is None or 0.0 <= p.heading_deg < 360.0, p
    if (a := bb("/vehicle/attitude")) is not None:
        assert -180.0 <= a.roll_deg <= 180.0 and -180.0 <= a.pitch_deg <= 180.0 and 0.0 <= a.yaw_deg < 360.0, a
    if (h := bb("/vehicle/heading_deg")) is not None:
        assert 0.0 <= h < 360.0
    if (s := bb("/vehicle/ground_speed_m_s")) is not None:
        assert 0.0 <= s < 1000.0
    if (e := bb("/vehicle/ekf")) is not None:
        variances = (e.velocity_variance, e.pos_horiz_variance, e.pos_vert_variance, e.compass_variance, e.terrain_alt_variance)
        assert all(v >= 0.0 for v in variances), e
    if (b := bb("/vehicle/battery")) is not None:
        assert b.remaining_pct is None or 0 <= b.remaining_pct <= 100, b
        assert b.voltage_v is None or b.voltage_v >= 0.0, b
    if (g := bb("/vehicle/gps")) is not None:
        assert g.fix_type in mavlink.enums["GPS_FIX_TYPE"], g
    channels = bb("/rc/channels")
    assert len(channels) <= 18 and all(c == 0 or 500 <= c <= 2500 for c in channels), channels
    assert bb("/rc/rssi") is None or 0 <= bb("/rc/rssi") <= 254
    if (text := bb("/vehicle/statustext")) is not None:
        assert isinstance(text[1], str) and len(text[1]) <= 50 and "\x00" not in text[1], text


# -- strategies -------------------------------------------------------------------------------------------------

_INTS = {"int8_t": 8, "int16_t": 16, "int32_t": 32, "int64_t": 64}
_UINTS = {"uint8_t": 8, "uint16_t": 16, "uint32_t": 32, "uint64_t": 64, "uint8_t_mavlink_version": 8}


@functools.cache
def _field(kind: str, length: int) -> st.SearchStrategy[Any]:
    """Any value a field of MAVLink type ``kind`` (array of ``length`` if not 0) can carry, the extremes most often."""
    if kind == "char":
        return st.binary(max_size=length)
    if kind in ("float", "double"):
        width = 32 if kind == "float" else 64
        one = st.one_of(st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, -1e-30, 3.4e38, -3.4e38]), st.floats(width=width))
    elif kind in _INTS:
        bits = _INTS[kind]
        low, high = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
        one = st.one_of(st.sampled_from([low, high, -1, 0, 1]), st.integers(low, high))
    else:
        high = (1 << _UINTS[kind]) - 1
        one = st.one_of(st.sampled_from([0, 1, high, high - 1]), st.integers(0, high))
    return st.lists(one, min_size=length, max_size=length) if length else one


@functools.cache
def absurd(name: str) -> st.SearchStrategy[Any]:
    """A message of type ``name`` whose every field holds any value its type allows (one strategy a type, made once: built again
    at every draw, hypothesis validated and labelled it again, ~40 % of the fuzzers' CPU; the examples drawn are the same)."""
    cls = CLASSES[name]
    fields = [_field(kind, length) for kind, length in zip(cls.fieldtypes, cls.array_lengths, strict=True)]
    return st.tuples(*fields).map(lambda values: cls(*values))


SEGMENT = st.one_of(
    st.binary(min_size=1, max_size=48),  # line noise
    st.builds(
        frame,
        st.sampled_from(HANDLED_IDS) | st.integers(0, 0xFFFFFF),
        st.binary(max_size=80),
        seq=st.integers(0, 255),
        incompat=st.sampled_from([0, 0, 0, 1, 0xFE]),
    ),
    st.builds(lambda data, cut: data[:cut], st.sampled_from([heartbeat(), heartbeat(system=2)]), st.integers(0, 20)),  # truncated
    st.builds(
        lambda data, at, xor: data[:at] + bytes([data[at] ^ xor]) + data[at + 1 :], st.just(heartbeat(15)), st.integers(0, 20), st.integers(1, 255)
    ),
    st.sampled_from([b"\xfd", b"\xfe", b"\x55", b"\xfd\xff", b"\xfe\xff"]),  # a magic byte, a header promising the longest payload
    st.just(heartbeat()),
)


# -- tests ------------------------------------------------------------------------------------------------------


@pytest.fixture
def on_line() -> ReaderOnNoisyLine:
    return ReaderOnNoisyLine()


@FUZZ
@given(segments=st.lists(SEGMENT, max_size=25), chunks=st.lists(st.integers(1, 300), min_size=1, max_size=6))
def test_line_noise_never_raises_nor_becomes_a_fact(segments: list[bytes], chunks: list[int]) -> None:
    """Random bytes, random-payload packets with good CRCs, truncated and corrupted packets, read in random chunks."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(heartbeat())
    data = b"".join(segments)
    for chunk in chunks:
        on_line.tick(data[:chunk], chunk=chunk)
        data = data[chunk:]
        assert_sane()
    on_line.tick(data)
    on_line.flush()
    assert_sane()
    assert on_line.reader.autopilot == AUTOPILOT


@FUZZ
@given(noise=st.binary(max_size=400), mode=st.integers(0, 30))
def test_the_reader_resynchronises_after_any_noise(noise: bytes, mode: int) -> None:
    """After any noise, 300 quiet bytes (more than the longest packet a false header can promise) and the next heartbeat is heard."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(heartbeat() + noise + b"\x00" * 300 + heartbeat(mode))
    on_line.flush()
    assert bb("/vehicle/custom_mode") == mode


@FUZZ
@given(noise=st.lists(st.binary(max_size=30).map(lambda b: b.replace(b"\xfd", b"").replace(b"\xfe", b"")), min_size=1, max_size=10))
def test_noise_without_a_magic_byte_costs_no_packet(noise: list[bytes]) -> None:
    """Noise between packets that never looks like a packet start loses nothing: every packet is counted, the last one wins."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(b"".join(n + heartbeat(mode) for mode, n in enumerate(noise)))
    on_line.flush()
    assert (bb("/link/messages"), bb("/vehicle/custom_mode")) == (len(noise), len(noise) - 1)
    assert (bb("/link/bad_data") > 0) == any(noise) and bb("/link/bad_data") <= sum(map(len, noise))  # a run of noise is one BAD_DATA or more


KEY = bytes(range(32))


def signed_heartbeat(custom_mode: int, timestamp: int) -> bytes:
    """A heartbeat from the autopilot signed with :data:`KEY` at ``timestamp`` (10 µs units since 2015)."""
    mav = encoder(1, 1)
    mav.signing.secret_key, mav.signing.sign_outgoing, mav.signing.timestamp = KEY, True, timestamp
    msg = mav.heartbeat_encode(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, custom_mode, mavlink.MAV_STATE_ACTIVE)
    return bytes(msg.pack(mav))


@FUZZ
@given(segments=st.lists(SEGMENT, max_size=20))
def test_with_signing_only_signed_packets_become_facts(segments: list[bytes]) -> None:
    """Signing on: noise, unsigned heartbeats and frames claiming a signature never change a fact; the next signed packet does."""
    on_line = ReaderOnNoisyLine()
    on_line.link.line.setup_signing(KEY, sign_outgoing=True, allow_unsigned_callback=lambda _mav, _msg_id: False)
    now = on_line.link.line.mav.signing.timestamp
    on_line.tick(signed_heartbeat(4, now + 1))
    assert (on_line.reader.autopilot, bb("/vehicle/custom_mode")) == (AUTOPILOT, 4)
    before = facts(VEHICLE_KEYS)
    on_line.tick(b"".join(segments) + heartbeat(15))
    on_line.flush()
    assert facts(VEHICLE_KEYS) == before
    on_line.tick(b"\x00" * 300 + signed_heartbeat(10, now + 2))
    on_line.flush()
    assert bb("/vehicle/custom_mode") == 10


@FUZZ
@given(messages=st.lists(st.sampled_from(HANDLED[:-1]).flatmap(absurd), min_size=1, max_size=8))
def test_absurd_values_from_the_autopilot_never_become_facts(messages: list[Any]) -> None:
    """Every field of every message the reader handles at any value its type allows (NaN, infinities, extremes)."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(heartbeat())
    for seq, msg in enumerate(messages, start=1):
        on_line.tick(pack(msg, seq=seq))
        assert_sane()


@FUZZ
@given(
    messages=st.lists(
        st.tuples(st.sampled_from(HANDLED).flatmap(absurd), st.sampled_from([(2, 1), (255, 190), (1, 191), (1, 0), (0, 0)])), min_size=1, max_size=10
    )
)
def test_other_systems_never_change_vehicle_facts(messages: list[tuple[Any, tuple[int, int]]]) -> None:
    """Once the autopilot is known, nothing another system or component says changes /vehicle, /rc or who the autopilot is."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(heartbeat(custom_mode=4))
    before, reconnects = facts(VEHICLE_KEYS), on_line.reconnects
    for msg, (system, component) in messages:
        on_line.tick(pack(msg, system, component))
    assert (facts(VEHICLE_KEYS), on_line.reconnects, on_line.reader.autopilot) == (before, reconnects, AUTOPILOT)


MISSION_REPLIES = ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_CURRENT"]


@st.composite
def mission_reply(draw: st.DrawFn) -> Any:
    """A mission-protocol message for us (any content otherwise), with a small seq/count now and then so transfers move on."""
    msg = draw(st.sampled_from(MISSION_REPLIES).flatmap(absurd))
    msg.target_system, msg.target_component = draw(st.sampled_from([0, 1])), draw(st.sampled_from([0, 191]))
    if hasattr(msg, "mission_type"):
        msg.mission_type = draw(st.sampled_from([0, 0, 0, 1, 255]))
    for name in ("seq", "count"):
        if hasattr(msg, name) and draw(st.booleans()):
            setattr(msg, name, draw(st.integers(0, 4)))
    return msg


@FUZZ
@given(operation=st.sampled_from(["upload", "download", "clear", "set_current"]), replies=st.lists(mission_reply(), min_size=1, max_size=12))
def test_absurd_mission_replies_during_a_transfer_never_raise(operation: str, replies: list[Any]) -> None:
    """Uploads, downloads, clears and set-currents answered with anything at all: the reader and the transfer never raise."""
    on_line = ReaderOnNoisyLine()
    on_line.tick(heartbeat())
    start = {
        "upload": lambda: on_line.mission.upload(waypoint_items([(47.0, 8.0), (47.001, 8.0), (47.001, 8.001)])),
        "download": on_line.mission.download,
        "clear": on_line.mission.clear,
        "set_current": lambda: on_line.mission.set_current(2),
    }
    start[operation]()
    for seq, msg in enumerate(replies, start=1):
        on_line.mission.flush()
        on_line.tick(pack(msg, seq=seq))
        assert_sane()
    on_line.clock.advance(60.0)
    for _ in range(10):  # and its retries run out
        on_line.mission.flush()
        on_line.tick()
    assert on_line.mission.status is not None


E7 = 10_000_000


def _global_position(lat: int, lon: int, hdg: int = 9000) -> Any:
    return mavlink.MAVLink_global_position_int_message(0, lat, lon, 0, 0, 0, 0, 0, hdg)


def _home(lat: int, lon: int) -> Any:
    return mavlink.MAVLink_home_position_message(lat, lon, 0, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0, 0)


def _attitude(roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0, yawspeed: float = 0.0) -> Any:
    return mavlink.MAVLink_attitude_message(0, roll, pitch, yaw, 0.0, 0.0, yawspeed)


def _sys_status(voltage_mv: int, current_ca: int, remaining: int) -> Any:
    return mavlink.MAVLink_sys_status_message(0, 0, 0, 0, voltage_mv, current_ca, remaining, 0, 0, 0, 0, 0, 0)


def _statustext(text: bytes) -> Any:
    return mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_WARNING, text, 0, 0)


@pytest.mark.parametrize(
    ("msg", "key", "expected"),
    [
        pytest.param(_global_position(90 * E7, 180 * E7), "/vehicle/position", (90.0, 180.0), id="position at the pole and the antimeridian"),
        pytest.param(_global_position(-90 * E7, -180 * E7), "/vehicle/position", (-90.0, -180.0), id="position at the other extremes"),
        pytest.param(_global_position(90 * E7 + 1, 0), "/vehicle/position", None, id="position past the pole"),
        pytest.param(_global_position(-(2**31), 2**31 - 1), "/vehicle/position", None, id="position at int32 extremes"),
        pytest.param(_global_position(0, 0), "/vehicle/position", None, id="position at 0,0 (no fix)"),
        pytest.param(_home(0, 0), "/vehicle/home", None, id="home at 0,0 (not set)"),
        pytest.param(_home(91 * E7, 0), "/vehicle/home", None, id="home past the pole"),
        pytest.param(_home(-353632610, 1491652300), "/vehicle/home", (-35.363261, 149.16523), id="home"),
    ],
)
def test_coordinates(on_line: ReaderOnNoisyLine, msg: Any, key: str, expected: tuple[float, float] | None) -> None:
    """Coordinates at the extremes of the globe are facts; past them, at int32 extremes, or 0/0 (unset) they are not."""
    on_line.tick(heartbeat() + pack(msg, seq=1))
    value = bb(key)
    assert (None if value is None else (value.lat, value.lon)) == expected


@pytest.mark.parametrize("hdg", [36000, 40000, 65534])
def test_a_heading_over_359_99_degrees_is_unknown(on_line: ReaderOnNoisyLine, hdg: int) -> None:
    """GLOBAL_POSITION_INT.hdg is 0..35999 cdeg (65535 = unknown): anything else is no heading at all."""
    on_line.tick(heartbeat() + pack(_global_position(47 * E7, 8 * E7, hdg), seq=1))
    assert bb("/vehicle/position").heading_deg is None


@pytest.mark.parametrize(
    "attitude",
    [
        _attitude(roll=math.nan),
        _attitude(pitch=math.inf),
        _attitude(yaw=-math.inf),
        _attitude(yawspeed=math.nan),
        _attitude(roll=3.4e38),
        _attitude(pitch=-100.0),
        _attitude(yaw=1e30),
        _attitude(yawspeed=3.4e38),
    ],
    ids=["roll nan", "pitch inf", "yaw -inf", "yawspeed nan", "roll 3.4e38", "pitch -100 rad", "yaw 1e30", "yawspeed 3.4e38"],
)
def test_an_impossible_attitude_is_dropped(on_line: ReaderOnNoisyLine, attitude: Any) -> None:
    """The last good attitude stays; a non-finite or impossible one never replaces it."""
    on_line.tick(heartbeat() + pack(_attitude(0.1, 0.2, 0.3), seq=1))
    good = bb("/vehicle/attitude")
    on_line.tick(pack(attitude, seq=2))
    assert bb("/vehicle/attitude") == good


def test_a_yaw_given_in_0_to_2pi_is_kept(on_line: ReaderOnNoisyLine) -> None:
    """Some autopilots send yaw in [0, 2pi) rather than (-pi, pi]: still an attitude."""
    on_line.tick(heartbeat() + pack(_attitude(yaw=4.0), seq=1))
    assert bb("/vehicle/attitude").yaw_deg == pytest.approx(math.degrees(4.0))


def test_a_yaw_a_hair_below_zero_is_within_0_to_360(on_line: ReaderOnNoisyLine) -> None:
    """-1e-30 rad % 360 is 360.0 in floating point: the yaw must still be in [0, 360)."""
    on_line.tick(heartbeat() + pack(_attitude(yaw=-1e-30), seq=1))
    assert 0.0 <= bb("/vehicle/attitude").yaw_deg < 360.0


@pytest.mark.parametrize(
    "report",
    [
        mavlink.MAVLink_ekf_status_report_message(831, math.nan, 0.1, 0.1, 0.1, 0.1, 0),
        mavlink.MAVLink_ekf_status_report_message(831, 0.1, math.inf, 0.1, 0.1, 0.1, 0),
        mavlink.MAVLink_ekf_status_report_message(831, 0.1, 0.1, 0.1, -0.5, 0.1, 0),
    ],
    ids=["nan", "inf", "negative variance"],
)
def test_an_impossible_ekf_report_is_dropped(on_line: ReaderOnNoisyLine, report: Any) -> None:
    """Variances are finite and not negative: a report saying otherwise leaves the last good one."""
    on_line.tick(heartbeat() + pack(mavlink.MAVLink_ekf_status_report_message(831, 0.1, 0.1, 0.1, 0.1, 0.1, 0), seq=1))
    good = bb("/vehicle/ekf")
    on_line.tick(pack(report, seq=2))
    assert bb("/vehicle/ekf") == good


@pytest.mark.parametrize(
    ("status", "expected"),
    [
        (_sys_status(12600, 150, 80), (12.6, 1.5, 80)),
        (_sys_status(65535, -1, -1), (None, None, None)),
        (_sys_status(65534, -32768, -128), (65.534, -327.68, None)),
        (_sys_status(0, 32767, 127), (0.0, 327.67, None)),
        (_sys_status(12600, -250, 101), (12.6, -2.5, None)),
    ],
    ids=["normal", "unknown", "negative remaining", "remaining over 100", "charging, 101 percent"],
)
def test_battery_remaining_outside_0_to_100_is_unknown(on_line: ReaderOnNoisyLine, status: Any, expected: tuple[Any, ...]) -> None:
    """SYS_STATUS.battery_remaining is 0..100 or -1 (unknown): anything else is unknown, not a charge."""
    on_line.tick(heartbeat() + pack(status, seq=1))
    battery = bb("/vehicle/battery")
    assert (battery.voltage_v, battery.current_a, battery.remaining_pct) == expected


def test_a_mode_number_that_does_not_exist_is_named_by_number(on_line: ReaderOnNoisyLine) -> None:
    on_line.tick(heartbeat(custom_mode=2**32 - 1))
    assert (bb("/vehicle/mode"), bb("/vehicle/custom_mode")) == (f"MODE({2**32 - 1})", 2**32 - 1)


def test_every_channel_field_is_read_whatever_chancount_says_and_unused_channels_are_no_signal(on_line: ReaderOnNoisyLine) -> None:
    """chancount 255 or 8: the 18 channels the message has (ArduPilot acts on channel 9 with chancount 8, issue 13);
    UINT16_MAX (unused) and nonsense PWM are 0 (no signal)."""
    channels = [1500, 65535, 1900, 40000, 499, 2501] + [1000] * 12
    on_line.tick(heartbeat() + pack(mavlink.MAVLink_rc_channels_message(0, 255, *channels, 254), seq=1))
    assert bb("/rc/channels") == (1500, 0, 1900, 0, 0, 0) + (1000,) * 12
    on_line.tick(pack(mavlink.MAVLink_rc_channels_message(0, 8, *([65535] * 8), 1500, *([65535] * 9), 254), seq=2))
    assert bb("/rc/channels") == (0,) * 8 + (1500,) + (0,) * 9
    on_line.tick(pack(mavlink.MAVLink_rc_channels_message(0, 8, *([65535] * 18), 255), seq=3))
    assert (bb("/rc/channels"), bb("/rc/connected"), bb("/rc/rssi")) == ((0,) * 18, False, None)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (b"\xff\xfe PreArm: bad \xc3", "\ufffd\ufffd PreArm: bad \ufffd"),
        (b"x" * 50, "x" * 50),
        (b"half\x00hidden", "half"),
        (b"\xe2\x82", "\ufffd\ufffd"),
    ],
    ids=["invalid utf-8", "50 bytes, no terminator", "nul inside", "truncated sequence"],
)
def test_statustext_is_text_whatever_the_bytes(on_line: ReaderOnNoisyLine, text: bytes, expected: str) -> None:
    on_line.tick(heartbeat() + pack(_statustext(text), seq=1))
    assert bb("/vehicle/statustext") == (mavlink.MAV_SEVERITY_WARNING, expected)


def test_a_gps_fix_type_that_does_not_exist_is_no_fix(on_line: ReaderOnNoisyLine) -> None:
    """GPS_RAW_INT.fix_type 200 is not a 3D fix (nor any fix): the report is dropped."""
    on_line.tick(heartbeat() + pack(mavlink.MAVLink_gps_raw_int_message(0, 3, 0, 0, 0, 120, 65535, 0, 0, 11), seq=1))
    good = bb("/vehicle/gps")
    on_line.tick(pack(mavlink.MAVLink_gps_raw_int_message(0, 200, 0, 0, 0, 120, 65535, 0, 0, 11), seq=2))
    assert bb("/vehicle/gps") == good


@pytest.mark.parametrize("heading", [-1, 361, 32767, -32768])
def test_a_vfr_hud_heading_outside_0_to_360_is_dropped(on_line: ReaderOnNoisyLine, heading: int) -> None:
    on_line.tick(heartbeat() + pack(mavlink.MAVLink_vfr_hud_message(0.0, 2.0, 90, 50, 0.0, 0.0), seq=1))
    on_line.tick(pack(mavlink.MAVLink_vfr_hud_message(0.0, 2.0, heading, 50, 0.0, 0.0), seq=2))
    assert bb("/vehicle/heading_deg") == 90.0
