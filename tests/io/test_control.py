"""The control socket: owner-only, JSON lines, never blocking, never taken down by a bad request."""

from __future__ import annotations

import json
import os
import socket
import stat

import pytest

from executive.io.control import ControlServer, SocketInUse, request, socket_alive


@pytest.fixture
def path(tmp_path):
    return str(tmp_path / "executive.sock")


@pytest.fixture
def server(path):
    seen = []

    def handler(req):
        seen.append(req)
        if req["op"] == "explode":
            raise RuntimeError("boom")
        return {"ok": True, "echo": req}

    srv = ControlServer(path, handler)
    srv.seen = seen
    yield srv
    srv.close()


def talk(server, path: str, payload: bytes, replies: int = 1) -> list[dict]:
    """Send raw bytes, service the server until the replies are in."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as client:
        client.connect(path)
        client.sendall(payload)
        client.settimeout(2.0)
        data = b""
        for _ in range(200):
            server.service()
            try:
                client.setblocking(False)
                data += client.recv(65536)
            except BlockingIOError:
                pass
            if data.count(b"\n") >= replies:
                break
        return [json.loads(line) for line in data.splitlines()]


def test_the_socket_is_owner_only(server, path):
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600


def test_one_reply_per_request_line(server, path):
    replies = talk(server, path, b'{"op": "status"}\n{"op": "pause"}\n', replies=2)
    assert [r["echo"]["op"] for r in replies] == ["status", "pause"]


def test_a_request_split_across_reads_is_reassembled(server, path):
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as client:
        client.connect(path)
        client.sendall(b'{"op": "st')
        server.service()
        server.service()
        assert server.seen == []
        client.sendall(b'atus"}\n')
        for _ in range(50):
            server.service()
            if server.seen:
                break
    assert server.seen == [{"op": "status"}]


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b"not json\n", "not a JSON request"),
        (b"[1, 2]\n", 'a request is a JSON object with a string "op"'),
        (b'{"op": 5}\n', 'a request is a JSON object with a string "op"'),
        (b'{"op": "explode"}\n', "RuntimeError: boom"),
        (b"\xff\xfe\n", "not a JSON request"),
    ],
)
def test_bad_requests_get_a_reason_and_the_server_lives_on(server, path, payload, reason):
    (reply,) = talk(server, path, payload)
    assert reply["ok"] is False and reason in reply["reason"]
    assert talk(server, path, b'{"op": "status"}\n')[0]["ok"] is True


def test_service_never_blocks_without_clients(server):
    assert server.service() == 0


def test_a_stale_socket_file_is_replaced_but_a_live_one_is_not(path):
    with open(path, "w"):
        pass  # left behind by a crash (not a listening socket)
    srv = ControlServer(path, lambda r: {"ok": True})
    try:
        assert socket_alive(path)
        with pytest.raises(SocketInUse):
            ControlServer(path, lambda r: {"ok": True})
    finally:
        srv.close()
    assert not os.path.exists(path)


def test_client_request_round_trip(server, path):
    import threading

    stop = threading.Event()

    def serve():
        while not stop.is_set():
            server.service()
            stop.wait(0.005)

    thread = threading.Thread(target=serve)
    thread.start()
    try:
        assert request(path, "upload", filename="m.yaml", text="x") == {"ok": True, "echo": {"op": "upload", "filename": "m.yaml", "text": "x"}}
    finally:
        stop.set()
        thread.join()


def test_client_without_an_executive_raises(tmp_path):
    with pytest.raises(OSError):
        request(str(tmp_path / "nobody.sock"), "status", timeout_s=0.5)
