"""The progress line: mission state, leg i/n, distance to the next waypoint, mode, armed."""

from __future__ import annotations

from typing import TextIO

from executive import blackboard, geo
from executive.clock import Clock
from executive.mission.model import Waypoint
from executive.state import GlobalPosition


class Progress:
    """Writes the progress line: rewritten in place on a terminal, else a line when something changes.

    On a terminal the line is refreshed every ``period_s`` of clock time; elsewhere (a log file, a
    service journal) a line is written when the state, leg or mode changes, and every
    ``quiet_period_s`` otherwise.
    """

    def __init__(self, stream: TextIO, clock: Clock, *, period_s: float = 0.5, quiet_period_s: float = 10.0) -> None:
        self._stream = stream
        self._clock = clock
        self._tty = stream.isatty()
        self._period_s = period_s if self._tty else quiet_period_s
        self._bb = blackboard.reader("progress", ["/mission/state", "/mission/leg_index", "/mission/leg_count", "/mission/target",
                                                  "/vehicle/position", "/vehicle/mode", "/vehicle/armed"])  # fmt: skip
        self._next = float("-inf")
        self._last_key: tuple[object, ...] = ()

    def line(self) -> str:
        """The current progress line."""
        bb = self._bb
        state, index, count = bb.get("/mission/state"), bb.get("/mission/leg_index"), bb.get("/mission/leg_count")
        target: Waypoint | None = bb.get("/mission/target")
        position: GlobalPosition | None = bb.get("/vehicle/position")
        leg = f"leg {min(index + 1, count)}/{count}"
        to_go = ""
        if target is not None and position is not None:
            distance, bearing = geo.distance_bearing(position.lat, position.lon, target.lat, target.lon)
            to_go = f"  {distance:7.1f} m at {bearing:03.0f}°"
        armed = "armed" if bb.get("/vehicle/armed") else "disarmed"
        return f"[{self._clock.now():8.1f} s] {state:<9} {leg}{to_go}  {bb.get('/vehicle/mode') or '-'} {armed}"

    def update(self, force: bool = False) -> None:
        """Write the line if it is due (or ``force``)."""
        now = self._clock.now()
        bb = self._bb
        key = (bb.get("/mission/state"), bb.get("/mission/leg_index"), bb.get("/vehicle/mode"), bb.get("/vehicle/armed"))
        changed = key != self._last_key
        if not (force or now >= self._next or (changed and not self._tty)):
            return
        self._next = now + self._period_s
        self._last_key = key
        if self._tty:
            self._stream.write("\r\x1b[K" + self.line())
        else:
            self._stream.write(self.line() + "\n")
        self._stream.flush()

    def close(self) -> None:
        """End the in-place line so later output starts on its own line."""
        if self._tty:
            self._stream.write("\n")
            self._stream.flush()
