"""Skimming: what the reader does not read is framed, checked and counted, never decoded; what it reads is decoded as before."""

from __future__ import annotations

import pytest

from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.skim import BOOT_TIME_OFFSETS, Skimmer, UnreadMessage
from executive.world.dialect import encoder, mavlink

BOOT_MS = 123_456_789


def skimming_parser(read: frozenset[str]) -> mavlink.MAVLink:
    """pymavlink's parser as the executive's link has it: robust, with the skimmer in place of its decode."""
    mav = mavlink.MAVLink(None)
    mav.robust_parsing = True
    mav.decode = Skimmer(mav, read)
    return mav


def with_boot_time(cls: type[mavlink.MAVLink_message]) -> mavlink.MAVLink_message:
    """A message of kind ``cls``: ``time_boot_ms`` set, every other field zero (so that MAVLink 2 cuts the payload's trailing zeros)."""
    args: list[object] = []
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))  # array lengths are in wire order
    for name, kind in zip(cls.fieldnames, cls.fieldtypes, strict=True):
        length = lengths[name]
        if name == "time_boot_ms":
            args.append(BOOT_MS)
        elif kind == "char":
            args.append(b"")
        elif length:
            args.append([0] * length)
        else:
            args.append(0.0 if kind in ("float", "double") else 0)
    return cls(*args)


@pytest.fixture
def reader(link, clock, commander) -> MavlinkReader:
    return MavlinkReader(link, clock, commander, link_timeout_s=3.0)


@pytest.fixture
def reader_kinds(reader) -> frozenset[str]:
    return reader.kinds_read


def test_every_kind_carrying_a_boot_time_gives_it_undecoded(reader_kinds):
    sender = encoder(1, 1)
    skimmed = [cls for cls in mavlink.mavlink_map.values() if cls.id in BOOT_TIME_OFFSETS and cls.msgname not in reader_kinds]
    assert len(skimmed) > 30
    for seq, cls in enumerate(skimmed):
        sender.seq = seq
        (msg,) = skimming_parser(reader_kinds).parse_buffer(with_boot_time(cls).pack(sender))
        assert isinstance(msg, UnreadMessage), cls.msgname
        assert (msg.get_type(), msg.get_seq(), msg.get_srcSystem(), msg.get_srcComponent()) == (cls.msgname, seq, 1, 1)
        assert msg.time_boot_ms == BOOT_MS, cls.msgname


def test_kinds_read_are_decoded_in_full(reader_kinds):
    buf = encoder(1, 1).attitude_encode(BOOT_MS, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0).pack(encoder(1, 1))
    (msg,) = skimming_parser(reader_kinds).parse_buffer(buf)
    assert not isinstance(msg, UnreadMessage)
    assert (msg.get_type(), msg.yaw) == ("ATTITUDE", pytest.approx(0.3))


def test_a_damaged_unread_message_is_bad_data_as_pymavlink_says(reader_kinds):
    buf = bytearray(encoder(1, 1).vibration_encode(1, 0.1, 0.1, 0.1, 0, 0, 0).pack(encoder(1, 1)))
    buf[12] ^= 0xFF
    (msg,) = skimming_parser(reader_kinds).parse_buffer(bytes(buf))
    assert msg.get_type() == "BAD_DATA"
    assert "invalid MAVLink CRC" in msg.reason


def test_a_link_that_checks_signatures_still_refuses_unsigned_unread_messages(reader_kinds):
    mav = skimming_parser(reader_kinds)
    mav.signing.secret_key = bytes(range(32))
    mav.signing.allow_unsigned_callback = lambda _mav, _msg_id: False
    (msg,) = mav.parse_buffer(encoder(1, 1).vibration_encode(1, 0.1, 0.1, 0.1, 0, 0, 0).pack(encoder(1, 1)))
    assert msg.get_type() == "BAD_DATA"
    assert mav.signing.reject_count == 1


def test_the_reader_counts_unread_messages_for_the_links_health_and_sees_a_reboot_in_them(reader, link, reader_kinds):
    sender, mav = encoder(1, 1), skimming_parser(reader_kinds)

    def receive(*messages: mavlink.MAVLink_message) -> None:
        for msg in messages:
            link.incoming.extend(mav.parse_buffer(msg.pack(sender)))
            sender.seq += 1  # as MAVLink.send does
        reader.drain()

    receive(sender.heartbeat_encode(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, mavlink.MAV_STATE_STANDBY))
    assert reader.autopilot == (1, 1)
    receive(sender.system_time_encode(0, 600_000), sender.system_time_encode(0, 601_000))
    sender.seq += 5  # five lost on the way
    receive(sender.system_time_encode(0, 602_000))
    assert (reader.health.received, reader.health.lost, reader.health.reboots) == (4, 5, 0)
    receive(sender.system_time_encode(0, 900))  # its boot time went back: the autopilot rebooted
    assert reader.health.reboots == 1
