"""A MAVLink link: something that receives and sends messages without blocking."""

from __future__ import annotations

from typing import Protocol

from executive.io.mavlink.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, mavutil


class Link(Protocol):
    """What the reader and the commander need from a link (a fake one in tick tests)."""

    def recv(self) -> MAVLinkMessage | None:
        """The next message received, or ``None`` at once when there is none."""
        ...

    def send(self, msg: MAVLinkMessage) -> None:
        """Send an encoded message (it gets this link's sequence number and ids)."""
        ...

    def close(self) -> None: ...


class PymavlinkLink:
    """A link over serial, UDP or TCP, from a pymavlink connection string.

    ``udpout:127.0.0.1:14550``, ``udpin:0.0.0.0:14550``, ``tcp:127.0.0.1:5760``, ``/dev/ttyACM0``...
    A serial device may carry its baud rate after a comma: ``/dev/ttyAMA0,921600``.
    """

    def __init__(self, url: str, system_id: int = 1, component_id: int = EXECUTIVE_COMPONENT) -> None:
        device, _, baud = url.partition(",")
        self.url = url
        self._conn = mavutil.mavlink_connection(
            device,
            baud=int(baud) if baud else 115200,
            source_system=system_id,
            source_component=component_id,
            dialect="ardupilotmega",
            autoreconnect=True,
        )

    def recv(self) -> MAVLinkMessage | None:
        return self._conn.recv_msg()

    def send(self, msg: MAVLinkMessage) -> None:
        self._conn.mav.send(msg)

    def close(self) -> None:
        self._conn.close()
