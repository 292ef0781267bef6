"""The tick side of the live view: each tick, the track kept and, when asked for, an immutable frame handed over.

A :class:`Frame` is everything the page shows at one tick: the tree (its shape, each node's status
and feedback), the blackboard as short text, the status, and the plan (route and track in local
metres). It is built on the tick thread only when the web side has asked for one (:attr:`LiveFeed.wanted`,
a plain flag: no lock, no queue), then published by replacing one reference: the latest wins and
nothing on the tick thread ever waits for a browser.
"""

from __future__ import annotations

import collections
import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import py_trees

from executive.observers.snapshots import show_value
from executive.tree.ticks import describe, status_codes
from executive.world import blackboard, frames

if TYPE_CHECKING:
    from executive.mission.lifecycle import MissionState
    from executive.mission.model import Mission
    from executive.operator import Operator
    from executive.operator.status import StatusSource
    from executive.world.state import GlobalPosition

#: What the page's buttons may ask; everything else stays with ``executive ctl``.
WEB_REQUESTS = ("pause", "resume", "abort")
#: A new track point once the vehicle is this far from the last one, metres.
TRACK_SPACING_M = 0.5
#: Past this many points the track keeps every other one (and starts a new epoch: clients take it whole).
MAX_TRACK_POINTS = 20_000
#: Operator requests answered per tick (a flood is answered over several ticks).
MAX_REQUESTS_PER_TICK = 8

_tree_ids = itertools.count(1)

Reply = Callable[[dict[str, Any]], object]


@dataclass(frozen=True)
class TreeShape:
    """The nodes of a tree in pre-order (id, name, type, parent id: as a snapshot file's ``tree`` line); ``serial`` is new for each tree."""

    serial: int
    nodes: tuple[Mapping[str, Any], ...]

    def to_json(self) -> dict[str, Any]:
        return {"id": self.serial, "nodes": [dict(node) for node in self.nodes]}


@dataclass(frozen=True)
class Plan:
    """The route in local metres (east, north) from ``origin`` (lat, lon), the waypoint headed for (0-based), home."""

    origin: tuple[float, float]
    route: tuple[tuple[float, float], ...]
    current: int
    home: tuple[float, float] | None

    def to_json(self) -> dict[str, Any]:
        return {"origin": self.origin, "route": self.route, "current": self.current, "home": self.home}


@dataclass(frozen=True)
class TrackView:
    """The first ``length`` points (east, north) of an append-only list: later points are appended, never changed."""

    epoch: int
    points: Sequence[tuple[float, float]]
    length: int


@dataclass
class Seen:
    """What one client has been sent already (so each message carries only what is new to it)."""

    tree: int | None = None
    track_epoch: int | None = None
    track_length: int = 0
    blackboard: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Frame:
    """The page's content at one tick; never changed once made (the tick thread makes a new one)."""

    tick: int
    t: float
    tree: TreeShape | None
    statuses: tuple[str, ...]
    feedback: tuple[str, ...]
    blackboard: Mapping[str, str]
    status: Mapping[str, Any] | None
    plan: Plan | None
    track: TrackView | None
    #: Where the vehicle is (east, north), if known.
    here: tuple[float, float] | None = None

    def message(self, seen: Seen) -> dict[str, Any]:
        """This frame as JSON for a client that has ``seen`` what it has (updated): the tree and the track only when new to it."""
        msg: dict[str, Any] = {"tick": self.tick, "t": round(self.t, 2), "s": self.statuses, "f": self.feedback}
        tree = self.tree.serial if self.tree else None
        if tree != seen.tree:
            msg["tree"] = self.tree.to_json() if self.tree else None
            seen.tree = tree
        changed = {k: v for k, v in self.blackboard.items() if seen.blackboard.get(k) != v}
        if changed:
            msg["bb"] = changed
            seen.blackboard.update(changed)
        msg["status"] = dict(self.status) if self.status is not None else None
        msg["plan"] = self.plan.to_json() if self.plan else None
        msg["here"] = self.here
        if self.track is not None:
            restart = self.track.epoch != seen.track_epoch or self.track.length < seen.track_length  # (a replay going back)
            start = 0 if restart else seen.track_length
            msg["track"] = {"restart": restart, "points": list(self.track.points[start : self.track.length])}
            seen.track_epoch, seen.track_length = self.track.epoch, self.track.length
        return msg


def new_tree(nodes: Sequence[Mapping[str, Any]]) -> TreeShape:
    """A tree described as a snapshot file's ``tree`` line, with a serial of its own."""
    return TreeShape(next(_tree_ids), tuple(nodes))


