"""Hostile clients on the control socket: garbage, huge lines, floods, half-open and many connections, no file descriptors left.

The server's contract: :meth:`ControlServer.service` never raises and never blocks (every call returns in
well under a tick), every complete line gets exactly one reply in order, and a well-formed request is
answered whatever came before it.
"""

from __future__ import annotations

import contextlib
import errno
import json
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.io.control import MAX_CLIENTS, MAX_REQUEST_BYTES, ControlServer
from tests_support import runqueue_wait_s

ROOT = Path(__file__).parents[2]
TICK_BUDGET_S = 0.5  # a service() call takes well under 40 ms here; a blocking send stalled it for 1 s (time waiting for a CPU left out)
GOOD = b'{"op": "status"}\n'


class Server:
    """A ControlServer whose handler echoes; :meth:`pump` services it and keeps the slowest call."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.seen: list[dict[str, Any]] = []
        self.control = ControlServer(path, self._handle)
        self.slowest = 0.0

    def _handle(self, request: dict[str, Any]) -> dict[str, Any]:
        self.seen.append(request)
        if request["op"] == "explode":
            raise RuntimeError("boom")
        return {"ok": True, "echo": request}

    def tick(self) -> None:
        """One service() call, timed: the wall time less what this thread waited for a CPU (a blocking call still counts in full)."""
        start, waited = time.perf_counter(), runqueue_wait_s()
        self.control.service()
        self.slowest = max(self.slowest, time.perf_counter() - start - (runqueue_wait_s() - waited))

    def pump(self, until: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Service until ``until()`` (or fail after ``timeout_s``)."""
        deadline = time.monotonic() + timeout_s
        while not until():
            assert time.monotonic() < deadline, "the server never got there"
            self.tick()


class Client:
    """A non-blocking client that collects reply lines as they come."""

    def __init__(self, path: str, server: Server | None = None) -> None:
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.setblocking(False)
        while (code := self.sock.connect_ex(path)) in (errno.EAGAIN, errno.EWOULDBLOCK):  # the backlog is full: let the server accept
            assert server is not None, "the listen backlog is full"
            server.tick()
        assert code == 0, errno.errorcode[code]
        self.received = b""
        self.closed_by_server = False

    def send(self, data: bytes) -> int:
        try:
            return self.sock.send(data)
        except (BlockingIOError, BrokenPipeError, ConnectionResetError):  # full, or the server has closed the connection
            return 0

    def replies(self) -> list[dict[str, Any]]:
        while not self.closed_by_server:
            try:
                chunk = self.sock.recv(1 << 20)
            except BlockingIOError:
                break
            except ConnectionResetError:
                chunk = b""
            self.received += chunk
            self.closed_by_server = not chunk
        return [json.loads(line) for line in self.received.splitlines()]

    def send_all(self, data: bytes, server: Server) -> None:
        """Send all of ``data``, servicing the server whenever the socket is full."""
        while data:
            data = data[self.send(data) :]
            server.tick()

    def gone(self) -> bool:
        """Whether the server has closed the connection (reading what is left)."""
        self.replies()
        return self.closed_by_server

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def server(tmp_path: Path) -> Iterator[Server]:
    srv = Server(str(tmp_path / "executive.sock"))
    yield srv
    srv.control.close()
    assert srv.slowest < TICK_BUDGET_S, f"a service() call took {srv.slowest:.3f} s"


def exchange(server: Server, payload: bytes, lines: int) -> list[dict[str, Any]]:
    """Send ``payload`` on a new connection and collect ``lines`` replies."""
    client = Client(server.path, server)
    client.send_all(payload, server)
    server.pump(lambda: len(client.replies()) >= lines)
    replies = client.replies()
    client.close()
    return replies


