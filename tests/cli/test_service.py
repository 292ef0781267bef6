"""``executive service install``: the systemd unit, and its ExecStart run for real under a fake service manager (NOTIFY_SOCKET, JOURNAL_STREAM)."""

from __future__ import annotations

import json
import os
import re
import shlex
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from executive.cli import main
from tests_support import mission_text

ROOT = Path(__file__).parents[2]
SHORT = mission_text("short", "{lat: -35.3631710, lon: 149.1652300}", simulator="{ekf_ready_after_s: 1}")


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    path = tmp_path / "short mission.yaml"  # a space: ExecStart quotes it
    path.write_text(SHORT)
    return path


def unit_of(capsys, *argv: str) -> dict[str, list[str]]:
    """``service install --print``'s unit: each directive's values (comments left out)."""
    assert main(["service", "install", *argv, "--print"]) == 0
    unit: dict[str, list[str]] = {}
    for line in capsys.readouterr().out.splitlines():
        if "=" in line and not line.startswith("#"):
            key, value = line.split("=", 1)
            unit.setdefault(key, []).append(value)
    return unit


def exec_start(unit: dict[str, list[str]]) -> list[str]:
    """ExecStart as systemd splits it (our quoting is a subset of the shell's; %% and $$ are systemd's escapes)."""
    return shlex.split(unit["ExecStart"][0].replace("%%", "%").replace("$$", "$"))


def test_the_unit_runs_the_mission_under_notify_with_a_watchdog_restart_and_resume(capsys, mission, tmp_path):
    unit = unit_of(
        capsys, str(mission), "--mavlink", "/dev/ttyACM0,921600", "--user", "pi", "--watchdog-sec", "10", "--run-options=--gcs udpin:0.0.0.0:14551"
    )
    command = exec_start(unit)
    assert command[:5] == [sys.executable, "-m", "executive", "run", str(mission.resolve())]
    options = " ".join(command[5:])
    assert "--journal /var/lib/executive/short-mission.db --resume" in options
    assert "--wait" in command  # at boot the mission waits for a person's start; only an unfinished run goes on by itself
    assert "--mavlink /dev/ttyACM0,921600" in options and options.endswith("--gcs udpin:0.0.0.0:14551")
    expected = {
        "Type": ["notify"], "NotifyAccess": ["main"], "WatchdogSec": ["10"], "Restart": ["on-failure"], "RestartPreventExitStatus": ["1 2"],
        "User": ["pi"], "StandardError": ["journal"], "SyslogIdentifier": ["executive-short-mission"], "WantedBy": ["multi-user.target"],
    }  # fmt: skip
    assert {key: unit.get(key) for key in expected} == expected


def test_start_at_boot_is_asked_for_not_the_default(capsys, mission):
    assert "--wait" not in unit_of(capsys, str(mission), "--start-at-boot")["ExecStart"][0].split()
    assert "--wait" in unit_of(capsys, str(mission))["ExecStart"][0].split()


def test_install_writes_the_unit_it_prints(capsys, mission, tmp_path):
    printed = unit_of(capsys, str(mission), "--name", "survey")
    assert main(["service", "install", str(mission), "--name", "survey", "--unit-dir", str(tmp_path)]) == 0
    written = (tmp_path / "executive-survey.service").read_text()
    assert "systemctl daemon-reload && systemctl enable --now executive-survey" in capsys.readouterr().out
    assert f"ExecStart={printed['ExecStart'][0]}\n" in written and oct((tmp_path / "executive-survey.service").stat().st_mode)[-3:] == "644"


