"""The Groot2 monitor protocol as BehaviorTree.CPP v4's ``Groot2Publisher`` speaks it (pure encoding: no sockets).

From BehaviorTree.CPP's ``include/behaviortree_cpp/loggers/groot2_protocol.h`` and
``src/loggers/groot2_publisher.cpp``: a request is a multipart ZeroMQ message whose first frame is a
6-byte header (protocol id 2, the request type as an ASCII letter, a little-endian uint32 id), with a
second frame for requests that carry a payload. A reply's first frame is the request header echoed
(with our protocol id) followed by the tree's 16-byte UUID; its second frame is the answer. An error is
the two frames ``error`` and a message. Node statuses travel as 3-byte records (uint16 uid, uint8 status),
transitions as 9-byte records (a 48-bit microsecond time since recording started, uint16 uid, uint8 status).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass

PROTOCOL_ID = 2
DEFAULT_PORT = 1667  # Groot2Publisher's default; its publish socket is the next port


class RequestType:
    """``BT::Monitor::RequestType``: the letters a client sends."""

    FULLTREE = ord("T")
    STATUS = ord("S")
    BLACKBOARD = ord("B")
    HOOK_INSERT = ord("I")
    HOOK_REMOVE = ord("R")
    BREAKPOINT_REACHED = ord("N")
    BREAKPOINT_UNLOCK = ord("U")
    REMOVE_ALL_HOOKS = ord("A")
    DISABLE_ALL_HOOKS = ord("D")
    HOOKS_DUMP = ord("H")
    TOGGLE_RECORDING = ord("O")
    GET_TRANSITIONS = ord("P")


# BT::NodeStatus, and what Groot2Publisher::callback writes for a node gone back to IDLE: 10 + the status it had
IDLE, RUNNING, SUCCESS, FAILURE, SKIPPED = 0, 1, 2, 3, 4
IDLE_AFTER = 10

_HEADER = struct.Struct("<BBI")
HEADER_SIZE = _HEADER.size
UUID_SIZE = 16


class ProtocolError(ValueError):
    """A request that is not the Groot2 protocol."""


@dataclass(frozen=True)
class RequestHeader:
    """A request's first frame: protocol id, request type (a letter), request id."""

    protocol: int
    type: int
    id: int

    @classmethod
    def decode(cls, frame: bytes) -> RequestHeader:
        if len(frame) != HEADER_SIZE:
            raise ProtocolError("wrong request header")  # Groot2Publisher's own words
        return cls(*_HEADER.unpack(frame))

    def encode(self) -> bytes:
        return _HEADER.pack(self.protocol, self.type, self.id)


def reply_header(request: RequestHeader, tree_uuid: bytes) -> bytes:
    """A reply's first frame: the request header with our protocol id, then the tree's UUID."""
    return RequestHeader(PROTOCOL_ID, request.type, request.id).encode() + tree_uuid


def error_reply(message: str) -> list[bytes]:
    return [b"error", message.encode()]


def status_buffer(statuses: Iterable[tuple[int, int]]) -> bytes:
    """(uid, status) records, 3 bytes each."""
    return b"".join(struct.pack("<HB", uid, status) for uid, status in statuses)


def transitions_buffer(transitions: Iterable[tuple[int, int, int]]) -> bytes:
    """(microseconds since the recording started, uid, status) records, 9 bytes each (the time cut to 48 bits)."""
    return b"".join(struct.pack("<Q", us & 0xFFFF_FFFF_FFFF)[:6] + struct.pack("<HB", uid, status) for us, uid, status in transitions)
