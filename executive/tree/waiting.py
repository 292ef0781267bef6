"""What the mission is waiting for: the deepest running node of its tree, that node's feedback, and for how long.

One rule for every view (the live status line, ``executive ctl status`` and ``ctl tree``, the web
page, a replay): of the nodes RUNNING at a tick (each with every ancestor running), the deepest,
the first in pre-order among equals, is what the mission waits on. A running node whose child
failed at that tick waits for the child to succeed (``Wait until EKF ok?`` retries ``EKF ok?``):
the child is named, with its own feedback. The time counts from the tick the deepest running node
started running without a break.

It works on :class:`~executive.observers.snapshots.TickState` (a live tree's, or a recording's), so the
replay shows what the run showed. :class:`TreeWatch` follows a running tree for the runtime: it
publishes ``/mission/waiting`` and keeps the latest tree state for ``executive ctl tree``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from py_trees.common import Status

from executive.behaviours.base import FAILURE, RUNNING
from executive.tree.ticks import STATUS_CODES, TickState, describe
from executive.world import blackboard

if TYPE_CHECKING:
    import py_trees

    from executive.mission.model import Mission

MAX_FEEDBACK_CHARS = 60  # the status line stays one line


@dataclass(frozen=True)
class Waiting:
    """The node the mission waits on (``node``, at ``path``), what it says, and the clock time it started running."""

    node: str
    path: str
    feedback: str
    since: float

    def seconds(self, now: float) -> float:
        return max(0.0, now - self.since)

    def to_dict(self, now: float | None) -> dict[str, Any]:
        """Plain values for JSON: node, path, feedback, since (clock time), for_s (seconds running at ``now``; None without it)."""
        seconds = None if now is None else round(self.seconds(now), 1)
        return {"node": self.node, "path": self.path, "feedback": self.feedback, "since": round(self.since, 3), "for_s": seconds}


def waiting_text(waiting: dict[str, Any]) -> str:
    """:meth:`Waiting.to_dict` for a person: ``waiting: EKF ok? (12 s): EKF has no position estimate (flags 0xa7)``."""
    feedback = waiting["feedback"]
    note = feedback if len(feedback) <= MAX_FEEDBACK_CHARS else feedback[: MAX_FEEDBACK_CHARS - 3] + "..."
    seconds = "" if waiting["for_s"] is None else f" ({waiting['for_s']:.0f} s)"
    return f"waiting: {waiting['node']}{seconds}" + (f": {note}" if note else "")


class _Shape:
    """A tree's structure from its description (pre-order: id, name, parent): children, paths; made once per tree."""

    def __init__(self, nodes: list[dict[str, Any]]) -> None:
        self.nodes = nodes
        self.children: dict[int, list[int]] = {n["id"]: [] for n in nodes}
        self.names: dict[int, list[str]] = {}
        self.root: int | None = None
        for node in nodes:  # pre-order: a parent comes before its children
            i, parent = node["id"], node["parent"]
            if parent is None:
                self.root = i
                self.names[i] = [node["name"]]
            else:
                self.children[parent].append(i)
                self.names[i] = [*self.names[parent], node["name"]]

    def deepest_running(self, running: Callable[[int], bool]) -> int | None:
        """Level by level down the running nodes: the first (in pre-order) of the deepest level."""
        level = [self.root] if self.root is not None and running(self.root) else []
        deepest = None
        while level:
            deepest = level[0]
            level = [child for node in level for child in self.children[node] if running(child)]
        return deepest


def deepest_running(state: TickState) -> int | None:
    """The id of the deepest node running at that tick with all its ancestors (first in pre-order among equals); None if none."""
    return _Shape(state.nodes).deepest_running(lambda i: state.status.get(i) == "R")


