"""The control socket: operator requests over a local Unix socket, one JSON object per line each way.

Owner-only (0600): only the user running the executive can command it. Serviced once per tick,
never blocking: pending connections are accepted, complete lines answered, the rest kept.
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import math
import os
import socket
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

log = logging.getLogger(__name__)

MAX_REQUEST_BYTES = 4 << 20  # an upload carries a mission file (<= 1 MiB) as JSON text
MAX_CLIENTS = 32  # connections served at once; one more is told so and closed
MAX_ACCEPTS_PER_SERVICE = 64  # a storm of connections cannot hold up a tick
MAX_REQUESTS_PER_SERVICE = 16  # per connection and tick: a flood of requests is answered over several ticks
MAX_UNREAD_REPLY_BYTES = 1 << 20  # a client leaving more replies than this unread is dropped

Handler = Callable[[dict[str, Any]], dict[str, Any]]


def default_socket_path(pid: int | None = None) -> str:
    """``$XDG_RUNTIME_DIR/executive.sock``, else a per-user file in the temp directory; with ``pid``, that process's own beside it."""
    runtime_dir = os.environ.get("XDG_RUNTIME_DIR")
    own = "" if pid is None else f"-{pid}"
    if runtime_dir:
        return os.path.join(runtime_dir, f"executive{own}.sock")
    return os.path.join(tempfile.gettempdir(), f"executive-{os.getuid()}{own}.sock")


class SocketInUse(OSError):
    """Another executive is serving on this socket path."""


@dataclass
class _Connection:
    """One client: bytes read but not yet answered, replies not yet sent, whether it has stopped sending."""

    inbox: bytearray = field(default_factory=bytearray)
    outbox: bytearray = field(default_factory=bytearray)
    eof: bool = False


