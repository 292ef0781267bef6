"""The simulated autopilot's end of the link: every MAVLink client of a ``tcpin:`` or ``udpin:`` address, at once.

As mavlink-router's endpoints do, each client (an executive, a ground station, a MAVProxy) gets
every message the vehicle sends, and what any of them sends is taken. pymavlink's own ``tcpin``
serves one client at a time: a second one connected, heard nothing and gave up. (ArduPilot SITL,
measured: one client per TCP port; a second client of port 5760+10i heard no HEARTBEAT in 10 s while
port 5762+10i served a third; a ground station beside an executive takes that other port.)
Each client has its own parser (a message cut in two by one client is not spliced into another's);
what the vehicle sends is packed once (one sequence, one signature) and written to each.
A TCP client comes on ``accept`` and goes when its connection closes; a UDP client comes with its
first datagram and is dropped after :data:`UDP_SILENCE_S` of silence (UDP says nothing of leaving).
Each is logged, with the number of clients left.
"""

from __future__ import annotations

import logging
import socket
import time
from dataclasses import dataclass, field
from typing import Any

from executive.world.dialect import MAVLinkMessage, mavlink

log = logging.getLogger(__name__)

#: A UDP client not heard for this long (wall seconds) is no longer sent to (ground stations send a heartbeat every second).
UDP_SILENCE_S = 10.0
_RECV_BYTES = 65536


class ClientAddressError(ValueError):
    """An address the simulator cannot listen on (not ``tcpin:HOST:PORT`` or ``udpin:HOST:PORT``)."""


@dataclass
class _Peer:
    """One peer: its address, its own parser, when it was last heard (UDP) and its socket (TCP)."""

    address: tuple[str, int]
    parser: Any
    heard: float
    sock: socket.socket | None = None
    pending: list[MAVLinkMessage] = field(default_factory=list)

    @property
    def name(self) -> str:
        return f"{self.address[0]}:{self.address[1]}"


class Clients:
    """Listens on ``url``; :attr:`mav` sends to every client (``mav.send(msg)``), :meth:`recv_msg` reads from any of them."""

    def __init__(self, url: str, system_id: int, component_id: int, signing_key: bytes | None = None) -> None:
        scheme, host, port = _parse(url)
        self.tcp = scheme == "tcpin"
        self._signing_key = signing_key
        self._system_id, self._component_id = system_id, component_id
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_STREAM if self.tcp else socket.SOCK_DGRAM)
        try:
            self.socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self.socket.bind((host, port))
            if self.tcp:
                self.socket.listen(8)
        except OSError:
            self.socket.close()
            raise
        self.socket.setblocking(False)
        self._clients: dict[tuple[str, int], _Peer] = {}
        self.mav = self._new_mav(self)  # what the vehicle sends: packed once, written to every client

    def _new_mav(self, file: object) -> Any:
        mav = mavlink.MAVLink(file, srcSystem=self._system_id, srcComponent=self._component_id)
        mav.robust_parsing = True
        if self._signing_key is not None:  # like ArduPilot with a key set: sign everything, refuse unsigned packets
            mav.signing.secret_key = self._signing_key
            mav.signing.sign_outgoing = True
            mav.signing.allow_unsigned_callback = lambda _mav, _msg_id: False
            mav.signing.timestamp = int((max(time.time(), 1420070400) - 1420070400) * 100_000)  # 10 us units since 2015, as pymavlink
        return mav

    @property
    def address(self) -> tuple[str, int]:
        host, port = self.socket.getsockname()[:2]
        return host, port

    @property
    def count(self) -> int:
        """How many clients are served now."""
        return len(self._clients)

    def write(self, data: bytes) -> None:
        """Send ``data`` (one packed message) to every client; a TCP client whose connection broke is let go."""
        for client in list(self._clients.values()):
            try:
                if client.sock is not None:
                    client.sock.sendall(data)
                else:
                    self.socket.sendto(data, client.address)
            except BlockingIOError:
                pass  # a client that does not read loses messages, as on a radio; the others are not held up
            except (BrokenPipeError, ConnectionResetError):  # it closed its end
                self._leave(client, "disconnected")
            except OSError as exc:
                self._leave(client, f"send failed: {exc.strerror or exc}")

    def recv_msg(self) -> MAVLinkMessage | None:
        """The next message from any client (None when none is waiting); newcomers accepted, the departed and the silent let go."""
        self._accept()
        now = time.monotonic()
        for client in list(self._clients.values()):
            if client.pending:
                return client.pending.pop(0)
            if client.sock is None and now - client.heard > UDP_SILENCE_S:
                self._leave(client, f"not heard for {UDP_SILENCE_S:g} s")
        return self._read()

    def close(self) -> None:
        for client in list(self._clients.values()):
            if client.sock is not None:
                client.sock.close()
        self._clients.clear()
        self.socket.close()

    def _accept(self) -> None:
        if not self.tcp:
            return
        while True:
            try:
                sock, address = self.socket.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            sock.setblocking(False)
            self._join(_Peer(address[:2], self._new_mav(None), time.monotonic(), sock))

    def _read(self) -> MAVLinkMessage | None:
        """Read what has come (a datagram, or every TCP client's bytes) and return the first message it holds."""
        if self.tcp:
            for client in list(self._clients.values()):
                try:
                    data = client.sock.recv(_RECV_BYTES) if client.sock is not None else b""
                except (BlockingIOError, InterruptedError):
                    continue
                except ConnectionResetError:  # closed with our messages unread: as good as a goodbye
                    data = b""
                except OSError as exc:
                    self._leave(client, f"connection lost: {exc.strerror or exc}")
                    continue
                if not data:
                    self._leave(client, "disconnected")
                    continue
                self._parse(client, data)
        else:
            while True:
                try:
                    data, address = self.socket.recvfrom(_RECV_BYTES)
                except (BlockingIOError, InterruptedError):
                    break
                except OSError:  # an ICMP port unreachable from a client gone (Linux reports it on the next call)
                    continue
                client = self._clients.get(address[:2])
                if client is None:
                    client = self._join(_Peer(address[:2], self._new_mav(None), time.monotonic()))
                client.heard = time.monotonic()
                self._parse(client, data)
        for client in self._clients.values():
            if client.pending:
                return client.pending.pop(0)
        return None

    def _parse(self, client: _Peer, data: bytes) -> None:
        messages = client.parser.parse_buffer(data) or []
        client.pending += [m for m in messages if m is not None]

    def _join(self, client: _Peer) -> _Peer:
        self._clients[client.address] = client
        log.info("MAVLink client %s connected (%d client%s)", client.name, self.count, "" if self.count == 1 else "s")
        return client

    def _leave(self, client: _Peer, why: str) -> None:
        if self._clients.pop(client.address, None) is None:
            return
        if client.sock is not None:
            client.sock.close()
        log.info("MAVLink client %s left: %s (%d client%s)", client.name, why, self.count, "" if self.count == 1 else "s")


def _parse(url: str) -> tuple[str, str, int]:
    scheme, _, rest = url.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme not in ("tcpin", "udpin") or not host or not port.isdigit() or int(port) > 65535:
        raise ClientAddressError(f"expected tcpin:HOST:PORT or udpin:HOST:PORT, got {url!r}")
    return scheme, host, int(port)
