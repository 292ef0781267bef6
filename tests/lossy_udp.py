"""A lossy UDP link for tests: a relay on loopback that drops a fraction of the datagrams and swaps some."""

from __future__ import annotations

import random
import socket
import time
from dataclasses import dataclass, field

from udp_relay import UdpRelay


def mavlink_msgid(datagram: bytes) -> int | None:
    """The message id of the (first) MAVLink packet in a datagram, if it starts with one."""
    if len(datagram) >= 10 and datagram[0] == 0xFD:
        return datagram[7] | datagram[8] << 8 | datagram[9] << 16
    if len(datagram) >= 6 and datagram[0] == 0xFE:
        return datagram[5]
    return None


@dataclass
class Direction:
    """What happened to the datagrams going one way."""

    forwarded: int = 0
    dropped: int = 0
    reordered: int = 0
    dropped_ids: list[int | None] = field(default_factory=list)  # MAVLink message ids of the dropped datagrams


class LossyUdpProxy(UdpRelay):
    """Relays datagrams between a client and a UDP server on loopback, losing ``drop`` of them and swapping ``reorder``.

    The client sends to :attr:`port`; the proxy forwards to ``server_port`` from a socket of its
    own, so the server answers the proxy, which forwards to the client (the last address heard
    from). Each direction decides with its own ``random.Random`` seeded from ``seed``. A datagram
    picked for reordering is held and sent after the next one going the same way, or after
    ``hold_s`` if none comes. The relay thread stops at :meth:`stop` or after ``lifetime_s``,
    whichever comes first, so a forgotten proxy cannot outlive its test by much.
    """

    poll_s = 0.005

    def __init__(
        self,
        server_port: int,
        *,
        drop: float = 0.2,
        reorder: float = 0.1,
        seed: int = 1,
        lifetime_s: float = 10.0,
        hold_s: float = 0.02,
        host: str = "127.0.0.1",
    ) -> None:
        if not 0.0 <= drop + reorder <= 1.0:
            raise ValueError(f"drop + reorder must be within [0, 1], got {drop} + {reorder}")
        super().__init__(lifetime_s=lifetime_s, host=host)
        self.drop, self.reorder, self.hold_s = drop, reorder, hold_s
        self._server = (host, server_port)
        self._client: tuple[str, int] | None = None
        self._client_side = self.bind()
        self._server_side = self.bind()
        self.up, self.down = Direction(), Direction()  # client -> server, server -> client
        self._random = {"up": random.Random(seed), "down": random.Random(seed + 1)}
        self._held: dict[str, tuple[bytes, float]] = {}

    @property
    def port(self) -> int:
        """Where the client sends."""
        return self._client_side.getsockname()[1]

    def on_datagram(self, sock: socket.socket, data: bytes, sender: tuple[str, int]) -> None:
        if sock is self._client_side:
            self._client = sender
            self._relay("up", data)
        elif self._client is not None:
            self._relay("down", data)

    def on_idle(self) -> None:
        now = time.monotonic()
        for way, (data, since) in list(self._held.items()):
            if now - since >= self.hold_s:
                del self._held[way]
                self._send(way, data)

    def _relay(self, way: str, data: bytes) -> None:
        stats = self.up if way == "up" else self.down
        draw = self._random[way].random()
        if draw < self.drop:
            stats.dropped += 1
            stats.dropped_ids.append(mavlink_msgid(data))
            return
        held = self._held.pop(way, None)
        if held is None and draw < self.drop + self.reorder:
            stats.reordered += 1
            self._held[way] = (data, time.monotonic())
            return
        self._send(way, data)
        if held is not None:
            self._send(way, held[0])  # after the one that overtook it

    def _send(self, way: str, data: bytes) -> None:
        (self.up if way == "up" else self.down).forwarded += 1
        try:
            if way == "up":
                self._server_side.sendto(data, self._server)
            elif self._client is not None:
                self._client_side.sendto(data, self._client)
        except OSError:
            pass  # the server or the client has gone: the datagram is lost, as on a real link
