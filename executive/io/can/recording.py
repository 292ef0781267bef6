"""``--can-log``: record every frame read from or sent to a bus in candump's log format."""

from __future__ import annotations

import time

import can


class RecordingBus(can.BusABC):
    """Wraps a bus: what is received and sent also goes to ``path`` (``.log`` = candump -L, readable by can-utils)."""

    def __init__(self, bus: can.BusABC, path: str) -> None:
        self._bus = bus
        self._log = can.Logger(path)
        self.channel_info = f"recording {bus.channel_info}"
        super().__init__(channel=getattr(bus, "channel", None))

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        msg = self._bus.recv(timeout)
        if msg is not None:
            self._log(msg)
        return msg, False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._bus.send(msg, timeout)
        if not msg.timestamp:  # frames we build carry no time; a log line needs the moment it left
            msg.timestamp = time.time()
        msg.is_rx = False  # candump's T, not R: the executive's own 0x111/0x421 told from the base's frames
        self._log(msg)

    def shutdown(self) -> None:
        self._log.stop()
        self._bus.shutdown()
        super().shutdown()
