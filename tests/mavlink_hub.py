"""A MAVLink hub for tests: one UDP port where several vehicles and executives meet, as mavlink-router or MAVProxy make one."""

from __future__ import annotations

import select
import socket
import threading
import time
from types import TracebackType


class UdpHub:
    """Forwards every datagram it receives to every other endpoint it knows, unchanged.

    ``servers`` are the ports of vehicles listening with ``udpin`` (they speak once spoken to);
    every other sender (an executive on ``udpout:127.0.0.1:<port>``) is learned from its first
    datagram. The relay thread stops at :meth:`stop` or after ``lifetime_s``.
    """

    def __init__(self, servers: list[int], *, lifetime_s: float = 120.0, host: str = "127.0.0.1") -> None:
        self.lifetime_s = lifetime_s
        self.endpoints: list[tuple[str, int]] = [(host, port) for port in servers]
        self.forwarded = 0
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind((host, 0))
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def port(self) -> int:
        """Where an executive sends."""
        return self._sock.getsockname()[1]

    def start(self) -> UdpHub:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="udp-hub", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self._sock.close()

    def __enter__(self) -> UdpHub:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.stop()

    def _run(self) -> None:
        deadline = time.monotonic() + self.lifetime_s
        while not self._stop.is_set() and time.monotonic() < deadline:
            readable, _, _ = select.select([self._sock], [], [], 0.01)
            if not readable:
                continue
            try:
                data, sender = self._sock.recvfrom(65535)
            except OSError:
                continue
            if sender not in self.endpoints:
                self.endpoints.append(sender)
            for endpoint in self.endpoints:
                if endpoint != sender:
                    try:
                        self._sock.sendto(data, endpoint)
                        self.forwarded += 1
                    except OSError:
                        pass  # that endpoint has gone; the others still hear