class ControlServer:
    """Serves ``handler`` on a Unix socket at ``path``; call :meth:`service` every tick."""

    def __init__(self, path: str, handler: Handler) -> None:
        self.path = path
        self._handler = handler
        if os.path.exists(path):
            if socket_alive(path):
                raise SocketInUse(f"{path}: another executive is listening there")
            os.unlink(path)  # left behind by a crash
        self._server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        # Bound and listening under a name of its own, then linked into place: a client that finds the path
        # can connect (bound but not yet listening, it was refused: seen under load). link() fails where
        # the path exists, as bind() does, so two executives never share one.
        staging = f"{path}.{os.getpid()}"
        old_umask = os.umask(0o177)
        try:
            self._server.bind(staging)
        finally:
            os.umask(old_umask)
        try:
            os.chmod(staging, 0o600)
            self._server.listen(8)
            os.link(staging, path)
        except FileExistsError:
            self._server.close()
            raise OSError(errno.EADDRINUSE, f"{path}: address already in use") from None
        finally:
            os.unlink(staging)
        self._server.setblocking(False)
        self._clients: dict[socket.socket, _Connection] = {}
        self.accept_errors = 0

    def service(self) -> int:
        """Read and answer what is waiting, accept new connections (and answer them); returns the requests answered. Never blocks."""
        served = self._serve(list(self._clients))  # first, so that connections their clients closed make room
        return served + self._serve(self._accept())

    def _serve(self, clients: list[socket.socket]) -> int:
        """Read from each of ``clients``, answer its complete lines, send what it can take; close it once it is done."""
        answered = 0
        for client in clients:
            conn = self._clients[client]
            if not conn.eof and len(conn.inbox) <= MAX_REQUEST_BYTES:  # a flood of requests waits in the kernel, not here
                self._read(client, conn)
            if client in self._clients:
                answered += self._answer_lines(client, conn)
            if client in self._clients:
                self._flush(client, conn)
            if client in self._clients and conn.eof and not conn.inbox and not conn.outbox:
                self._drop(client)
        return answered

    def close(self) -> None:
        for client in list(self._clients):
            self._drop(client)
        self._server.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path)

    def _accept(self) -> list[socket.socket]:
        accepted: list[socket.socket] = []
        for _ in range(MAX_ACCEPTS_PER_SERVICE):
            try:
                client, _ = self._server.accept()
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:  # out of file descriptors (EMFILE, ENFILE) or buffers: the connection waits in the backlog
                self.accept_errors += 1
                if self.accept_errors == 1 or self.accept_errors % 100 == 0:
                    log.warning("control socket: cannot accept a connection (%d so far): %s", self.accept_errors, exc)
                break
            client.setblocking(False)
            if len(self._clients) >= MAX_CLIENTS:
                with contextlib.suppress(OSError):
                    client.send(_encode({"ok": False, "reason": f"too many connections (at most {MAX_CLIENTS})"}))
                client.close()
                continue
            self._clients[client] = _Connection()
            accepted.append(client)
        return accepted

    def _read(self, client: socket.socket, conn: _Connection) -> None:
        try:
            data = client.recv(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            conn.eof = True  # answer what is complete (and a last line without its newline), then close
            return
        conn.inbox += data

    def _answer_lines(self, client: socket.socket, conn: _Connection) -> int:
        """Answer up to MAX_REQUESTS_PER_SERVICE complete lines; a line over MAX_REQUEST_BYTES drops the client."""
        answered = 0
        while answered < MAX_REQUESTS_PER_SERVICE:
            end = conn.inbox.find(b"\n")
            if (end if end >= 0 else len(conn.inbox)) > MAX_REQUEST_BYTES:
                conn.outbox += _encode({"ok": False, "reason": f"request over {MAX_REQUEST_BYTES} bytes"})
                self._flush(client, conn)
                self._drop(client)
                break
            if end < 0 and not (conn.eof and conn.inbox):
                break
            line = bytes(conn.inbox[:end] if end >= 0 else conn.inbox)
            del conn.inbox[: end + 1 if end >= 0 else len(conn.inbox)]
            conn.outbox += _encode(self._answer(line))
            answered += 1
            if len(conn.outbox) > MAX_UNREAD_REPLY_BYTES:  # it asks and never reads
                self._drop(client)
                break
        return answered

    def _answer(self, line: bytes) -> dict[str, Any]:
        try:
            request = json.loads(line, parse_constant=_not_finite, parse_float=_finite)
        except (ValueError, RecursionError) as exc:  # not UTF-8, not JSON, NaN, 1e999, an integer of over 4300 digits, nested too deep
            return {"ok": False, "reason": f"not a JSON request: {type(exc).__name__}: {str(exc)[:200]}"}
        if not isinstance(request, dict) or not isinstance(request.get("op"), str):
            return {"ok": False, "reason": 'a request is a JSON object with a string "op"'}
        try:
            return self._handler(request)
        except Exception as exc:  # a bad request must not take the executive down
            log.exception("control request %r failed", request.get("op"))
            return {"ok": False, "reason": f"{type(exc).__name__}: {exc}"}

    def _flush(self, client: socket.socket, conn: _Connection) -> None:
        """Send what the socket takes now; the rest waits for the next service."""
        while conn.outbox:
            try:
                sent = client.send(conn.outbox)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # the client went away
                self._drop(client)
                return
            del conn.outbox[:sent]

    def _drop(self, client: socket.socket) -> None:
        self._clients.pop(client, None)
        client.close()


def _finite(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text[:40]} is not a finite number")
    return value


def _not_finite(text: str) -> float:
    raise ValueError(f"{text} is not a number")


def _encode(reply: dict[str, Any]) -> bytes:
    """A reply as one JSON line; one that cannot be encoded says so."""
    try:
        return json.dumps(reply).encode() + b"\n"
    except (TypeError, ValueError) as exc:
        return json.dumps({"ok": False, "reason": f"the reply could not be encoded: {exc}"}).encode() + b"\n"


def socket_alive(path: str) -> bool:
    """Whether an executive answers on the Unix socket at ``path``."""
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        probe.connect(path)
    except OSError:
        return False
    finally:
        probe.close()
    return True


def request(path: str, op: str, timeout_s: float = 10.0, **args: Any) -> dict[str, Any]:
    """Client side: send one request, wait for its reply (raises OSError when no executive answers)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(timeout_s)
        sock.connect(path)
        sock.sendall(json.dumps({"op": op, **args}).encode() + b"\n")
        reply = bytearray()
        while not reply.endswith(b"\n"):
            chunk = sock.recv(65536)
            if not chunk:
                raise ConnectionError(f"{path}: the executive closed the connection without answering")
            reply += chunk
    return json.loads(reply)


__all__ = ["ControlServer", "SocketInUse", "default_socket_path", "request", "socket_alive"]