#: Lines that are no request, and the one that is: (line, whether it is answered ok).
NONSENSE = [
    (b"[" * 100_000, False),
    (b'{"op": "status", "x": ' + b"[" * 10_000, False),
    (b'{"a": ' * 50_000, False),
    (b"9" * 5_000, False),
    (b'{"op": "status", "n": ' + b"9" * 5_000 + b"}", False),
    (b'{"op": "status", "x": 1e999999}', False),
    (b'{"op": "status", "x": NaN}', False),
    (b'{"op": "status", "x": -Infinity}', False),
    (b"\xff\xfe\x00{", False),
    (b"\x00" * 100, False),
    (b'{"op": null}', False),
    (b'{"op": ["status"]}', False),
    (b'"op"', False),
    (b"", False),
    (b'{"op": "explode"}', False),
    (b"\xef\xbb\xbf" + GOOD.strip(), True),  # a UTF-8 BOM: json reads it
    (b'{"op": "\\ud800"}', True),  # a lone surrogate is a string JSON allows
]


@pytest.mark.parametrize(("line", "ok"), NONSENSE, ids=lambda b: repr(b[:24]) if isinstance(b, bytes) else str(b))
def test_nonsense_gets_a_reason_and_the_next_request_an_answer(server: Server, line: bytes, ok: bool) -> None:
    """Deep nesting, 5000-digit integers, NaN and 1e999, NUL, bad UTF-8, a handler that raises: an ok:false reply, then service as usual."""
    replies = exchange(server, line + b"\n" + GOOD, 2)
    assert [r["ok"] for r in replies] == [ok, True]
    assert replies[1] == {"ok": True, "echo": {"op": "status"}}
    assert ok or "echo" not in replies[0], "nothing that is not a request reaches the handler"


GARBAGE = st.one_of(st.binary(max_size=300), st.sampled_from([line for line, _ in NONSENSE]), st.text(max_size=50).map(str.encode)).map(
    lambda b: b.replace(b"\n", b"")
)


