"""A CAN bus in memory: two ends on a channel of their own, what one sends the other receives."""

from __future__ import annotations

import itertools
import queue
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Self

if TYPE_CHECKING:
    import can

_channels = itertools.count()


class MemoryBus:
    """One end of a two-ended bus in memory, with the calls the executive makes on a ``can.BusABC`` (``send``, ``recv``, ``shutdown``).

    Each frame sent reaches the other end as a copy (its own ``data``, ``is_rx`` set, stamped with the time it was
    sent), in order. Not
    python-can's ``virtual`` interface: that one deep-copies every frame for every listener, a third of
    a lock-step bunker run with its CAN base.
    """

    def __init__(self, channel: str) -> None:
        self.channel = channel
        self.channel_info = f"in-memory CAN {channel}"
        self._incoming: queue.SimpleQueue[can.Message] = queue.SimpleQueue()
        self._peer: MemoryBus | None = None
        self._open = True

    @classmethod
    def pair(cls, channel: str) -> tuple[MemoryBus, MemoryBus]:
        """Two ends of a fresh bus."""
        one, other = cls(channel), cls(channel)
        one._peer, other._peer = other, one
        return one, other

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        import can

        if not self._open:
            raise can.CanOperationError("Cannot operate on a closed bus")
        assert self._peer is not None
        self._peer._incoming.put(
            can.Message(
                timestamp=time.time(),  # when it was sent, as python-can's virtual bus stamps it
                arbitration_id=msg.arbitration_id,
                is_extended_id=msg.is_extended_id,
                is_remote_frame=msg.is_remote_frame,
                is_error_frame=msg.is_error_frame,
                channel=self.channel,
                dlc=msg.dlc,
                data=msg.data,
                is_fd=msg.is_fd,
                is_rx=True,
                bitrate_switch=msg.bitrate_switch,
                error_state_indicator=msg.error_state_indicator,
            )
        )

    def recv(self, timeout: float | None = None) -> can.Message | None:
        """The next frame received, waiting at most ``timeout`` seconds for one (None: for ever); None if none came."""
        if not self._open:
            import can

            raise can.CanOperationError("Cannot operate on a closed bus")
        try:
            return self._incoming.get(block=timeout != 0, timeout=timeout) if timeout != 0 else self._incoming.get_nowait()
        except queue.Empty:
            return None

    def shutdown(self) -> None:
        """Close this end (idempotent)."""
        self._open = False


class VirtualCan:
    """Two ends of a fresh CAN bus in memory (:class:`MemoryBus`): what one end sends, the other receives (not itself).

    ``with VirtualCan() as (base, ours): ...`` (the base's end first), or keep it and :meth:`shutdown`
    both ends after. Each one is on a channel of its own, so tests never hear each other's frames.
    """

    def __init__(self, name: str = "executive-test") -> None:
        #: The far end (the AgileX base, or whatever the test plays); and the executive's end.
        self.base, self.ours = MemoryBus.pair(f"{name}-{next(_channels)}")

    def __iter__(self) -> Iterator[can.BusABC]:
        return iter((self.base, self.ours))  # type: ignore[arg-type]  # what the executive calls on a bus

    def shutdown(self) -> None:
        """Shut both ends (idempotent)."""
        self.base.shutdown()
        self.ours.shutdown()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()
