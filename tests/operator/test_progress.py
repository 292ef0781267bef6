"""The status for a person and for tools: JSON lines at 2 Hz and on every change."""

from __future__ import annotations

import io
import json
import re

from executive.operator.progress import Progress
from executive.world import blackboard
from executive.world.clock import ManualClock


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


def test_each_change_of_state_leg_or_armed_also_brings_a_line_at_once() -> None:
    clock, out = ManualClock(), io.StringIO()
    progress = Progress(out, clock)
    writer = blackboard.writer("test", ["/mission/state", "/mission/leg_index", "/mission/leg_count", "/vehicle/armed"])
    writer.set("/mission/leg_count", 4)
    progress.update()
    for key, value in (("/vehicle/armed", True), ("/mission/state", "RUNNING"), ("/mission/leg_index", 1)):
        clock.advance(0.1)
        writer.set(key, value)
        progress.update()
    clock.advance(0.1)
    progress.update()  # nothing changed, not due
    lines = [json.loads(line) for line in out.getvalue().splitlines()]
    assert [(line["t"], line["armed"], line["state"], line["leg"]) for line in lines][1:] == [
        (0.1, True, lines[0]["state"], lines[0]["leg"]),
        (0.2, True, "RUNNING", lines[0]["leg"]),
        (0.3, True, "RUNNING", 2),
    ]


class Terminal(io.StringIO):
    """What a terminal receives, stdout and stderr alike."""

    def isatty(self) -> bool:
        return True


def test_a_log_record_from_another_thread_is_written_apart_from_the_live_line() -> None:
    import logging
    import threading

    from executive.operator.logs import LiveLineHandler, UtcFormatter

    clock, terminal = ManualClock(), Terminal()
    progress = Progress(terminal, clock)
    handler = LiveLineHandler(terminal)
    handler.setFormatter(UtcFormatter())
    handler.live = progress
    logger = logging.getLogger("executive.test_progress")
    logger.addHandler(handler)
    try:
        _set_mode("HOLD")
        progress.update()
        line = terminal.getvalue().removeprefix("\r\x1b[K")
        assert line.startswith("[     0.0 s] ") and "HOLD" in line
        worker = threading.Thread(target=logger.warning, args=("link lost",))
        worker.start()
        worker.join()
    finally:
        logger.removeHandler(handler)
    after = terminal.getvalue().removeprefix("\r\x1b[K" + line)
    # the line erased, the record from the line's start, the line drawn again
    record = r"\r\x1b\[K\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z t=\d+\.\d{3} executive WARNING test_progress: link lost\n"
    assert re.fullmatch(record + re.escape(line), after), repr(after)


def _long_status() -> None:
    """A status whose full line is far wider than 80 columns: every field present, a long wait."""
    from executive.mission.model import Waypoint
    from executive.tree.waiting import Waiting
    from executive.world.state import Battery, GlobalPosition

    here = GlobalPosition(-35.3632, 149.1652, 0.0, 0.0, 0.0, 0.0, None, 0.0)
    values = {
        "/mission/state": "RUNNING", "/mission/leg_index": 1, "/mission/leg_count": 8, "/mission/target": Waypoint(lat=-35.3620, lon=149.1650),
        "/vehicle/position": here, "/vehicle/armed": True, "/vehicle/mode": "GUIDED", "/vehicle/battery": Battery(12.1, 3.0, 87, 0.0),
        "/mission/waiting": Waiting("Go to waypoint", "Mission/Legs/Go to waypoint", "leg 2/8: 133.9 m at 352°", 0.0),
    }  # fmt: skip
    writer = blackboard.writer("test", list(values))
    for key, value in values.items():
        writer.set(key, value)


def test_the_live_line_fits_an_80_column_terminal_leaving_out_the_least_important_fields(monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    clock, terminal = ManualClock(), Terminal()
    progress = Progress(terminal, clock)
    _long_status()
    progress.update()
    full = progress._source.snapshot()
    from executive.operator.status import status_line

    assert len(f"[     0.0 s] {status_line(full)}") > 80  # what the line would be, unfitted
    shown = terminal.getvalue().removeprefix("\r\x1b[K")
    assert len(shown) < 80, shown  # a wrapped line leaves a stale row at each redraw (\x1b[K clears one row)
    assert shown.startswith("[     0.0 s] RUNNING   leg 2/8") and "GUIDED armed" in shown, shown
    monkeypatch.setenv("COLUMNS", "200")  # the window widened: the next line has everything
    clock.advance(0.5)
    progress.update()
    assert terminal.getvalue().rsplit("\r\x1b[K", 1)[1] == f"[     0.5 s] {status_line(progress._source.snapshot())}"


def test_fields_are_left_out_from_the_least_important_and_the_first_is_cut_only_when_alone_too_wide() -> None:
    from executive.operator.status import fit

    fields = ["RUNNING   leg 2/8", "GUIDED armed", "batt 87%", "waiting: Go to waypoint (14 s): leg 2/8: 123.4 m at 090°"]
    assert fit(fields, 41) == "RUNNING   leg 2/8  GUIDED armed  batt 87%"
    assert fit(fields, 31) == "RUNNING   leg 2/8  GUIDED armed"
    assert fit(fields, 10) == "RUNNING   "
    assert fit(fields) == "  ".join(fields)


def test_off_a_terminal_every_status_is_one_json_line_whatever_its_length(monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    clock, out = ManualClock(), io.StringIO()
    progress = Progress(out, clock)
    _long_status()
    progress.update()
    clock.advance(0.5)
    progress.update()
    lines = out.getvalue().split("\n")
    assert lines[-1] == "" and "\r" not in out.getvalue() and "\x1b" not in out.getvalue()
    assert [json.loads(line)["leg"] for line in lines[:-1]] == [2, 2]
