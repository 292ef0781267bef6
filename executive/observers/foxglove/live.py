"""``run --foxglove [HOST:]PORT``: the running vehicle live in Foxglove, on the same channels as the MCAP file.

The Foxglove WebSocket server is the Foxglove SDK's (``foxglove-sdk``, imported only here): its
server runs on threads of its own (Rust), and logging a message only queues it for each client
subscribed (at most ``BACKLOG`` per client, the oldest dropped): the tick never waits on a client.
A client that joins late is given the tree, the run, its route and the mission's state again at
the next keyframe (every 100 ticks), as the file gives them at the top of each rotated file.
"""

from __future__ import annotations

from typing import Any

from executive.observers.mcap.messages import CHANNELS, schema_bytes
from executive.observers.mcap.recording import LATCHED

#: Messages kept for a client that does not read (the SDK's default is 1024): about 10 s of a run at 10 Hz.
BACKLOG = 1024


class FoxgloveAddressError(ValueError):
    """``--foxglove`` is not ``[HOST:]PORT``."""


def parse_address(text: str) -> tuple[str, int]:
    """``[HOST:]PORT`` (port 0: any free one); the host is 127.0.0.1, this machine alone, unless given."""
    host, _, port_text = text.rpartition(":")
    try:
        port = int(port_text)
    except ValueError:
        raise FoxgloveAddressError(f"{text!r} is not [HOST:]PORT: {port_text!r} is not a port number") from None
    if not 0 <= port <= 65535:
        raise FoxgloveAddressError(f"{text!r}: the port must be 0 to 65535")
    return host or "127.0.0.1", port


class FoxgloveSink:
    """A :class:`~executive.observers.mcap.recording.Sink` serving every message to Foxglove clients, live, on ``host``:``port``."""

    def __init__(self, host: str, port: int, backlog: int = BACKLOG) -> None:
        """``backlog``: messages kept for each client that has not read them yet (past it the SDK drops them)."""
        import foxglove

        self._foxglove = foxglove
        self._context = foxglove.Context()  # its own: nothing else logged in this process reaches the clients
        self._server = foxglove.start_server(name="executive", host=host, port=port, context=self._context, message_backlog_size=backlog)
        self.host, self.port = host, self._server.port
        self._channels: dict[str, Any] = {}
        self._latched: dict[str, tuple[tuple[str, bytes], int, bytes]] = {}
        for topic, name in CHANNELS.items():  # advertised from the start: a client subscribes before the run (MAVLink's as they come)
            self._channel(topic, (name, schema_bytes(name)))

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def put(self, topic: str, schema: tuple[str, bytes], log_ns: int, data: bytes) -> None:
        channel = self._channels.get(topic) or self._channel(topic, schema)
        channel.log(data, log_time=log_ns)
        if topic in LATCHED:
            self._latched[topic] = (schema, log_ns, data)

    def _channel(self, topic: str, schema: tuple[str, bytes]) -> Any:
        fox = self._foxglove
        channel = self._channels[topic] = fox.Channel(
            topic, schema=fox.Schema(name=schema[0], encoding="jsonschema", data=schema[1]), message_encoding="json", context=self._context
        )
        return channel

    def keyframe(self, tick: int, log_ns: int) -> None:
        for topic, (_, _, data) in self._latched.items():
            self._channels[topic].log(data, log_time=log_ns)

    def ticked(self) -> bool:
        return True

    def close(self) -> None:
        self._server.stop()
        for channel in self._channels.values():
            channel.close()