def test_a_bad_mission_or_run_option_writes_nothing(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(SHORT.replace("lat: -35.3631710", "lat: -95.0"))
    assert main(["service", "install", str(bad), "--unit-dir", str(tmp_path)]) == 2
    assert f"{bad}:8:11: waypoints[0].lat:" in capsys.readouterr().err
    good = tmp_path / "good.yaml"
    good.write_text(SHORT)
    assert main(["service", "install", str(good), "--unit-dir", str(tmp_path), "--run-options=--warp 9"]) == 2
    assert "--run-options: not `executive run` options: --warp 9" in capsys.readouterr().err
    assert list(tmp_path.glob("*.service")) == []


def test_exec_start_under_a_fake_service_manager_notifies_ready_watchdog_status_stopping_and_logs_for_the_journal(capsys, mission, tmp_path):
    """The unit's own command, run as systemd would: READY=1 once the autopilot answers, WATCHDOG=1 from the loop, STOPPING=1 at the end."""
    journal = tmp_path / "run.db"
    unit = unit_of(capsys, str(mission), "--journal", str(journal), "--start-at-boot", f"--run-options=--speedup 20 --socket {tmp_path / 'ctl.sock'}")
    manager = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    manager.bind(str(tmp_path / "notify"))
    manager.settimeout(0.2)
    messages: list[tuple[float, str]] = []
    read_end, write_end = os.pipe()  # stderr as the journal's stream: JOURNAL_STREAM names it
    info = os.fstat(write_end)
    env = {**os.environ, "NOTIFY_SOCKET": str(tmp_path / "notify"), "WATCHDOG_USEC": "200000", "JOURNAL_STREAM": f"{info.st_dev}:{info.st_ino}"}
    proc = subprocess.Popen(exec_start(unit), cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=write_end)
    os.close(write_end)

    def listen() -> None:
        while proc.poll() is None or (messages[-1:] and "STOPPING=1" not in messages[-1][1]):
            try:
                messages.append((time.monotonic(), manager.recv(4096).decode()))
            except TimeoutError:
                if proc.poll() is not None:
                    return

    listener = threading.Thread(target=listen, daemon=True)
    listener.start()
    with os.fdopen(read_end) as stderr:
        err = stderr.read()
    assert proc.wait(timeout=300) == 0, err  # bounds a hung run only
    listener.join(timeout=5)
    manager.close()
    kinds = [text.split("=", 1)[0] for _, text in messages]
    assert kinds[0] == "READY" and "autopilot 1/1 heard on udpout:127.0.0.1:" in messages[0][1]
    assert kinds[-1] == "STOPPING" and messages[-1][1] == "STOPPING=1\nSTATUS=mission COMPLETED: every waypoint reached"
    pings = [t for t, text in messages if text == "WATCHDOG=1"]
    assert len(pings) >= 3, messages  # every 0.1 s of wall time while the loop ticks
    assert any(text.startswith("STATUS=RUNNING") for _, text in messages)
    # stderr in the journal: each record with its syslog priority, no timestamp of our own (the journal stamps it)
    assert re.search(r"^<6>mission\.lifecycle: mission READY -> RUNNING", err, re.M), err
    assert not re.search(r"^\d{4}-\d\d-\d\dT", err, re.M)
    assert journal.exists()


def test_a_crash_exits_70_with_its_traceback_so_the_service_restarts_on_it_and_not_on_an_ended_mission(capsys, monkeypatch, mission):
    def broken(*_args, **_kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr("executive.cli.run.build_runtime", broken)
    assert main(["run", str(mission), "--socket", "none"]) == 70
    err = capsys.readouterr().err
    assert "Traceback" in err and "RuntimeError: a bug" in err and "executive: run: crashed (a bug, traceback above): exit 70" in err


def test_record_takes_an_mcap_file_rotated_at_the_size_asked(capsys, mission, tmp_path, monkeypatch):
    """``--record FILE.mcap``: the unit's run records every tick as MCAP; rotated past ``--record-rotate-mb``, each file seekable alone."""
    from mcap.reader import make_reader

    from executive.observers.snapshots import replay
    from tests_support import run_in_lockstep

    record = tmp_path / "run.mcap"
    run = shlex.split(unit_of(capsys, str(mission), "--record", str(record), "--record-rotate-mb", "0.01")["ExecStart"][0])
    assert run[run.index("--snapshots") :][:4] == ["--snapshots", str(record), "--snapshots-rotate-mb", "0.01"]
    assert main(["service", "install", str(mission), "--record-rotate-mb", "1", "--print"]) == 2
    assert "--record-rotate-mb: there is no --record to rotate" in capsys.readouterr().err
    run_in_lockstep(monkeypatch)
    argv = ["run", str(mission), "--snapshots", str(record), "--snapshots-rotate-mb", "0.01", "--speedup", "50", "--socket", "none"]
    assert main(argv) == 0, capsys.readouterr().err
    older, newer = tmp_path / "run.mcap.1", record
    assert older.stat().st_size > 10_485
    for part in (older, newer):
        with part.open("rb") as f:
            summary = make_reader(f).get_summary()
        assert summary is not None and part.stat().st_size < 40_000  # 0.01 MiB: 10 KiB chunks, a file a chunk and its index over

        assert {"/tree", "/tree/tick", "/mission/state"} <= {c.topic for c in summary.channels.values()}
    last = replay(newer)
    assert last.blackboard["/mission/state"] == "'COMPLETED'"
    with older.open("rb") as f:
        ticks = [json.loads(m.data)["tick"] for _, _, m in make_reader(f).iter_messages(topics=["/tree/tick"])]
    # the older file reads alone, from its own keyframe (its first tick) to its last; how many ticks a file holds varies with what
    # the vehicle said when (a lock-step run over UDP): 5 in one run in 16, so not its first + 5
    assert len(ticks) > 1 and replay(older, ticks[-1]).tick == ticks[-1]
