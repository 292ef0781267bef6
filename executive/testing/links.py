"""MAVLink as a test sees it: peers whose messages look as if they came off the wire, and a link that records what was sent."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from executive.io.mavlink.link import MemoryLink
from executive.world.dialect import MAVLinkMessage, encoder, mavlink


class Peer:
    """``Peer(1, 1).heartbeat(...)``: the message a component would send, header and all (packed and parsed back)."""

    def __init__(self, system_id: int, component_id: int) -> None:
        self._encoder = encoder(system_id, component_id)
        self._parser = mavlink.MAVLink(None)

    def __getattr__(self, name: str) -> Callable[..., MAVLinkMessage]:
        encode = getattr(self._encoder, f"{name}_encode")

        def send(*args: Any) -> MAVLinkMessage:
            return self._parser.decode(bytearray(encode(*args).pack(self._encoder)))

        return send


#: The vehicle's autopilot (system 1, component 1).
AUTOPILOT = Peer(1, 1)
#: A ground station (system 255, component 190).
GCS = Peer(255, 190)


def ack(command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> MAVLinkMessage:
    """The autopilot's COMMAND_ACK of ``command`` to the executive (component 191)."""
    return AUTOPILOT.command_ack(command, result, 0, 0, 1, 191)


class FakeLink(MemoryLink):
    """A Link that records what is sent (:attr:`sent`) and returns what a test queued for reception (:attr:`incoming`)."""

    def take(self, kind: str | None = None) -> list[MAVLinkMessage]:
        """Messages sent since the last take (of one type, if given), oldest first."""
        taken = [m for m in self.sent if kind is None or m.get_type() == kind]
        self.sent = [m for m in self.sent if m not in taken]
        return taken
