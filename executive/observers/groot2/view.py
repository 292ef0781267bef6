"""What a Groot2 monitor is shown, handed from the tick thread to the server thread without either waiting for the other.

The tick side (:meth:`MonitorView.show_tree`, :meth:`MonitorView.ticked`) replaces immutable values
(one reference each: the latest wins) and appends transitions to a bounded deque; the server side
reads them. Nothing on the tick side takes a lock, blocks, or does more than a walk of the tree's
statuses; the blackboard is copied only while a client has asked for it in the last few seconds.
"""

from __future__ import annotations

import collections
import dataclasses
import enum
import math
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from executive.observers.groot2.model import MonitoredNode, StatusTrack, to_xml
from executive.observers.groot2.protocol import IDLE, IDLE_AFTER, status_buffer, transitions_buffer

#: Transitions kept for a client that records (BehaviorTree.CPP keeps 1000 too).
MAX_TRANSITIONS = 1000
#: The blackboard is copied each tick for this long after a client last asked for it.
BLACKBOARD_INTEREST_S = 5.0


def jsonable(value: Any) -> Any:
    """A blackboard value as JSON-like data for msgpack: numbers, text, lists and maps; anything else as its repr."""
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else repr(value)
    if isinstance(value, enum.Enum):
        return value.name
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [jsonable(v) for v in value]
    return repr(value)


class _Tree:
    """One tree as served: its UUID (new for each tree: a client fetches the tree again), XML (made on first request), status records."""

    def __init__(self, root: MonitoredNode, describe: Callable[[], MonitoredNode] | None) -> None:
        self.uuid = uuid.uuid4().bytes
        self._root = root
        self._describe = describe  # the same tree with ports: made on the server's thread, when first asked
        self._xml: str | None = None
        self.uids = [node.uid for node in root.preorder()]
        self.track = StatusTrack(self.uids)
        self.statuses = status_buffer((uid, IDLE) for uid in self.uids)

    def xml(self) -> str:
        if self._xml is None:
            self._xml = to_xml(self._describe() if self._describe is not None else self._root)
        return self._xml


class MonitorView:
    """The tree, its statuses, transitions and blackboard, as the last tick left them."""

    def __init__(self, wall_clock: Callable[[], float] = time.time) -> None:
        self._tree: _Tree | None = None
        self._wall = wall_clock
        self._transitions: collections.deque[tuple[int, int, int]] = collections.deque(maxlen=MAX_TRANSITIONS)
        self._recording_since: float | None = None  # the tick time recording started at (set by the tick side)
        self.recording = False
        self._board: dict[str, Any] = {}
        self._board_serial = 0  # how many copies the tick side made
        self._board_wanted_until = -math.inf  # wall time, set by the server side
        self._blackboard: Callable[[], Mapping[str, Any]] | None = None

    # -- the tick side -----------------------------------------------------------------------------------

    def show_tree(self, root: MonitoredNode, describe: Callable[[], MonitoredNode] | None = None) -> None:
        """A new tree (a run begins): its statuses all IDLE, a new UUID."""
        self._tree = _Tree(root, describe)
        self._transitions.clear()

    def ticked(self, statuses: Sequence[int | None], t: float, blackboard: Callable[[], Mapping[str, Any]] | None = None) -> None:
        """After a tick: each node's status in pre-order (a Groot2 code, None for not ticked), at tick time ``t`` (seconds)."""
        tree = self._tree
        if tree is None:
            return
        changed = tree.track.update(statuses)
        if changed:
            tree.statuses = status_buffer(zip(tree.uids, tree.track.codes, strict=True))
        if self.recording:
            if self._recording_since is None:
                self._recording_since = t
            us = round((t - self._recording_since) * 1e6)
            self._transitions.extend((us, uid, code if code < IDLE_AFTER else IDLE) for uid, code in changed)
        else:
            self._recording_since = None
        if blackboard is not None and self._wall() < self._board_wanted_until:
            self._board = {key: jsonable(value) for key, value in blackboard().items()}
            self._board_serial += 1

    # -- the server side ---------------------------------------------------------------------------------

    @property
    def tree_uuid(self) -> bytes:
        tree = self._tree
        return tree.uuid if tree is not None else bytes(16)

    def tree_xml(self) -> str | None:
        tree = self._tree
        return tree.xml() if tree is not None else None

    def status_records(self) -> bytes:
        tree = self._tree
        return tree.statuses if tree is not None else b""

    def blackboard(self, names: Sequence[str], wait_s: float = 0.5) -> dict[str, dict[str, Any]]:
        """The blackboard of each subtree asked for: ours is one, ``MainTree`` (others are left out, as BehaviorTree.CPP does).

        The first request in a while waits (on the server's thread) up to ``wait_s`` for the next tick's copy.
        """
        idle = self._wall() >= self._board_wanted_until
        self._board_wanted_until = self._wall() + BLACKBOARD_INTEREST_S
        if idle:
            serial, deadline = self._board_serial, time.monotonic() + wait_s
            while self._board_serial == serial and time.monotonic() < deadline:
                time.sleep(0.01)
        return {name: self._board for name in names if name == "MainTree"}

    def start_recording(self) -> int:
        """Transitions are kept from the next tick on; the wall time now in microseconds (what the client times them from)."""
        self._transitions.clear()
        self._recording_since = None
        self.recording = True
        return round(self._wall() * 1e6)

    def stop_recording(self) -> None:
        self.recording = False

    def take_transitions(self) -> bytes:
        """The transitions kept since the last time, as 9-byte records."""
        taken = []
        while self._transitions:
            taken.append(self._transitions.popleft())
        return transitions_buffer(taken)
