"""The relay thread under the tests' UDP hub and lossy link: sockets on loopback, a bounded lifetime, clean stop."""

from __future__ import annotations

import select
import socket
import threading
import time
from types import TracebackType
from typing import Self


class UdpRelay:
    """Reads datagrams from its sockets on a thread and hands each to :meth:`on_datagram`.

    The thread stops at :meth:`stop` or after ``lifetime_s``, whichever comes first, so a
    forgotten relay cannot outlive its test by much. Subclasses open their sockets with
    :meth:`bind` and may do timed work in :meth:`on_idle` (called every ``poll_s``).
    """

    poll_s = 0.01

    def __init__(self, *, lifetime_s: float, host: str = "127.0.0.1") -> None:
        self.lifetime_s = lifetime_s
        self.host = host
        self._sockets: list[socket.socket] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def bind(self) -> socket.socket:
        """A new UDP socket on an ephemeral loopback port, read by the relay."""
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind((self.host, 0))
        self._sockets.append(sock)
        return sock

    def on_datagram(self, sock: socket.socket, data: bytes, sender: tuple[str, int]) -> None:
        raise NotImplementedError

    def on_idle(self) -> None:
        """Timed work between reads (nothing by default)."""

    def start(self) -> Self:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=type(self).__name__, daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop relaying and close the sockets (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for sock in self._sockets:
            sock.close()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.stop()

    def _run(self) -> None:
        deadline = time.monotonic() + self.lifetime_s
        while not self._stop.is_set() and time.monotonic() < deadline:
            readable, _, _ = select.select(self._sockets, [], [], self.poll_s)
            for sock in readable:
                try:
                    data, sender = sock.recvfrom(65535)
                except OSError:
                    continue
                self.on_datagram(sock, data, sender)
            self.on_idle()
