"""A MAVLink hub for tests: one UDP port where several vehicles and executives meet, as mavlink-router or MAVProxy make one."""

from __future__ import annotations

import socket

from udp_relay import UdpRelay


class UdpHub(UdpRelay):
    """Forwards every datagram it receives to every other endpoint it knows, unchanged.

    ``servers`` are the ports of vehicles listening with ``udpin`` (they speak once spoken to);
    every other sender (an executive on ``udpout:127.0.0.1:<port>``) is learned from its first
    datagram. The relay thread stops at :meth:`stop` or after ``lifetime_s``.
    """

    def __init__(self, servers: list[int], *, lifetime_s: float = 120.0, host: str = "127.0.0.1") -> None:
        super().__init__(lifetime_s=lifetime_s, host=host)
        self.endpoints: list[tuple[str, int]] = [(host, port) for port in servers]
        self.forwarded = 0
        self._sock = self.bind()

    @property
    def port(self) -> int:
        """Where an executive sends."""
        return self._sock.getsockname()[1]

    def on_datagram(self, sock: socket.socket, data: bytes, sender: tuple[str, int]) -> None:
        if sender not in self.endpoints:
            self.endpoints.append(sender)
        for endpoint in self.endpoints:
            if endpoint != sender:
                try:
                    self._sock.sendto(data, endpoint)
                    self.forwarded += 1
                except OSError:
                    pass  # that endpoint has gone; the others still hear
