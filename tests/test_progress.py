"""The status for a person and for tools: JSON lines at 2 Hz and on every change."""

from __future__ import annotations

import io
import json

from executive import blackboard
from executive.clock import ManualClock
from executive.progress import Progress


def _set_mode(mode: str) -> None:
    blackboard.writer("test", ["/vehicle/mode"]).set("/vehicle/mode", mode)


def test_json_lines_come_every_half_second_and_at_once_on_a_mode_change() -> None:
    clock, out = ManualClock(), io.StringIO()
    progress = Progress(out, clock)
    _set_mode("AUTO.LOITER")
    progress.update()
    clock.advance(0.1)
    _set_mode("OFFBOARD")  # held for less than a period: a tool must still see it
    progress.update()
    clock.advance(0.1)
    _set_mode("AUTO.TAKEOFF")
    progress.update()
    clock.advance(0.1)
    progress.update()  # nothing changed, not due: no line
    clock.advance(0.4)
    progress.update()  # due: half a second after the last line
    lines = [json.loads(line) for line in out.getvalue().splitlines()]
    assert [(line["t"], line["mode"]) for line in lines] == [(0.0, "AUTO.LOITER"), (0.1, "OFFBOARD"), (0.2, "AUTO.TAKEOFF"), (0.7, "AUTO.TAKEOFF")]
