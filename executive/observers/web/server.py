"""The web side of the live view: an aiohttp server in a thread of its own, one page, a WebSocket feed.

The page (``static/``, served from the package: no internet needed) gets frames over ``/ws``:
live, the latest frame at most ``FRAMES_PER_S`` times a wall second, each client at its own pace
(a slow one is sent the latest frame when it can take one, one that stops reading is dropped after
``SEND_TIMEOUT_S``); in a replay, the frame of the tick its slider asks for. ``POST /api/request``
passes pause / resume / abort to the operator on the tick thread and answers with its reply. When
the server listens beyond the loopback interface a request needs the token printed at start-up.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import ipaddress
import json
import logging
import secrets
import socket
import threading
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from executive.observers.web.feed import WEB_REQUESTS, Frame, LiveFeed, Seen

if TYPE_CHECKING:
    from aiohttp import web

log = logging.getLogger("executive.web.server")  # the name the log and the journal show, kept since 0.1

#: Live frames per second of wall time, at most (the page is for a person's eyes).
FRAMES_PER_S = 10.0
#: A client that cannot take a frame in this long (wall time) is dropped.
SEND_TIMEOUT_S = 10.0
#: How long a button's request waits for the tick thread's answer (wall time).
REQUEST_TIMEOUT_S = 5.0
MAX_CLIENTS = 16
#: The kernel's send buffer per client (else it grows to megabytes for a browser that stopped reading).
SEND_BUFFER_BYTES = 64 << 10
TOKEN_HEADER = "X-Executive-Token"
STATIC_FILES = {"index.html": "text/html", "live.js": "text/javascript", "live.css": "text/css"}


class WebAddressError(ValueError):
    """A ``--web`` address that cannot be used; ``str()`` says why."""


@dataclass(frozen=True)
class WebAddress:
    """Where the live view listens."""

    host: str
    port: int

    @property
    def loopback(self) -> bool:
        """Only this machine can reach it (no token needed)."""
        if self.host == "localhost":
            return True
        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:
            return False  # a host name: it may resolve to any interface

    def url(self, port: int | None = None) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port if port is None else port}/"


def parse_address(text: str) -> WebAddress:
    """``PORT``, ``HOST:PORT`` or ``[IPV6]:PORT``; the host is 127.0.0.1 unless given."""
    host, sep, port = text.rpartition(":")
    if not sep:
        host = "127.0.0.1"
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if not host:
        raise WebAddressError(f"{text!r}: no host before ':' (give [HOST:]PORT)")
    try:
        number = int(port)
    except ValueError:
        raise WebAddressError(f"{text!r}: the port {port!r} is not a number (give [HOST:]PORT)") from None
    if not 0 <= number <= 65535:
        raise WebAddressError(f"{text!r}: the port {number} is outside 0-65535")
    return WebAddress(host, number)


def read_token(path: str) -> str:
    """The token in ``path`` (its first line, stripped); WebAddressError when it cannot be read or is too short."""
    try:
        token = Path(path).read_text(encoding="utf-8").strip().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise WebAddressError(f"{path}: cannot read the token: {exc}") from exc
    if not token or len(token[0].strip()) < 16:
        raise WebAddressError(f"{path}:1:1: token: at least 16 characters")
    return token[0].strip()


def new_token() -> str:
    return secrets.token_urlsafe(18)


class Source(Protocol):
    """What the page shows: a run as it goes (:class:`LiveSource`) or a recording (:class:`executive.observers.web.replay.ReplaySource`)."""

    kind: str

    def hello(self) -> dict[str, Any]:
        """The first message to a client: what kind of view, what it may do."""

    def frame(self, tick: int | None) -> Frame | None:
        """The frame of ``tick`` (None: the latest); None when there is none yet."""


class LiveSource:
    """A running executive: frames from its :class:`LiveFeed`, requests to its operator."""

    kind = "live"

    def __init__(self, feed: LiveFeed) -> None:
        self.feed = feed

    def hello(self) -> dict[str, Any]:
        return {"requests": list(WEB_REQUESTS)}

    def frame(self, tick: int | None) -> Frame | None:
        self.feed.wanted = True  # the tick thread makes the next one
        return self.feed.latest


class _Browser:
    """One browser: the frame it is to be sent next (the latest wins) and what it has been sent."""

    def __init__(self, ws: web.WebSocketResponse) -> None:
        self.ws = ws
        self.seen = Seen()
        self.pending: Frame | None = None
        self.ready = asyncio.Event()
        #: Frames replaced by a newer one before this client could take them.
        self.superseded = 0

    def offer(self, frame: Frame) -> None:
        if self.pending is not None:
            self.superseded += 1
        self.pending = frame
        self.ready.set()

    async def pump(self) -> None:
        """Send each frame offered, the latest when several came while it was busy; drop the client once one cannot be sent in time."""
        while not self.ws.closed:
            await self.ready.wait()
            self.ready.clear()
            frame, self.pending = self.pending, None
            if frame is None:
                continue
            try:
                await asyncio.wait_for(self.ws.send_str(json.dumps(frame.message(self.seen))), SEND_TIMEOUT_S)
            except TimeoutError:
                log.info("live view: a browser that took no frame for %g s was dropped", SEND_TIMEOUT_S)
                await self.ws.close()
                return
            except (ConnectionError, RuntimeError):  # it went away
                return


Ask = Callable[[str, Callable[[dict[str, Any]], object]], None]


class WebServer:
    """The live view's server on ``address``: :meth:`bind` (OSError at once if the address cannot be had), :meth:`start`, :meth:`close`."""

    def __init__(
        self, address: WebAddress, *, token: str | None = None, frames_per_s: float = FRAMES_PER_S, send_buffer_bytes: int = SEND_BUFFER_BYTES
    ) -> None:
        self.address = address
        #: The kernel's send buffer for each client: what a browser that stops reading can hold up.
        self.send_buffer_bytes = send_buffer_bytes
        #: Live frames offered to each client per second of wall time, at most.
        self.frames_per_s = frames_per_s
        #: Required by requests (None: none needed, only this machine can reach the server).
        self.token = token
        self.source: Source | None = None
        self._ask: Ask | None = None
        self._clients: set[_Browser] = set()
        self._loop = asyncio.new_event_loop()
        self._thread: threading.Thread | None = None
        self._socket: socket.socket | None = None
        self._runner: web.AppRunner | None = None
        self._failed: Exception | None = None
        self.port = address.port
        #: Frames dropped for clients that could not keep up (the latest was sent instead).
        self.superseded = 0

    @property
    def url(self) -> str:
        return self.address.url(self.port)

    def bind(self) -> None:
        """Take the address now (OSError if it cannot be had): the port is known (``PORT`` 0 picks a free one) before anything runs."""
        family = socket.AF_INET6 if ":" in self.address.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.send_buffer_bytes)  # inherited by each accepted connection
            sock.bind((self.address.host, self.address.port))
            sock.listen(16)
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        self._socket = sock
        self.port = sock.getsockname()[1]

    def start(self, source: Source | None, ask: Ask | None = None) -> None:
        """Serve ``source`` from a daemon thread (binding first if :meth:`bind` was not called); ``ask`` passes requests to the operator."""
        if self._socket is None:
            self.bind()
        self.source, self._ask = source, ask
        started = threading.Event()
        self._thread = threading.Thread(target=self._serve, args=(started,), name="live view", daemon=True)
        self._thread.start()
        started.wait(10.0)
        if self._failed is not None:
            self.close()
            raise OSError(f"the live view's server did not start: {self._failed}") from self._failed

    def close(self) -> None:
        """Stop serving (bounded: a stuck client does not hold the executive up)."""
        if self._thread is not None:
            with contextlib.suppress(Exception):  # the loop may have ended already
                asyncio.run_coroutine_threadsafe(self._shutdown(), self._loop).result(2.0)
            with contextlib.suppress(RuntimeError):
                self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(2.0)
            self._thread = None
        if self._socket is not None:
            self._socket.close()  # (the server has closed it already, unless it never started)
            self._socket = None

    # -- the server's thread --------------------------------------------------------------------
    async def _shutdown(self) -> None:
        if self._runner is not None:
            await self._runner.cleanup()
        for task in asyncio.all_tasks():
            if task is not asyncio.current_task():
                task.cancel()

    def _serve(self, started: threading.Event) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self._setup())
        except Exception as exc:
            self._failed = exc
            self._loop.close()
            return
        finally:
            started.set()
        self._loop.create_task(self._broadcast())
        try:
            self._loop.run_forever()
        finally:
            self._loop.close()

    async def _setup(self) -> None:
        from aiohttp import web

        app = web.Application(client_max_size=4096)
        app.router.add_get("/", self._static)
        app.router.add_get("/static/{name}", self._static)
        app.router.add_get("/ws", self._feed)
        app.router.add_post("/api/request", self._request)
        self._runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=0.5)
        await self._runner.setup()
        assert self._socket is not None
        await web.SockSite(self._runner, self._socket).start()

    async def _broadcast(self) -> None:
        """Live: offer each client the latest frame, ``frames_per_s`` times a second while there are clients."""
        if self.source is None or self.source.kind != "live":
            return
        last: Frame | None = None
        while True:
            await asyncio.sleep(1.0 / self.frames_per_s)
            if not self._clients:
                continue
            frame = self.source.frame(None)
            if frame is not None and frame is not last:  # a new one
                last = frame
                for client in self._clients:
                    client.offer(frame)
            self.superseded = sum(client.superseded for client in self._clients)

    async def _static(self, request: web.Request) -> web.StreamResponse:
        from aiohttp import web

        name = request.match_info.get("name", "index.html")
        if name not in STATIC_FILES:
            raise web.HTTPNotFound()
        body = resources.files("executive.observers.web").joinpath("static", name).read_bytes()
        return web.Response(body=body, content_type=STATIC_FILES[name], headers={"Cache-Control": "no-cache"})

    async def _feed(self, request: web.Request) -> web.StreamResponse:
        from aiohttp import WSMsgType, web

        source = self.source
        if source is None or len(self._clients) >= MAX_CLIENTS:
            raise web.HTTPServiceUnavailable(text=f"at most {MAX_CLIENTS} live views at once")
        ws = web.WebSocketResponse(heartbeat=20.0)
        await ws.prepare(request)
        client = _Browser(ws)
        hello = {"hello": source.kind, "token_needed": self.token is not None, **source.hello()}
        await ws.send_str(json.dumps(hello))
        self._clients.add(client)
        pump = asyncio.create_task(client.pump())
        try:
            if (frame := source.frame(None)) is not None:
                client.offer(frame)
            async for msg in ws:  # a replay's slider asks for ticks
                if msg.type != WSMsgType.TEXT:
                    continue
                with contextlib.suppress(ValueError, TypeError, KeyError, LookupError):
                    frame = source.frame(int(json.loads(msg.data)["tick"]))
                    if frame is not None:
                        client.offer(frame)
        finally:
            self._clients.discard(client)
            pump.cancel()
        return ws

    async def _request(self, request: web.Request) -> web.StreamResponse:
        from aiohttp import web

        origin = request.headers.get("Origin")
        if origin is not None and origin.split("://", 1)[-1] != request.host:
            raise web.HTTPForbidden(text="a request from another site's page")
        if request.content_type != "application/json":  # a form posted by another site cannot send JSON without asking first (CORS)
            raise web.HTTPUnsupportedMediaType(text="send the request as application/json")
        if self.token is not None and not hmac.compare_digest(request.headers.get(TOKEN_HEADER, "").encode(), self.token.encode()):
            return web.json_response({"ok": False, "reason": "the token printed at start-up is needed (or wrong)"}, status=401)
        try:
            op = (await request.json())["op"]
        except (ValueError, KeyError, TypeError):
            return web.json_response({"ok": False, "reason": 'a request is {"op": "pause"|"resume"|"abort"}'}, status=400)
        if self._ask is None or op not in WEB_REQUESTS:
            takes = ", ".join(WEB_REQUESTS) if self._ask else "no"
            return web.json_response({"ok": False, "reason": f"this view takes only {takes} requests"}, status=400)
        loop = asyncio.get_running_loop()
        answer: asyncio.Future[dict[str, Any]] = loop.create_future()

        def reply(result: dict[str, Any]) -> None:  # on the tick thread: hand over, never wait
            with contextlib.suppress(RuntimeError):  # the server has stopped
                loop.call_soon_threadsafe(lambda: answer.done() or answer.set_result(result))

        self._ask(op, reply)
        try:
            return web.json_response(await asyncio.wait_for(answer, REQUEST_TIMEOUT_S))
        except TimeoutError:
            return web.json_response({"ok": False, "reason": f"the executive did not answer within {REQUEST_TIMEOUT_S:g} s"}, status=504)


def open_server(address_text: str, token_file: str | None) -> tuple[WebServer, str]:
    """A bound server for ``--web ADDRESS`` (and ``--web-token-file``), and what to tell the person at start-up.

    A token is needed when a token file is given, and always when the server listens beyond the
    loopback interface (a new one is made and shown if no file is given). WebAddressError: a bad
    address or token file; OSError: the address cannot be had.
    """
    address = parse_address(address_text)
    token = read_token(token_file) if token_file is not None else None if address.loopback else new_token()
    server = WebServer(address, token=token)
    server.bind()
    if token is None:
        return server, f"live view on {server.url}"
    if token_file is not None:
        return server, f"live view on {server.url} (its buttons need the token in {token_file})"
    return server, f"live view on {server.url} (its buttons need the token {token}: open {server.url}?token={token})"
