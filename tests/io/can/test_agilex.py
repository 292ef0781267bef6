"""AgileX protocol v2 frames: the thesis's captured frame, exact bytes, round trips, and fuzzing (decode never raises)."""

from __future__ import annotations

import logging

import can
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from executive.io.can import agilex
from executive.io.can.agilex import KNOWN_IDS, ControlModeSelect, FrameStats, MotionCommand, MotionState, Odometry, RcState, SystemState, decode
from executive.world.state import SwitchPosition

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def frame(arbitration_id: int, hex_bytes: str, **kwargs: object) -> can.Message:
    return can.Message(arbitration_id=arbitration_id, data=bytes.fromhex(hex_bytes), is_extended_id=False, **kwargs)  # type: ignore[arg-type]


def test_the_captured_frame_decodes_as_the_spec_says() -> None:
    rc = decode(frame(0x241, "A6 00 00 B0 00 00 00 7E"))
    assert rc == RcState(swa=UP, swb=MIDDLE, swc=UP, swd=UP, right_lr=0, right_ud=0, left_lr=-80, left_ud=0, knob=0, counter=0x7E)
    assert rc.valid


@pytest.mark.parametrize(
    ("byte0", "positions"),
    [
        (0b10_10_10_10, (UP, UP, UP, UP)),
        (0b11_11_11_11, (DOWN, DOWN, DOWN, DOWN)),
        (0b10_01_01_11, (DOWN, MIDDLE, MIDDLE, UP)),  # SWA bits 0-1 = 3, SWB bits 2-3 = 1, SWC bits 4-5 = 1, SWD bits 6-7 = 2
        (0b11_01_10_10, (UP, UP, MIDDLE, DOWN)),
    ],
)
def test_switch_bits(byte0: int, positions: tuple[SwitchPosition, ...]) -> None:
    rc = decode(frame(0x241, f"{byte0:02X} 00 00 00 00 00 00 00"))
    assert (rc.swa, rc.swb, rc.swc, rc.swd) == positions
    assert rc.valid


@pytest.mark.parametrize(
    ("byte0", "which"),
    [(0b10_10_10_01, "swa"), (0b01_10_10_10, "swd"), (0b10_10_00_10, "swb"), (0b10_00_10_10, "swc"), (0x00, "swa")],
)
def test_a_switch_code_it_cannot_have_is_none_and_the_frame_invalid(byte0: int, which: str) -> None:
    rc = decode(frame(0x241, f"{byte0:02X} 00 00 00 00 00 00 05"))
    assert getattr(rc, which) is None
    assert not rc.valid
    assert rc.counter == 5


def test_sticks_and_knob_are_signed_and_out_of_range_is_invalid() -> None:
    rc = decode(frame(0x241, "AA 64 9C 01 FF D8 00 10"))
    assert (rc.right_lr, rc.right_ud, rc.left_lr, rc.left_ud, rc.knob) == (100, -100, 1, -1, -40)
    assert rc.valid
    assert not decode(frame(0x241, "AA 65 00 00 00 00 00 10")).valid  # 101
    assert not decode(frame(0x241, "AA 00 00 00 00 80 00 10")).valid  # knob -128


def test_system_state_layout() -> None:
    system = decode(frame(0x211, "00 01 01 E6 00 04 00 2A"))
    assert system == SystemState(vehicle_state=0, control_mode=1, battery_dv=486, fault_code=0x0004, counter=42)
    assert system.battery_v == pytest.approx(48.6)
    assert system.rc_signal_lost
    assert system.faults == ("RC_SIGNAL_LOSS",)
    assert system.valid


def test_system_state_faults_and_the_old_sdk_rc_loss_byte() -> None:
    old_layout = decode(frame(0x211, "00 00 01 E6 04 00 00 00"))  # ugv_sdk 1.x: byte 4 alone, 0x04 = RC signal loss
    assert old_layout.rc_signal_lost
    assert old_layout.faults == ("RC_SIGNAL_LOSS",)
    many = decode(frame(0x211, "02 00 00 F0 81 03 00 00"))
    assert many.faults == ("BATTERY_LOW_FAULT", "BATTERY_LOW_WARNING", "MOTOR_DRIVER", "BIT15")
    assert not many.rc_signal_lost
    assert not decode(frame(0x211, "03 00 01 E6 00 00 00 00")).valid  # no vehicle state 3
    assert not decode(frame(0x211, "00 07 01 E6 00 00 00 00")).valid  # no control mode 7


def test_motion_state_odometry_command_and_mode_select_layouts() -> None:
    assert decode(frame(0x221, "01 F4 FF 38 00 00 00 00")) == MotionState(500, -200)
    assert decode(frame(0x221, "01 F4 FF 38 00 00 00 00")).angular_rad_s == pytest.approx(-0.2)
    assert decode(frame(0x311, "00 00 30 39 FF FF FF FE")) == Odometry(12345, -2)
    assert decode(frame(0x111, "00 96 00 C8 00 00 00 00")) == MotionCommand(150, 200)  # the Bunker manual's 0.15 m/s and 0.2 rad/s
    assert decode(frame(0x421, "01")) == ControlModeSelect(1)
    assert decode(frame(0x421, "01 00 00 00 00 00 00 00")) == ControlModeSelect(1)


