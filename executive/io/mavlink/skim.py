"""Messages the reader has no use for: framed and checked as pymavlink does, their payload left undecoded.

An ArduPilot streams on a companion port many messages the executive never reads (RAW_IMU,
SCALED_IMU2, VIBRATION, AHRS2... at 4-10 Hz each: two thirds of what arrives in the benchmarks'
stream). pymavlink decodes every one (payload unpacked, fields reordered, a message object built);
the reader needs only their header (the source, the sequence for the link's health) and, where they
carry it, ``time_boot_ms`` (a reboot shows there). :class:`Skimmer` stands in for one connection's
``MAVLink.decode``: a message of a kind outside those read comes out as an :class:`UnreadMessage`
once its length and checksum are found good; anything else (a kind read, a signed packet, a link
that checks signatures, a bad frame) goes through pymavlink's own decode, errors and all.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Callable, Collection

from executive.world.dialect import MAVLinkMessage, mavlink

_HEADER_LEN = 10  # MAVLink 2: magic, len, incompat, compat, seq, sysid, compid, msgid (3 bytes)
_CRC_LEN = 2


def _offset_of(cls: type[MAVLinkMessage], field: str) -> int:
    """Where ``field`` starts in the payload on the wire (fields are sent by size, arrays whole)."""
    items = re.findall(r"\d*[a-zA-Z]", cls.unpacker.format.lstrip("<"))  # one per field, in wire order
    return struct.calcsize("<" + "".join(items[: cls.ordered_fieldnames.index(field)]))


#: msgid -> offset of ``time_boot_ms`` in the payload, for every kind that carries it as a uint32.
BOOT_TIME_OFFSETS: dict[int, int] = {
    cls.id: _offset_of(cls, "time_boot_ms") for cls in mavlink.mavlink_map.values() if "time_boot_ms" in cls.fieldnames
}


class UnreadMessage(mavlink.MAVLink_message):
    """A message of a kind the reader does not read: its header, its bytes, and ``time_boot_ms`` if its kind carries one."""

    time_boot_ms: int

    def __init__(self, cls: type[MAVLinkMessage], msgbuf: bytearray, crc: int) -> None:
        super().__init__(cls.id, cls.msgname)
        self._header = mavlink.MAVLink_header(cls.id, msgbuf[2], msgbuf[3], msgbuf[1], msgbuf[4], msgbuf[5], msgbuf[6])
        self._msgbuf = msgbuf
        self._payload = msgbuf[_HEADER_LEN:-_CRC_LEN]
        self._crc = crc
        offset = BOOT_TIME_OFFSETS.get(cls.id)
        if offset is not None:  # trailing zero bytes are cut from a MAVLink 2 payload: what is missing is 0
            self.time_boot_ms = int.from_bytes(self._payload[offset : offset + 4].ljust(4, b"\0"), "little")


class Skimmer:
    """``MAVLink.decode`` for one connection that decodes in full only the kinds in ``read``.

    Install with ``mav.decode = Skimmer(mav, read)``: pymavlink's parser calls it for each frame.
    """

    def __init__(self, mav: mavlink.MAVLink, read: Collection[str]) -> None:
        self._mav = mav
        self._decode: Callable[[bytearray], MAVLinkMessage] = mav.decode
        self.unread = {cls.id: cls for cls in mavlink.mavlink_map.values() if cls.msgname not in read}

    def __call__(self, msgbuf: bytearray) -> MAVLinkMessage:
        if (
            len(msgbuf) > _HEADER_LEN + _CRC_LEN
            and msgbuf[0] == mavlink.PROTOCOL_MARKER_V2
            and not msgbuf[2] & mavlink.MAVLINK_IFLAG_SIGNED
            and self._mav.signing.secret_key is None  # unsigned packets are judged (and counted) by pymavlink
            and msgbuf[1] == len(msgbuf) - _HEADER_LEN - _CRC_LEN
        ):
            cls = self.unread.get(msgbuf[7] | msgbuf[8] << 8 | msgbuf[9] << 16)
            if cls is not None:
                crc = msgbuf[-2] | msgbuf[-1] << 8
                checked = msgbuf[1:-_CRC_LEN]
                checked.append(cls.crc_extra)
                if mavlink.x25crc(checked).crc == crc:
                    return UnreadMessage(cls, msgbuf, crc)
        return self._decode(msgbuf)  # a kind read, or a frame pymavlink must refuse with its own words
