"""The live view's server: where it listens, who may press its buttons, and what reaches the operator."""

from __future__ import annotations

import json
import socket
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.cli import main
from executive.observers.web.server import TOKEN_HEADER, WebAddress, WebAddressError, WebServer, open_server, parse_address, read_token

TOKEN = "a-token-of-twenty-chars"
SQUARE = str(Path(__file__).parents[3] / "missions" / "rover_square.yaml")


@pytest.mark.parametrize(
    ("text", "host", "port", "loopback"),
    [
        ("8080", "127.0.0.1", 8080, True),
        ("localhost:8080", "localhost", 8080, True),
        ("[::1]:9000", "::1", 9000, True),
        ("0.0.0.0:8080", "0.0.0.0", 8080, False),
        ("192.0.2.7:80", "192.0.2.7", 80, False),
        ("vehicle.local:80", "vehicle.local", 80, False),  # a name may resolve to any interface
    ],
)
def test_addresses(text, host, port, loopback):
    address = parse_address(text)
    assert (address.host, address.port, address.loopback) == (host, port, loopback)


@pytest.mark.parametrize(("text", "why"), [("http", "not a number"), (":80", "no host"), ("70000", "outside 0-65535"), ("h:8o", "'8o'")])
def test_bad_addresses_say_why(text, why):
    with pytest.raises(WebAddressError, match=why):
        parse_address(text)


def test_a_token_file_holds_at_least_16_characters(tmp_path):
    short = tmp_path / "short"
    short.write_text("abc\n")
    with pytest.raises(WebAddressError, match=f"{short}:1:1: token: at least 16 characters"):
        read_token(str(short))
    good = tmp_path / "good"
    good.write_text(f"  {TOKEN}  \nignored\n")
    assert read_token(str(good)) == TOKEN
    with pytest.raises(WebAddressError, match="cannot read"):
        read_token(str(tmp_path / "none"))


def test_start_up_names_the_token_file_but_not_its_token(tmp_path):
    path = tmp_path / "token"
    path.write_text(TOKEN)
    server, told = open_server("127.0.0.1:0", str(path))
    server.close()
    assert server.token == TOKEN and str(path) in told and TOKEN not in told
    server, told = open_server("127.0.0.1:0", None)
    server.close()
    assert server.token is None and told == f"live view on http://127.0.0.1:{server.port}/"


def test_beyond_loopback_a_new_token_is_made_and_printed():
    server, told = open_server("0.0.0.0:0", None)  # bound for a moment, nothing sent
    server.close()
    assert server.token is not None and len(server.token) >= 16
    assert (
        told
        == f"live view on http://0.0.0.0:{server.port}/ (its buttons need the token {server.token}: open http://0.0.0.0:{server.port}/?token={server.token})"
    )
    again, _ = open_server("0.0.0.0:0", None)
    again.close()
    assert again.token != server.token


@pytest.fixture
def server() -> Iterator[tuple[WebServer, list[str]]]:
    """A server needing TOKEN whose requests are answered at once (as the operator does on the tick thread)."""
    asked: list[str] = []

    def ask(op, reply):
        asked.append(op)
        reply({"ok": True, "reason": f"web: {op}", "state": "PAUSED"})

    web = WebServer(WebAddress("127.0.0.1", 0), token=TOKEN)
    web.start(None, ask=ask)  # no frames: only the buttons' requests
    yield web, asked
    web.close()


def post(server: WebServer, body: object, headers: dict[str, str]) -> tuple[int, dict]:
    data = body if isinstance(body, bytes) else json.dumps(body).encode()
    request = urllib.request.Request(f"{server.url}api/request", data=data, headers=headers, method="POST")
    try:
        with urllib.request.urlopen(request, timeout=10) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read() or b"{}") if error.headers.get_content_type() == "application/json" else {}


def test_a_request_needs_the_token(server):
    web, asked = server
    json_type = {"Content-Type": "application/json"}
    assert post(web, {"op": "pause"}, json_type)[0] == 401
    assert post(web, {"op": "pause"}, {**json_type, TOKEN_HEADER: "wrong"})[0] == 401
    assert asked == []
    status, reply = post(web, {"op": "pause"}, {**json_type, TOKEN_HEADER: TOKEN})
    assert (status, reply) == (200, {"ok": True, "reason": "web: pause", "state": "PAUSED"})
    assert asked == ["pause"]


def test_only_pause_resume_abort_as_json_from_our_own_page(server):
    web, asked = server
    ok = {"Content-Type": "application/json", TOKEN_HEADER: TOKEN}
    assert post(web, {"op": "delete"}, ok)[0] == 400
    assert post(web, b"not json", ok)[0] == 400
    assert post(web, {"op": "pause"}, {**ok, "Content-Type": "text/plain"})[0] == 415  # a form another site posts
    assert post(web, {"op": "pause"}, {**ok, "Origin": "http://elsewhere.example"})[0] == 403
    assert post(web, {"op": "abort"}, {**ok, "Origin": f"http://127.0.0.1:{web.port}"})[0] == 200
    assert asked == ["abort"]


def test_the_page_and_its_assets_come_from_the_package(server):
    web, _ = server
    with urllib.request.urlopen(web.url, timeout=10) as page:
        html = page.read().decode()
    assert '<script src="/static/live.js">' in html and "http" not in html.replace('xmlns="http://www.w3.org/2000/svg"', "")
    for name in ("live.js", "live.css"):
        with urllib.request.urlopen(f"{web.url}static/{name}", timeout=10) as asset:
            assert asset.status == 200 and b"//cdn" not in asset.read()
    with pytest.raises(urllib.error.HTTPError, match="404"):
        urllib.request.urlopen(f"{web.url}static/..%2Fserver.py", timeout=10)


def test_run_web_usage_errors(capsys):
    assert main(["run", SQUARE, "--web-token-file", "t"]) == 2
    assert "--web-token-file needs --web" in capsys.readouterr().err
    assert main(["run", SQUARE, "--web", "70000"]) == 2
    assert "--web: '70000': the port 70000 is outside 0-65535" in capsys.readouterr().err


def test_run_web_port_in_use_exits_3(capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        assert main(["run", SQUARE, "--web", str(port), "--socket", "none"]) == 3
    assert f"--web: cannot listen on {port}" in capsys.readouterr().err