def test_exact_command_bytes() -> None:
    assert MotionCommand.from_si(0.2, -0.3).encode().data == bytes.fromhex("00 C8 FE D4 00 00 00 00")
    assert ControlModeSelect().encode().data == bytes.fromhex("01 00 00 00 00 00 00 00")
    msg = MotionCommand.from_si(-1.5, 2.0).encode()
    assert (msg.arbitration_id, msg.is_extended_id, msg.dlc) == (0x111, False, 8)
    assert msg.data == bytes.fromhex("FA 24 07 D0 00 00 00 00")
    with pytest.raises(ValueError, match="out of range"):
        MotionCommand.from_si(40.0, 0.0)


VALID_FRAMES = [
    RcState(UP, MIDDLE, UP, UP, 0, 0, -80, 0, 0, 0x7E),
    RcState(DOWN, DOWN, DOWN, DOWN, 100, -100, 55, -55, -100, 0),
    SystemState(2, 1, 486, 0x0205, 255),
    MotionState(-32768, 32767),
    Odometry(2**31 - 1, -(2**31)),
    MotionCommand(1500, -2000),
    ControlModeSelect(0),
]


@pytest.mark.parametrize("original", VALID_FRAMES, ids=lambda f: type(f).__name__)
def test_round_trip(original: object) -> None:
    msg = original.encode()  # type: ignore[attr-defined]
    assert len(msg.data) == 8
    assert decode(msg) == original


def test_encoding_a_position_a_switch_does_not_have_raises() -> None:
    with pytest.raises(ValueError, match="SWA"):
        RcState(MIDDLE, MIDDLE, UP, UP, 0, 0, 0, 0, 0, 0).encode()


@pytest.mark.parametrize(
    "msg",
    [
        frame(0x241, "A6 00 00 B0 00 00 7E"),  # 7 bytes
        frame(0x241, ""),
        frame(0x211, "00 01 01 E6 00 00 00 2A 00 00 00 00", is_fd=True),  # 12 bytes
        frame(0x421, ""),
        can.Message(arbitration_id=0x241, data=bytes.fromhex("A60000B00000007E"), is_extended_id=True),
        can.Message(arbitration_id=0x241, is_remote_frame=True, dlc=8, is_extended_id=False),
        can.Message(is_error_frame=True),
        frame(0x251, "00 00 00 0A 00 00 01 2C"),
    ],
)
def test_frames_it_cannot_read_are_none(msg: can.Message) -> None:
    assert decode(msg) is None


def test_frame_stats_tell_bad_from_other() -> None:
    stats = FrameStats()
    for msg in (frame(0x241, "A6 00 00 B0 00 00 00 7E"), frame(0x241, "A6"), frame(0x241, "00 00 00 00 00 00 00 01"), frame(0x123, "00")):
        stats.record(msg, decode(msg))
    assert (stats.frames, stats.bad, stats.other, stats.per_id[0x241]) == (4, 2, 1, 3)


@settings(max_examples=500, deadline=None)
@given(
    arbitration_id=st.one_of(st.sampled_from(sorted(KNOWN_IDS)), st.integers(0, 0x1FFFFFFF)),
    data=st.binary(min_size=0, max_size=64),
    extended=st.booleans(),
    remote=st.booleans(),
)
def test_decode_never_raises(arbitration_id: int, data: bytes, extended: bool, remote: bool) -> None:
    try:
        msg = can.Message(arbitration_id=arbitration_id, data=data, is_extended_id=extended, is_remote_frame=remote, is_fd=len(data) > 8, check=False)
    except Exception:  # python-can refused to build it: not something a bus can deliver
        return
    result = decode(msg)
    stats = FrameStats()
    stats.record(msg, result)
    if result is not None:
        assert arbitration_id == type(result).ID and not extended and len(data) >= 1
        result.describe()
        result.fields()


@settings(max_examples=500, deadline=None)
@given(data=st.binary(min_size=8, max_size=8), arbitration_id=st.sampled_from([0x211, 0x221, 0x241, 0x311, 0x111]))
def test_every_8_byte_payload_of_a_known_id_decodes(data: bytes, arbitration_id: int) -> None:
    decoded = decode(can.Message(arbitration_id=arbitration_id, data=data, is_extended_id=False))
    assert decoded is not None
    if decoded.valid:  # a valid frame re-encodes to the same meaning
        assert decode(decoded.encode()) == decoded


def test_a_decoder_bug_is_logged_once_per_kind_with_the_frame_id_and_still_counted_bad(monkeypatch, caplog) -> None:
    monkeypatch.setattr(agilex, "_FAILURES_SAID", set())

    def broken(data: bytes) -> None:
        raise IndexError("a decoder bug")

    monkeypatch.setattr(RcState, "from_data", broken)
    monkeypatch.setattr(SystemState, "from_data", broken)
    stats = FrameStats()
    with caplog.at_level(logging.ERROR, logger="executive.io.can.agilex"):
        for msg in (frame(0x241, "A6 00 00 B0 00 00 00 7E"), frame(0x241, "00" * 8), frame(0x211, "00" * 8), frame(0x221, "00" * 8)):
            stats.record(msg, decode(msg))
    said = [r.getMessage() for r in caplog.records]
    assert said == [
        "CAN frame 0x241: the AgileX decoder raised IndexError (counted as a bad frame; said once)",
        "CAN frame 0x211: the AgileX decoder raised IndexError (counted as a bad frame; said once)",
    ]
    assert caplog.records[0].exc_info is not None  # with the decoder's traceback
    assert (stats.frames, stats.bad) == (4, 3)  # the motion state (0x221) decoded
