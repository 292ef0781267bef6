"""A serial device for tests: a pseudo-terminal bridged to a simulator's UDP port, that can be unplugged and plugged back.

As ``socat pty,link=NAME,raw,echo=0 udp:HOST:PORT``: the executive opens ``NAME`` (a symbolic link to
the pty, standing for ``/dev/serial/by-id/...``) as it would a USB serial device. :meth:`unplug`
closes the pty (the executive's reads then fail as a pulled cable's do) and removes the name;
:meth:`plug` makes a new pty (another ``/dev/pts/N``) under the same name.
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
import threading
import time
import tty
from types import TracebackType
from typing import Self


class PtyBridge:
    """A pty named ``name`` whose bytes go to ``target`` (a UDP ``(host, port)``, the simulator) and back; or, without one, to nobody."""

    def __init__(self, name: str, target: tuple[str, int] | None = None, *, lifetime_s: float = 120.0) -> None:
        self.name = name
        self.target = target
        self.lifetime_s = lifetime_s
        self._udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._udp.bind(("127.0.0.1", 0))
        self._lock = threading.Lock()
        self._master: int | None = None
        self._slave: int | None = None
        self._stop = threading.Event()
        self._unplugs = self._seen = 0  # unplugs asked, and the last one the thread has seen (it no longer watches that pty)
        self._thread = threading.Thread(target=self._run, name="PtyBridge", daemon=True)
        self.plug()

    @property
    def device(self) -> str:
        """The pty the name points to now (``/dev/pts/N``)."""
        return os.readlink(self.name)

    def plug(self) -> None:
        """A new pty under the name (the cable plugged back: the device may come back as another /dev/pts/N)."""
        master, slave = os.openpty()
        tty.setraw(slave)  # no echo, no line editing: bytes in, bytes out, before the executive configures it
        os.set_blocking(master, False)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.name)
        os.symlink(os.ttyname(slave), self.name)
        with self._lock:
            self._master, self._slave = master, slave

    def unplug(self) -> None:
        """The cable pulled: the pty closed (the executive's reads on it fail) and its name gone."""
        with self._lock:
            fds, self._master, self._slave = (self._master, self._slave), None, None
            self._unplugs += 1
        # the thread's select() holds the pty until it returns: closed only once it has let go, the hang-up is at once
        deadline = time.monotonic() + 1.0
        while self._thread.is_alive() and self._seen < self._unplugs and time.monotonic() < deadline:
            time.sleep(0.001)
        for fd in fds:
            if fd is not None:
                os.close(fd)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.name)

    def write(self, data: bytes) -> None:
        """Bytes from the device's side (as an autopilot, or a modem speaking something else, would send them)."""
        with self._lock:
            if self._master is not None:
                with contextlib.suppress(BlockingIOError):
                    os.write(self._master, data)

    def start(self) -> Self:
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.unplug()
        self._udp.close()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def _run(self) -> None:
        deadline = time.monotonic() + self.lifetime_s
        while not self._stop.is_set() and time.monotonic() < deadline:
            with self._lock:
                master, self._seen = self._master, self._unplugs
            try:
                readable, _, _ = select.select([self._udp] + ([master] if master is not None else []), [], [], 0.005)
            except (OSError, ValueError):  # the pty closed by unplug() meanwhile
                continue
            if self._udp in readable:
                data = self._udp.recv(65535)
                self.write(data)
            if master is not None and master in readable:
                try:
                    data = os.read(master, 65535)
                except OSError:  # unplugged meanwhile, or nobody has the device open
                    continue
                if self.target is not None:
                    self._udp.sendto(data, self.target)
