"""The Groot2 publisher's sockets: ZeroMQ request/reply on PORT and the publish socket on PORT + 1, as BehaviorTree.CPP binds them.

One thread of its own answers each request from a :class:`~executive.observers.groot2.view.MonitorView`
(``src/loggers/groot2_publisher.cpp``, ``Groot2Publisher::serverLoop``): ``FULLTREE`` the XML,
``STATUS`` the status records, ``BLACKBOARD`` (the subtree names, ``;``-separated) a msgpack map,
``TOGGLE_RECORDING`` (``start`` / ``stop``) and ``GET_TRANSITIONS`` the transitions. Breakpoints and
hooks are refused: they would make the tick wait for a person at a screen, and the executive's tick
never waits on a client. ``HOOKS_DUMP`` answers an empty list, ``REMOVE_ALL_HOOKS`` and
``DISABLE_ALL_HOOKS`` nothing, so that a client's start-up goes through. Nothing is ever published on
the publish socket (BehaviorTree.CPP sends only breakpoint notices on it); it is bound so a client that
connects to it finds it.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass

import msgpack
import zmq

from executive.observers.groot2.protocol import PROTOCOL_ID, ProtocolError, RequestHeader, RequestType, error_reply, reply_header
from executive.observers.groot2.view import MonitorView

log = logging.getLogger("executive.groot2.server")  # the name the log and the journal show, kept since 0.1


class Groot2AddressError(ValueError):
    """A ``--groot2`` value that is not [HOST:]PORT."""


@dataclass(frozen=True)
class Groot2Address:
    host: str
    port: int

    def __str__(self) -> str:
        return f"{self.host}:{self.port}"


def parse_address(text: str) -> Groot2Address:
    """``[HOST:]PORT``; the host is 127.0.0.1 (this machine only) unless given. The publish socket takes PORT + 1."""
    host, _, port_text = text.rpartition(":")
    try:
        port = int(port_text)
    except ValueError:
        raise Groot2AddressError(f"{text!r} is not [HOST:]PORT: {port_text!r} is not a port number") from None
    if not 1 <= port <= 65534:
        raise Groot2AddressError(f"{text!r}: the port must be 1 to 65534 (the publish socket takes the next one)")
    return Groot2Address(host or "127.0.0.1", port)


REFUSED = {
    RequestType.HOOK_INSERT: "breakpoints are not supported: the executive's tick never waits on a client",
    RequestType.HOOK_REMOVE: "Node ID not found",  # no hook was ever inserted
    RequestType.BREAKPOINT_UNLOCK: "Node ID not found",
}


class Groot2Server:
    """Serves ``view`` on ``address`` (and the port after it) from a thread of its own, until :meth:`close`."""

    POLL_MS = 100  # how often the thread looks whether it should stop (Groot2Publisher's receive timeout)

    def __init__(self, address: Groot2Address, view: MonitorView) -> None:
        self.address = address
        self.view = view
        self._context = zmq.Context()
        self._server = self._context.socket(zmq.REP)
        self._publisher = self._context.socket(zmq.PUB)
        for sock in (self._server, self._publisher):
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.SNDTIMEO, 1000)
        try:
            self._server.bind(f"tcp://{address.host}:{address.port}")
            self._publisher.bind(f"tcp://{address.host}:{address.port + 1}")
        except zmq.ZMQError as exc:
            self._context.destroy(linger=0)
            raise OSError(f"cannot listen on {address} and the port after it: {exc}") from exc
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="groot2", daemon=True)
        self.requests = 0  # answered, errors included

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self._context.destroy(linger=0)

    def _serve(self) -> None:
        poller = zmq.Poller()
        poller.register(self._server, zmq.POLLIN)
        while not self._stop.is_set():
            if not poller.poll(self.POLL_MS):
                continue
            frames = self._server.recv_multipart()
            try:
                reply = self.answer(frames)
            except Exception as exc:  # a bad request must not end the server: it is answered as an error
                log.warning("groot2: a request was not answered: %s", exc)
                reply = error_reply(str(exc))
            try:
                self._server.send_multipart(reply)
            except zmq.Again:
                log.warning("groot2: a client did not take its reply within 1 s")
            self.requests += 1

    def answer(self, frames: list[bytes]) -> list[bytes]:
        """The reply frames to one request."""
        try:
            request = RequestHeader.decode(frames[0] if frames else b"")
        except ProtocolError as exc:
            return error_reply(str(exc))
        if request.protocol != PROTOCOL_ID:
            return error_reply(f"protocol {request.protocol} is not Groot2's {PROTOCOL_ID}")
        view, kind = self.view, request.type
        head = reply_header(request, view.tree_uuid)
        if kind in REFUSED:
            return error_reply(REFUSED[kind])
        if kind == RequestType.FULLTREE:
            xml = view.tree_xml()
            return [head, xml.encode()] if xml is not None else error_reply("no tree is running yet")
        if kind == RequestType.STATUS:
            return [head, view.status_records()]
        if kind in (RequestType.BLACKBOARD, RequestType.TOGGLE_RECORDING) and len(frames) != 2:
            return error_reply("must be 2 parts message")  # Groot2Publisher's own words
        if kind == RequestType.BLACKBOARD:
            names = [n for n in frames[1].decode(errors="replace").split(";") if n]
            return [head, msgpack.packb(view.blackboard(names), use_bin_type=True)]
        if kind == RequestType.TOGGLE_RECORDING:
            command = frames[1].decode(errors="replace")
            if command == "start":
                return [head, str(view.start_recording()).encode()]
            if command == "stop":
                view.stop_recording()
            return [head]
        if kind == RequestType.GET_TRANSITIONS:
            return [head, view.take_transitions()]
        if kind == RequestType.HOOKS_DUMP:
            return [head, b"[]"]
        if kind in (RequestType.REMOVE_ALL_HOOKS, RequestType.DISABLE_ALL_HOOKS):
            return [head]
        return error_reply("Request not recognized")