class LiveFeed:
    """The live view's service on the tick thread (a run observer, a reader and a writer of the runtime).

    :meth:`answer` (a reader) applies the requests the page's buttons sent through the operator,
    as the control socket does; :meth:`publish` (a writer, after the tick) keeps the track and,
    when :attr:`wanted` is set, makes a :class:`Frame` and puts it in :attr:`latest`.
    """

    def __init__(self, mission_state: MissionState, status: StatusSource, operator: Operator, clock_now: Callable[[], float]) -> None:
        self._state = mission_state
        self._status = status
        self._operator = operator
        self._now = clock_now
        self._bb = blackboard.reader("live view", ["/vehicle/position"])
        self._tree: TreeShape | None = None
        self._nodes: list[py_trees.behaviour.Behaviour] = []
        self._origin: tuple[float, float] | None = None
        self._plan_of: tuple[Mission | None, int, Plan | None] = (None, -1, None)
        self._track: list[tuple[float, float]] = []
        self._track_epoch = 0
        self._last_position: GlobalPosition | None = None
        self._here: tuple[float, float] | None = None
        self._requests: collections.deque[tuple[str, Reply]] = collections.deque()
        self._ticks = 0
        #: Set by the web side when it wants the next frame; the tick that makes one clears it.
        self.wanted = False
        #: The latest frame (None until one was asked for).
        self.latest: Frame | None = None
        #: Frames made so far.
        self.frames = 0

    # -- the runtime's interfaces --------------------------------------------------------------
    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self._nodes, nodes = describe(root)
        self._tree = new_tree(nodes)

    def ticked(self, tick: int, now: float) -> None:
        pass  # a frame is made after every tick, the tree's or not (publish)

    def end(self, status: str, reason: str) -> None:
        pass  # the ended tree stays on the page, with its last statuses, until the next run's

    def answer(self) -> None:
        """Apply the operator requests the web side passed on (on the tick thread, as ``ctl``'s are)."""
        for _ in range(min(MAX_REQUESTS_PER_TICK, len(self._requests))):
            op, reply = self._requests.popleft()
            if op in WEB_REQUESTS:
                reply(self._operator.request(op, source="web").to_dict())
            else:
                reply({"ok": False, "reason": f"the live view asks only {', '.join(WEB_REQUESTS)}, not {op!r}", "state": str(self._state.status)})

    def publish(self) -> None:
        """After each tick: keep the track; make a frame if one is wanted."""
        self._ticks += 1
        self._follow_vehicle()
        if self.wanted:
            self.wanted = False
            self.latest = self._frame()
            self.frames += 1

    # -- the web side's interface (any thread) --------------------------------------------------
    def ask(self, op: str, reply: Reply) -> None:
        """Pass an operator request to the tick thread; ``reply`` is called there with the reply (it must not block)."""
        self._requests.append((op, reply))

    # -- making frames --------------------------------------------------------------------------
    def _follow_vehicle(self) -> None:
        position: GlobalPosition | None = self._bb.get("/vehicle/position")
        if position is None or position is self._last_position:
            return
        self._last_position = position
        origin = self._origin_for(position)
        north, east = frames.global_to_local(*origin, position.lat, position.lon)
        point = self._here = (round(east, 2), round(north, 2))
        if self._track and (point[0] - self._track[-1][0]) ** 2 + (point[1] - self._track[-1][1]) ** 2 < TRACK_SPACING_M**2:
            return
        if len(self._track) >= MAX_TRACK_POINTS:
            self._track = self._track[::2]  # a new list: frames already made keep theirs
            self._track_epoch += 1
        self._track.append(point)

    def _origin_for(self, position: GlobalPosition | None = None) -> tuple[float, float]:
        """The local frame's origin, fixed once chosen: the mission's home, else its first waypoint, else where the vehicle was first seen."""
        if self._origin is None:
            mission = self._state.mission
            if mission is not None and mission.home is not None:
                self._origin = (mission.home.lat, mission.home.lon)
            elif mission is not None and mission.waypoints:
                self._origin = (mission.waypoints[0].lat, mission.waypoints[0].lon)
            elif position is not None:
                self._origin = (position.lat, position.lon)
        return self._origin or (0.0, 0.0)

    def _plan(self) -> Plan | None:
        mission = self._state.mission
        if mission is None:
            return None
        leg = self._state.legs.leg_index
        cached_mission, cached_leg, plan = self._plan_of
        if mission is cached_mission and leg == cached_leg:
            return plan
        origin = self._origin_for()

        def local(lat: float, lon: float) -> tuple[float, float]:
            north, east = frames.global_to_local(*origin, lat, lon)
            return (round(east, 2), round(north, 2))

        home = local(mission.home.lat, mission.home.lon) if mission.home is not None else None
        plan = Plan(origin, tuple(local(wp.lat, wp.lon) for wp in mission.waypoints), leg, home)
        self._plan_of = (mission, leg, plan)
        return plan

    def _frame(self) -> Frame:
        values = {key: show_value(blackboard.value(key)) for key in blackboard.KEYS}
        return Frame(
            tick=self._ticks,
            t=self._now(),
            tree=self._tree,
            statuses=tuple(status_codes(self._nodes)),
            feedback=tuple(n.feedback_message or "" for n in self._nodes),
            blackboard=values,
            status=self._status.snapshot(),
            plan=self._plan(),
            track=TrackView(self._track_epoch, self._track, len(self._track)),
            here=self._here,
        )
