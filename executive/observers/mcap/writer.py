"""An MCAP writer whose per-message cost fits in a tick: chunked, zstd-compressed, indexed (https://mcap.dev/spec).

The ``mcap`` library's :class:`mcap.writer.Writer` builds a record object and a dozen small writes
for each message: about 8 µs, most of what recording a tick as MCAP cost. Here a message is one
``struct.pack`` and an append to the chunk's buffer; the records written once a chunk or a file
(chunk, message indexes, summary, footer) are the library's own :mod:`mcap.records`, so the layout
is the library's: the ``mcap`` reader (and its CRC checks) reads what this writes.
"""

from __future__ import annotations

import struct
import zlib
from collections import defaultdict
from typing import Protocol

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Metadata, MetadataIndex, Schema, Statistics, SummaryOffset

MAGIC = b"\x89MCAP0\r\n"
#: A message record's head: opcode, record length, channel id, sequence, log time, publish time (then the data).
_MESSAGE = struct.Struct("<BQHIQQ")
_MESSAGE_INDEX_HEAD = struct.Struct("<BQHI")


class Output(Protocol):
    def write(self, data: bytes) -> object: ...

    def tell(self) -> int: ...


class ChunkedWriter:
    """Schemas, channels and messages into zstd chunks of about ``chunk_size`` bytes; :meth:`finish` writes the summary."""

    def __init__(self, out: Output, chunk_size: int, library: str = "executive") -> None:
        self._out, self._chunk_size = out, chunk_size
        self._compress = zstandard.ZstdCompressor().compress
        self._chunk = bytearray()
        self._index: dict[int, list[int]] = {}  # channel id -> log time, offset, log time, offset...
        self._chunk_indexes: list[ChunkIndex] = []
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._counts: dict[int, int] = defaultdict(int)
        self._metadata: list[MetadataIndex] = []
        self._write(MAGIC)
        self._record(Header(profile="", library=library))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(schema)
        self._chunk += _record_bytes(schema)
        return schema.id

    def register_channel(self, topic: str, message_encoding: str, schema_id: int) -> int:
        channel = Channel(id=len(self._channels) + 1, topic=topic, message_encoding=message_encoding, metadata={}, schema_id=schema_id)
        self._channels.append(channel)
        self._chunk += _record_bytes(channel)
        return channel.id

    def add_message(self, channel: int, log_time: int, data: bytes, sequence: int) -> None:
        """One message (published when logged); the chunk written once it is full."""
        chunk = self._chunk
        index = self._index.get(channel)
        if index is None:
            index = self._index[channel] = []
        index += (log_time, len(chunk))
        chunk += _MESSAGE.pack(Opcode.MESSAGE, 22 + len(data), channel, sequence, log_time, log_time)
        chunk += data
        self._counts[channel] += 1
        if len(chunk) >= self._chunk_size:
            self._end_chunk()

    def add_metadata(self, name: str, metadata: dict[str, str]) -> None:
        self._end_chunk()
        offset = self._out.tell()
        data = _record_bytes(Metadata(name=name, metadata=metadata))
        self._write(data)
        self._metadata.append(MetadataIndex(offset=offset, length=len(data), name=name))

    def finish(self) -> None:
        self._end_chunk()
        self._record(DataEnd(data_section_crc=0))
        summary_start = self._out.tell()
        summary = RecordBuilder()
        offsets: list[SummaryOffset] = []

        def group(opcode: Opcode, records: list) -> None:
            start = summary.count
            for record in records:
                record.write(summary)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=summary_start + start, group_length=summary.count - start))

        group(Opcode.SCHEMA, self._schemas)
        group(Opcode.CHANNEL, self._channels)
        messages = sum(self._counts.values())
        times = [i.message_start_time for i in self._chunk_indexes] or [0]
        ends = [i.message_end_time for i in self._chunk_indexes] or [0]
        statistics = Statistics(
            message_count=messages, schema_count=len(self._schemas), channel_count=len(self._channels), attachment_count=0,
            metadata_count=len(self._metadata), chunk_count=len(self._chunk_indexes), message_start_time=min(times),
            message_end_time=max(ends), channel_message_counts=dict(self._counts),
        )  # fmt: skip
        group(Opcode.STATISTICS, [statistics])
        group(Opcode.CHUNK_INDEX, self._chunk_indexes)
        group(Opcode.METADATA_INDEX, self._metadata)
        offset_start = summary_start + summary.count
        for offset in offsets:
            offset.write(summary)
        data = summary.end()
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 20, summary_start, offset_start), zlib.crc32(data))
        self._write(data)
        self._record(Footer(summary_start=summary_start, summary_offset_start=offset_start, summary_crc=crc))
        self._write(MAGIC)

    def _end_chunk(self) -> None:
        """The chunk so far written compressed, then its messages' indexes; the chunk index kept for the summary."""
        if not self._chunk:
            return
        data = bytes(self._chunk)
        compressed = self._compress(data)
        start = self._out.tell()
        times = [t for index in self._index.values() for t in index[0::2]]
        first, last = (min(times), max(times)) if times else (0, 0)
        chunk = Chunk(
            message_start_time=first, message_end_time=last, uncompressed_size=len(data), uncompressed_crc=zlib.crc32(data),
            compression="zstd", data=compressed,
        )  # fmt: skip
        record = _record_bytes(chunk)
        self._write(record)
        indexes_start = self._out.tell()
        offsets: dict[int, int] = {}
        indexes = bytearray()
        for channel, entries in self._index.items():
            if entries:
                offsets[channel] = indexes_start + len(indexes)
                indexes += _MESSAGE_INDEX_HEAD.pack(Opcode.MESSAGE_INDEX, 6 + 8 * len(entries), channel, 8 * len(entries))
                indexes += struct.pack(f"<{len(entries)}Q", *entries)
        self._write(bytes(indexes))
        self._chunk_indexes.append(
            ChunkIndex(
                message_start_time=first, message_end_time=last, chunk_start_offset=start, chunk_length=len(record),
                message_index_offsets=offsets, message_index_length=len(indexes), compression="zstd",
                compressed_size=len(compressed), uncompressed_size=len(data),
            )
        )  # fmt: skip
        self._chunk = bytearray()
        self._index = {}

    def _record(self, record: object) -> None:
        self._write(_record_bytes(record))

    def _write(self, data: bytes) -> None:
        self._out.write(data)


def _record_bytes(record: object) -> bytes:
    builder = RecordBuilder()
    record.write(builder)  # type: ignore[attr-defined]
    return builder.end()
