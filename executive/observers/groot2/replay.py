"""A recorded run (a snapshot file of ``run --snapshots``) served to Groot2 as it ran: its ticks played at their recorded times."""

from __future__ import annotations

import threading
from collections.abc import Callable

from executive.observers.groot2.model import SNAPSHOT_CODES, from_snapshot
from executive.observers.groot2.view import MonitorView
from executive.observers.snapshots import Recording
from executive.tree.ticks import TickState


class ReplayFeed:
    """Plays ``recording`` into ``view``: each recorded tick at its recorded time divided by ``speed``, then holds the last one."""

    def __init__(self, recording: Recording, view: MonitorView, speed: float = 1.0, start: int | None = None) -> None:
        if speed <= 0.0:
            raise ValueError("the speed must be above 0")
        self.recording = recording
        self.view = view
        self.speed = speed
        self.ticks = [tick for tick in recording.ticks if start is None or tick >= start]
        self.position: int | None = None  # the tick shown
        self._tree = -1
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._play, name="groot2 replay", daemon=True)

    def show(self, tick: int, state: TickState | None = None) -> TickState:
        """Show recorded tick ``tick`` (its tree first, if it is another run's); ``state``: that tick's, if already read."""
        tree = self.recording.tree_of(tick)
        if tree != self._tree:
            self._tree = tree
            self.view.show_tree(from_snapshot(self.recording.trees[tree]))
        state = state or self.recording.state_at(tick)
        nodes = self.recording.trees[tree]
        self.view.ticked([SNAPSHOT_CODES.get(state.status.get(n["id"], "-")) for n in nodes], state.t, lambda: dict(state.blackboard))
        self.position = tick
        return state

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)

    def _play(self, wait: Callable[[float], bool] | None = None) -> None:
        """Each tick shown when its recorded time, divided by the speed, has passed since the one before."""
        wait = wait or self._stop.wait
        last_t: float | None = None
        for tick in self.ticks:
            state = self.recording.state_at(tick)
            if last_t is not None and wait(max(0.0, (state.t - last_t) / self.speed)):
                return
            self.show(tick, state)
            last_t = state.t
