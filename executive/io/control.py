"""The control socket: operator requests over a local Unix socket, one JSON object per line each way.

Owner-only (0600): only the user running the executive can command it. Serviced once per tick,
never blocking: pending connections are accepted, complete lines answered, the rest kept.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import socket
import tempfile
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)

MAX_REQUEST_BYTES = 4 << 20  # an upload carries a mission file (<= 1 MiB) as JSON text

Handler = Callable[[dict[str, Any]], dict[str, Any]]


def default_socket_path() -> str:
    """``$XDG_RUNTIME_DIR/executive.sock``, else a per-user file in the temp directory."""
    runtime_dir = os.environ.get("XDG_RUNTIME_DIR")
    return os.path.join(runtime_dir, "executive.sock") if runtime_dir else os.path.join(tempfile.gettempdir(), f"executive-{os.getuid()}.sock")


class SocketInUse(OSError):
    """Another executive is serving on this socket path."""


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
        old_umask = os.umask(0o177)
        try:
            self._server.bind(path)
        finally:
            os.umask(old_umask)
        os.chmod(path, 0o600)
        self._server.listen(8)
        self._server.setblocking(False)
        self._clients: dict[socket.socket, bytearray] = {}

    def service(self) -> int:
        """Accept, read and answer what is waiting; returns the number of requests answered."""
        while True:
            try:
                client, _ = self._server.accept()
            except (BlockingIOError, InterruptedError):
                break
            client.setblocking(False)
            self._clients[client] = bytearray()
        answered = 0
        for client, buffer in list(self._clients.items()):
            try:
                data = client.recv(65536)
            except (BlockingIOError, InterruptedError):
                continue
            except OSError:
                data = b""
            if not data:
                self._drop(client)
                continue
            buffer += data
            if len(buffer) > MAX_REQUEST_BYTES:
                self._send(client, {"ok": False, "reason": f"request over {MAX_REQUEST_BYTES} bytes"})
                self._drop(client)
                continue
            while b"\n" in buffer:
                line, _, rest = bytes(buffer).partition(b"\n")
                buffer[:] = rest
                self._send(client, self._answer(line))
                answered += 1
        return answered

    def close(self) -> None:
        for client in list(self._clients):
            self._drop(client)
        self._server.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path)

    def _answer(self, line: bytes) -> dict[str, Any]:
        try:
            request = json.loads(line)
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            return {"ok": False, "reason": f"not a JSON request: {exc}"}
        if not isinstance(request, dict) or not isinstance(request.get("op"), str):
            return {"ok": False, "reason": 'a request is a JSON object with a string "op"'}
        try:
            return self._handler(request)
        except Exception as exc:  # a bad request must not take the executive down
            log.exception("control request %r failed", request.get("op"))
            return {"ok": False, "reason": f"{type(exc).__name__}: {exc}"}

    def _send(self, client: socket.socket, reply: dict[str, Any]) -> None:
        try:
            client.setblocking(True)  # a reply is small; the client is waiting for it
            client.settimeout(1.0)
            client.sendall(json.dumps(reply).encode() + b"\n")
            client.setblocking(False)
        except OSError:
            self._drop(client)

    def _drop(self, client: socket.socket) -> None:
        self._clients.pop(client, None)
        client.close()


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
