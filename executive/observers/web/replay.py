"""``executive replay SNAPSHOTS --web PORT``: a recording on the live view's page, a tick slider to move through it.

A snapshot file holds the tree and the blackboard (as text), not the status or the route: the status
bar is read from the blackboard's values, the track from ``/vehicle/position`` and the route from
the targets the mission headed for (``/mission/target``), in the order they came.
"""

from __future__ import annotations

import bisect
import re
from typing import Any

from executive.observers.snapshots import Recording, literal, shown_fields
from executive.observers.web.feed import Frame, Plan, TrackView, new_tree
from executive.world import frames

_LAT_LON = re.compile(r"\blat=(-?[0-9.]+(?:e-?[0-9]+)?), lon=(-?[0-9.]+(?:e-?[0-9]+)?)")
_BATTERY = re.compile(r"\bremaining_pct=(-?[0-9]+)")


def _lat_lon(text: str | None) -> tuple[float, float] | None:
    found = _LAT_LON.search(text or "")
    return (float(found[1]), float(found[2])) if found else None


def _waiting(text: str | None, t: float) -> dict[str, Any] | None:
    """``/mission/waiting`` as recorded (a ``Waiting(...)`` repr) as the live status has it: node, path, feedback, since, for_s."""
    if not text or not text.startswith("Waiting("):
        return None
    fields = shown_fields(text)
    since = fields.get("since")
    for_s = round(t - since, 1) if isinstance(since, int | float) else None
    return {"node": fields.get("node"), "path": fields.get("path"), "feedback": fields.get("feedback") or "", "since": since, "for_s": for_s}


def status_of(values: dict[str, str], t: float) -> dict[str, Any]:
    """The status bar's fields, read from a recorded blackboard at clock time ``t``."""
    leg, legs = literal(values.get("/mission/leg_index")) or 0, literal(values.get("/mission/leg_count")) or 0
    battery = _BATTERY.search(values.get("/vehicle/battery") or "")
    return {
        "state": literal(values.get("/mission/state")),
        "reason": literal(values.get("/mission/reason")),
        "leg": min(leg + 1, legs),
        "legs": legs,
        "mode": literal(values.get("/vehicle/mode")),
        "armed": bool(literal(values.get("/vehicle/armed"))),
        "link_up": bool(literal(values.get("/link/up"))),
        "battery_pct": int(battery[1]) if battery else None,
        "battery_v": None,
        "yaw_deg": None,
        "waiting": _waiting(values.get("/mission/waiting"), t),
    }


class ReplaySource:
    """The frames of a recording, each made when the page asks for its tick."""

    kind = "replay"

    def __init__(self, path: str) -> None:
        self._origin: tuple[float, float] | None = None
        self._track: list[tuple[float, float]] = []
        self._track_ticks: list[int] = []
        self._targets: list[tuple[float, float]] = []
        self._target_ticks: list[int] = []
        self._last_target: str | None = None
        self.recording = Recording(path, watch=self._watch)
        self._trees = [new_tree(nodes) for nodes in self.recording.trees]

    def _local(self, point: tuple[float, float]) -> tuple[float, float]:
        if self._origin is None:
            self._origin = point
        north, east = frames.global_to_local(*self._origin, *point)
        return (round(east, 2), round(north, 2))

    def _watch(self, line: dict[str, Any]) -> None:
        """Gather the track and the targets as the recording is indexed."""
        values = line.get("bb", {})
        if (where := _lat_lon(values.get("/vehicle/position"))) is not None:
            point = self._local(where)
            if not self._track or point != self._track[-1]:
                self._track.append(point)
                self._track_ticks.append(line["tick"])
        target = values.get("/mission/target")
        if target is not None and target != self._last_target:
            self._last_target = target
            if (where := _lat_lon(target)) is not None and (not self._targets or self._local(where) != self._targets[-1]):
                self._targets.append(self._local(where))
                self._target_ticks.append(line["tick"])

    def hello(self) -> dict[str, Any]:
        return {"first": self.recording.first, "last": self.recording.last, "requests": []}

    def frame(self, tick: int | None) -> Frame | None:
        tick = self.recording.last if tick is None else self.recording.nearest(tick)
        state = self.recording.state_at(tick)
        count = len(state.nodes)
        seen = bisect.bisect_right(self._track_ticks, tick)
        targets = bisect.bisect_right(self._target_ticks, tick)
        plan = Plan(self._origin, tuple(self._targets), max(targets - 1, 0), None) if self._origin and self._targets else None
        return Frame(
            tick=state.tick,
            t=state.t,
            tree=self._trees[self.recording.tree_of(tick)],
            statuses=tuple(state.status.get(i, "-") for i in range(count)),
            feedback=tuple(state.feedback.get(i, "") for i in range(count)),
            blackboard=dict(state.blackboard),
            status=status_of(state.blackboard, state.t),
            plan=plan,
            track=TrackView(0, self._track, seen),
            here=self._track[seen - 1] if seen else None,
        )
