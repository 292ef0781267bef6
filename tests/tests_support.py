"""Message factories for tests: MAVLink peers whose messages look as if they came off the wire."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from executive.io.mavlink.dialect import MAVLinkMessage, encoder, mavlink


class Peer:
    """``Peer(1, 1).heartbeat(...)``: the message a component would send, header and all."""

    def __init__(self, system_id: int, component_id: int) -> None:
        self._encoder = encoder(system_id, component_id)
        self._parser = mavlink.MAVLink(None)

    def __getattr__(self, name: str) -> Callable[..., MAVLinkMessage]:
        encode = getattr(self._encoder, f"{name}_encode")

        def send(*args: Any) -> MAVLinkMessage:
            return self._parser.decode(bytearray(encode(*args).pack(self._encoder)))

        return send


AUTOPILOT = Peer(1, 1)
GCS = Peer(255, 190)


def ack(command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> MAVLinkMessage:
    return AUTOPILOT.command_ack(command, result, 0, 0, 1, 191)