class WaitingWatch:
    """Follows a tree's states tick by tick, in order: what it waits for at each, and since when."""

    def __init__(self) -> None:
        self._shape: _Shape | None = None
        self._running: int | None = None
        self._since = 0.0
        self._last: Waiting | None = None
        self._named: int | None = None

    def update(self, state: TickState) -> Waiting | None:
        """What the tree waits for at ``state`` (a recording's, or a live tree's :meth:`TreeWatch.view`)."""
        status = state.status
        return self.follow(state.nodes, lambda i: status.get(i) == "R", lambda i: status.get(i) == "F", state.feedback.get, state.t)

    def follow(
        self,
        nodes: list[dict[str, Any]],
        running: Callable[[int], bool],
        failed: Callable[[int], bool],
        feedback: Callable[[int], str | None],
        t: float,
    ) -> Waiting | None:
        """The same, from the tree's description and each node's status and feedback by id (a live tree's, read where it is)."""
        if self._shape is None or self._shape.nodes is not nodes:
            self._shape = _Shape(nodes)
        deepest = self._shape.deepest_running(running)
        if deepest != self._running:
            self._running, self._since = deepest, t
        if deepest is None:
            self._last = None
            return None
        # a running node whose child failed waits for that child to succeed (a wait until, a retry)
        return self._say(next((child for child in self._shape.children[deepest] if failed(child)), deepest), feedback)

    def again(self, feedback: Callable[[int], str | None]) -> Waiting | None:
        """At a tick where every node has the status it had at the last one (a walk would find the same nodes), with the feedback now."""
        if self._running is None:
            return None
        assert self._named is not None
        return self._say(self._named, feedback)

    def _say(self, named: int, feedback: Callable[[int], str | None]) -> Waiting:
        """What the tree waits for: ``named`` (the deepest running node, or its failed child) with its feedback now."""
        assert self._shape is not None
        note = feedback(named) or ""
        last = self._last
        if last is None or (self._named, last.since, last.feedback) != (named, self._since, note):
            names = self._shape.names[named]
            self._named, self._last = named, (last := Waiting(names[-1], "/".join(names), note, self._since))
        return last


class TreeWatch:
    """A run observer: after each tick of the tree, publishes what it waits for (``/mission/waiting``: its one writer) and keeps its statuses.

    :meth:`view` is the tree at its latest tick (the last run's, as it was at its last tick, once
    it is over), for ``executive ctl tree`` and other viewers; None before any mission has run.
    Each tick costs a copy of each node's status and feedback, and a walk down the running nodes when one changed status.
    """

    def __init__(self) -> None:
        self._bb = blackboard.writer("tree watch", ["/mission/waiting"])
        self._description: list[dict[str, Any]] = []
        self._nodes: list[py_trees.behaviour.Behaviour] = []
        self._watch = WaitingWatch()
        self._tick: tuple[int, float] | None = None
        self._statuses: list[Status] = []
        self._feedback: list[str] = []
        self._followed: list[Status] | None = None  # the statuses the waiting watch last followed (None: none yet, for this tree)
        self._live = False

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self._nodes, self._description = describe(root)
        self._watch = WaitingWatch()
        self._followed = None
        self._live = True
        # the new tree as it is until its first tick (a mission replaced while paused waits for the resume): never the old one's statuses
        self._statuses = [n.status for n in self._nodes]
        self._feedback = [n.feedback_message for n in self._nodes]

    def ticked(self, tick: int, now: float) -> None:
        # copied: once the run ends the tree is stopped (every status INVALID), and its last tick is what ``view`` shows
        self._tick = (tick, now)
        statuses = [n.status for n in self._nodes]
        feedback = self._feedback = [n.feedback_message for n in self._nodes]
        if statuses == self._followed:  # most ticks: no node changed status, and the walk down the running nodes is the same
            waiting = self._watch.again(feedback.__getitem__)
        else:
            running, failure = RUNNING, FAILURE
            is_running, has_failed = (lambda i: statuses[i] is running), (lambda i: statuses[i] is failure)
            waiting = self._watch.follow(self._description, is_running, has_failed, feedback.__getitem__, now)
        self._statuses = self._followed = statuses
        if waiting is not self._bb.get("/mission/waiting"):
            self._bb.set("/mission/waiting", waiting)

    def end(self, status: str, reason: str) -> None:
        self._live = False
        self._bb.set("/mission/waiting", None)

    def hold(self, waiting: Waiting | None) -> None:
        """Before the tree first ticks: what holds it back (the distance rule, :mod:`executive.admission.reach`); None once nothing does."""
        shown: Waiting | None = self._bb.get("/mission/waiting")
        if waiting is None:
            if shown is not None:
                self._bb.set("/mission/waiting", None)
        elif shown is None or shown.feedback != waiting.feedback:
            self._bb.set("/mission/waiting", waiting)

    def view(self) -> dict[str, Any] | None:
        """The tree at its latest tick (:meth:`TickState.tree_dict`) with ``live`` (False: the run is over); None if none ran."""
        if self._tick is None:
            return None
        codes = {i: STATUS_CODES.get(s, "-") for i, s in enumerate(self._statuses)}
        state = TickState(*self._tick, self._description, codes, {i: m for i, m in enumerate(self._feedback) if m})
        return {**state.tree_dict(), "live": self._live}
