"""A CAN bus in memory: python-can's ``virtual`` interface, two ends on a channel of their own."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import TYPE_CHECKING, Self

if TYPE_CHECKING:
    import can

_channels = itertools.count()


class VirtualCan:
    """Two ends of a fresh CAN bus in memory: what one end sends, the other receives (not itself).

    ``with VirtualCan() as (base, ours): ...`` (the base's end first), or keep it and :meth:`shutdown`
    both ends after. Each one is on a channel of its own, so tests never hear each other's frames.
    """

    def __init__(self, name: str = "executive-test") -> None:
        import can  # not at import: python-can costs every process that loads the kit 45 ms

        channel = f"{name}-{next(_channels)}"
        #: The far end (the AgileX base, or whatever the test plays).
        self.base: can.BusABC = can.Bus(interface="virtual", channel=channel)
        #: The executive's end.
        self.ours: can.BusABC = can.Bus(interface="virtual", channel=channel)

    def __iter__(self) -> Iterator[can.BusABC]:
        return iter((self.base, self.ours))

    def shutdown(self) -> None:
        """Shut both ends (idempotent)."""
        self.base.shutdown()
        self.ours.shutdown()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()
