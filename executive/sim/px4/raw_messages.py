"""Messages PX4 sends that pymavlink's ardupilotmega dialect lacks, packed as raw MAVLink 2 frames."""

from __future__ import annotations

import struct
from collections.abc import Sequence

from executive.world.dialect import MAVLinkMessage, mavlink

# Messages of MAVLink's common set that pymavlink's ardupilotmega dialect lacks: id, name, wire fields (type, name).
CURRENT_EVENT_SEQUENCE = (411, "CURRENT_EVENT_SEQUENCE", (("uint16_t", "sequence"), ("uint8_t", "flags")))
TIME_ESTIMATE_TO_TARGET = (
    380, "TIME_ESTIMATE_TO_TARGET",
    tuple(("int32_t", f) for f in ("safe_return", "land", "mission_next_item", "mission_end", "commanded_action")),
)  # fmt: skip

_TYPES = {"uint8_t": "B", "int8_t": "b", "uint16_t": "H", "int16_t": "h", "uint32_t": "I", "int32_t": "i", "float": "f"}


class RawMessage(MAVLinkMessage):
    """A MAVLink 2 message of a definition the loaded dialect lacks, packed from its wire fields (in wire order)."""

    def __init__(self, msg_id: int, name: str, fields: Sequence[tuple[str, str]], values: Sequence[int | float]) -> None:
        super().__init__(msg_id, name)
        self._fieldnames = [field for _, field in fields]
        for field, value in zip(self._fieldnames, values, strict=True):
            setattr(self, field, value)
        self._raw_payload = struct.pack("<" + "".join(_TYPES[kind] for kind, _ in fields), *values)
        self._crc_extra = crc_extra(name, fields)

    def pack(self, mav: mavlink.MAVLink, force_mavlink1: bool = False) -> bytes:
        return self._pack(mav, self._crc_extra, self._raw_payload, force_mavlink1=force_mavlink1)


def crc_extra(name: str, fields: Sequence[tuple[str, str]]) -> int:
    """A message definition's CRC_EXTRA, as mavgen computes it (scalar fields, in wire order)."""
    crc = mavlink.x25crc(f"{name} ".encode())
    for kind, field in fields:
        crc.accumulate(f"{kind} {field} ".encode())
    return (crc.crc & 0xFF) ^ (crc.crc >> 8)
