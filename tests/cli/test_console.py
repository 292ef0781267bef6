"""``executive run`` on a terminal, as a person sees it: timestamped log records, the operator's events by default, the live line apart."""

from __future__ import annotations

import os
import pty
import re
import select
import signal
import subprocess
import time
from pathlib import Path

from tests_support import executive_process

ROOT = Path(__file__).parents[2]
MINIMAL = ROOT / "tests/data/minimal_mission.yaml"  # one waypoint, no auto-arm: it runs, waiting for the operator to arm
RECORD = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z t=\d+\.\d{3} executive (INFO|WARNING|ERROR) [\w.]+: ")
LIVE = "\r\x1b[K["  # the live line drawn (again)


def read_terminal(fd: int, until: callable, timeout_s: float) -> str:
    """What the process wrote to its terminal until ``until(text)`` holds (or the time is up)."""
    text = ""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not until(text):
        ready, _, _ = select.select([fd], [], [], 0.2)
        if ready:
            try:
                text += os.read(fd, 65536).decode("utf-8", "replace")
            except OSError:  # the process has closed the terminal
                break
    return text


def test_on_a_terminal_each_log_record_starts_its_own_line_with_a_utc_timestamp(tmp_path):
    main_fd, terminal = pty.openpty()
    proc = executive_process(
        "run", str(MINIMAL), "--speedup", "40", "--socket", str(tmp_path / "s.sock"), stdout=terminal, stderr=terminal, stdin=subprocess.DEVNULL
    )
    os.close(terminal)
    try:
        # a record written while the live line was showing: the operator's INFO (the autopilot's EKF messages, the state changes)
        text = read_terminal(main_fd, lambda t: LIVE in t and RECORD.search(t, t.index(LIVE)) is not None, timeout_s=300)
    finally:
        proc.send_signal(signal.SIGINT)
        text += read_terminal(main_fd, lambda _t: proc.poll() is not None, timeout_s=30)
        proc.wait(timeout=10)
        os.close(main_fd)
    records = list(RECORD.finditer(text))
    assert records and LIVE in text, text
    after_live = [m for m in records if m.start() > text.index(LIVE)]
    assert after_live, text
    for record in records:
        before = text[: record.start()]
        # its own line: after a newline, or after the live line was erased (never glued to "batt 100%")
        assert before == "" or before.endswith(("\n", "\r\x1b[K")), repr(text[max(0, record.start() - 80) : record.end()])
    # without -v, the operator's events are shown: the mission's state changes
    assert "INFO mission.lifecycle: mission READY -> RUNNING" in text
    assert "ABORTED: stopped: SIGINT" in text