@settings(derandomize=True, deadline=None, max_examples=30, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(garbage=st.lists(GARBAGE, max_size=6), split=st.integers(1, 4096))
def test_any_garbage_then_a_well_formed_request(server: Server, garbage: list[bytes], split: int) -> None:
    """One reply per line, in order, whatever the lines hold and however they are cut; the well-formed request at the end is answered."""
    payload = b"".join(g + b"\n" for g in garbage) + GOOD
    client = Client(server.path, server)
    for start in range(0, len(payload), split):
        client.send_all(payload[start : start + split], server)
    server.pump(lambda: len(client.replies()) >= len(garbage) + 1)
    replies = client.replies()
    client.close()
    assert len(replies) == len(garbage) + 1 and all(isinstance(r["ok"], bool) for r in replies)
    assert replies[-1] == {"ok": True, "echo": {"op": "status"}}


def test_a_line_over_4_mib_is_refused_while_others_are_served(server: Server) -> None:
    """The huge line streams in over many ticks; another client is answered meanwhile; the huge one is refused and closed."""
    huge, other = Client(server.path, server), Client(server.path, server)
    payload, sent = b"x" * (MAX_REQUEST_BYTES + 65536), 0
    other.send(GOOD)
    while not huge.gone():
        sent += huge.send(payload[sent:]) if sent < len(payload) else 0
        server.tick()
    assert other.replies() == [{"ok": True, "echo": {"op": "status"}}]
    assert huge.replies() == [{"ok": False, "reason": f"request over {MAX_REQUEST_BYTES} bytes"}]


def test_a_client_that_never_reads_cannot_stall_the_tick(server: Server) -> None:
    """A flood of requests whose replies are never read: every service() stays short and another client is still answered."""
    flooder = Client(server.path, server)
    burst = GOOD * 1000
    for _ in range(300):
        flooder.send(burst)
        server.tick()
    assert exchange(server, GOOD, 1) == [{"ok": True, "echo": {"op": "status"}}]
    flooder.close()


def test_a_client_that_stops_sending_still_gets_its_answers(server: Server) -> None:
    """Half-closed (shutdown for writing): every request is answered, the last one even without its newline; then the server closes."""
    client = Client(server.path, server)
    client.send(GOOD + b'{"op": "pause"}\n{"op": "resume"}')
    client.sock.shutdown(socket.SHUT_WR)
    server.pump(client.gone)
    assert [r["echo"]["op"] for r in client.replies()] == ["status", "pause", "resume"]


def test_clients_that_vanish_or_go_silent_change_nothing(server: Server) -> None:
    """Connect-and-close, close right after asking, a half-written request left hanging: no exception, and the next client is served."""
    for _ in range(50):
        Client(server.path, server).close()
    asker = Client(server.path, server)
    asker.send(GOOD * 10)
    asker.close()
    silent = Client(server.path, server)
    silent.send(b'{"op": "sta')
    for _ in range(20):
        server.tick()
    assert exchange(server, GOOD, 1) == [{"ok": True, "echo": {"op": "status"}}]
    silent.close()


def test_many_connections_at_once(server: Server) -> None:
    """Four times as many clients as are served at once: each gets one reply (an answer or 'too many'), and the server lives on."""
    clients = [Client(server.path, server) for _ in range(4 * MAX_CLIENTS)]
    for client in clients:
        client.send(GOOD)
    server.pump(lambda: all(client.replies() for client in clients))
    replies = [client.replies() for client in clients]
    assert all(len(r) == 1 for r in replies)
    answered = sum(r[0] == {"ok": True, "echo": {"op": "status"}} for r in replies)
    refused = sum(r[0] == {"ok": False, "reason": f"too many connections (at most {MAX_CLIENTS})"} for r in replies)
    assert (answered + refused, answered >= MAX_CLIENTS) == (len(clients), True)
    for client in clients:
        client.close()
    assert exchange(server, GOOD, 1) == [{"ok": True, "echo": {"op": "status"}}]


SERVER_WITHOUT_FILE_DESCRIPTORS = textwrap.dedent(
    """
    import os, resource, sys, time
    from executive.io.control import ControlServer
    path, stop = sys.argv[1], sys.argv[2]
    server = ControlServer(path, lambda request: {"ok": True, "op": request["op"]})
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(map(int, os.listdir("/proc/self/fd"))) + 4, resource.getrlimit(resource.RLIMIT_NOFILE)[1]))
    print("ready", flush=True)
    deadline, told = time.monotonic() + 30, False
    while not os.path.exists(stop) and time.monotonic() < deadline:
        server.service()
        if server.accept_errors and not told:
            print("out of file descriptors", flush=True)
            told = True
        time.sleep(0.002)
    server.close()
    print("accept errors", server.accept_errors, flush=True)
    """
)


@contextlib.contextmanager
def answering(path: str, hang_s: float = 30.0) -> Iterator[socket.socket]:
    """A connection to ``path`` once the server has room in its backlog again (it drains it at its own pace: no wall-clock margin)."""
    deadline = time.monotonic() + hang_s
    while True:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(10.0)
        try:
            sock.connect(path)
            break
        except BlockingIOError:  # EAGAIN: the backlog is still full
            sock.close()
            assert time.monotonic() < deadline, "the server never accepted again"
            time.sleep(0.05)
    with sock:
        yield sock


def test_running_out_of_file_descriptors(tmp_path: Path) -> None:
    """A server with room for three connections and forty clients: accept fails (EMFILE) and it lives on, then answers."""
    path, stop = str(tmp_path / "s.sock"), tmp_path / "stop"
    child = subprocess.Popen(
        [sys.executable, "-c", SERVER_WITHOUT_FILE_DESCRIPTORS, path, str(stop)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout is not None and child.stdout.readline() == "ready\n"
        clients = []
        for _ in range(40):
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.settimeout(0.2)
            try:
                sock.connect(path)
                sock.sendall(GOOD)
            except OSError:  # the backlog is full: the server cannot accept
                pass
            clients.append(sock)
        assert child.stdout.readline() == "out of file descriptors\n"  # accept failed (EMFILE), and the server went on
        for sock in clients:
            sock.close()
        with answering(path) as sock:
            sock.sendall(GOOD)
            reply = b""
            while not reply.endswith(b"\n"):
                reply += sock.recv(4096) or b"\n"
        assert json.loads(reply) == {"ok": True, "op": "status"}
    finally:
        stop.touch()
        out, err = child.communicate(timeout=30)
    assert (child.returncode, "Traceback" in err) == (0, False), err
    assert int(out.split()[-1]) > 0, "the test never ran the server out of file descriptors"
