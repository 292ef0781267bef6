"""From the terminal: `ctl tree` and `ctl status` say what a running mission waits for; SIGTERM ends it ABORTED in the journal."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from executive.cli import main
from executive.io.control import request
from tests_support import executive_process, mission_text

ROOT = Path(__file__).parents[2]
MISSION = mission_text(
    "slow-ekf",
    "{lat: -35.3629906, lon: 149.1652300}",
    simulator="{ekf_ready_after_s: 600}  # the mission waits on the EKF for the whole test",
    limits="{ekf_wait_s: 900}",
)


def ctl(capsys, sock: Path, *args: str) -> tuple[int, str, str]:
    """``executive ctl`` in this process (`ctl tree --watch`, ended by Ctrl-C, runs as a process of its own below): exit code, stdout, stderr."""
    code = main(["ctl", "--socket", str(sock), *args])
    out, err = capsys.readouterr()
    return code, out, err


def wait_for_ekf_wait(sock: Path, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            waiting = request(str(sock), "status", timeout_s=2.0)["status"]["waiting"]
        except OSError:
            waiting = None  # not serving yet
        if waiting is not None and waiting["node"] == "EKF ok?":
            return
        time.sleep(0.05)
    pytest.fail("the mission never waited on the EKF")


def test_ctl_tree_and_status_show_the_wait_and_sigterm_ends_the_run_aborted_in_the_journal(tmp_path, capsys):
    mission, sock, db = tmp_path / "slow_ekf.yaml", tmp_path / "ctl.sock", tmp_path / "journal.db"
    mission.write_text(MISSION)
    run = executive_process("run", str(mission), "--speedup", "2", "--socket", str(sock), "--journal", str(db))
    try:
        wait_for_ekf_wait(sock)
        code, out, err = ctl(capsys, sock, "tree")
        assert code == 0, err
        lines = out.splitlines()
        assert lines[0].startswith("RUNNING ") and "waiting: EKF ok? (" in lines[0], lines[0]
        assert any(line.startswith("            * Wait until EKF ok? -- waiting (") for line in lines), lines
        assert any(line.startswith("                ✕ EKF ok? -- EKF has no position estimate") for line in lines), lines
        assert "            - Arm" in lines  # not reached yet

        _, status, _ = ctl(capsys, sock, "status")
        assert "waiting: EKF ok? (" in status and ": EKF has no position estimate" in status, status

        watch = executive_process("ctl", "--socket", str(sock), "tree", "--watch", "--interval", "0.1", stdout=subprocess.PIPE)
        assert watch.stdout is not None
        prints = 0
        while prints < 2:  # two prints of the tree, a tick or more apart
            line = watch.stdout.readline()
            assert line, watch.stderr.read() if watch.stderr else ""
            prints += line.startswith("tick ")
        watch.send_signal(signal.SIGINT)
        _, err = watch.communicate(timeout=10)
        assert (watch.returncode, err) == (0, "")  # Ctrl-C is how a watch ends

        run.send_signal(signal.SIGTERM)
        _, err = run.communicate(timeout=30)
    finally:
        if run.poll() is None:
            run.kill()
            run.communicate()
    assert run.returncode == 1
    assert "mission 'slow-ekf' ABORTED: stopped: SIGTERM" in err and "Traceback" not in err
    assert main(["report", str(db)]) == 0
    report = capsys.readouterr().out
    assert ": ABORTED stopped: SIGTERM" in report.splitlines()[1] and "UNFINISHED" not in report
