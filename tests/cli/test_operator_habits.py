"""Operator tools meet a person's habits (issue 17): each rough edge, found by running the command, tested from the command line.

Everything here fails (or ends) early: no mission runs for long.
"""

from __future__ import annotations

import io
import json
import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import py_trees
import pytest

from executive.cli import main
from executive.io.control import ControlServer, default_socket_path, request
from executive.mission.lifecycle import MissionState
from executive.observers.journal import Journal
from executive.observers.snapshots import SnapshotRecorder
from executive.operator.progress import Progress
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink
from tests_support import executive_process

ROOT = Path(__file__).parents[2]
SQUARE = str(ROOT / "missions" / "rover_square.yaml")
CAN_LOG = ROOT / "tests" / "data" / "can" / "bunker_rc.log"


def free_port() -> int:
    """A TCP port nothing listens on (bound by the OS, then let go)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def free_udp_port() -> int:
    """A UDP port nothing listens on (bound by the OS, then let go)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def heartbeat_back(gcs: socket.socket, port: int, timeout_s: float = 120.0) -> bool:
    """A ground station's HEARTBEAT from ``gcs`` to an executive listening on ``port`` (again, until it is up), until one of its own
    comes back; False if none in ``timeout_s`` (wall time bounds only a hung process)."""
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    hello = mav.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0).pack(mav)
    parser = mavlink.MAVLink(None)
    deadline = time.monotonic() + timeout_s
    gcs.settimeout(0.2)  # how often it speaks again while the executive starts, not a margin: it waits for the answer
    while time.monotonic() < deadline:
        gcs.sendto(hello, ("127.0.0.1", port))
        try:
            datagram = gcs.recv(2048)
        except (TimeoutError, ConnectionRefusedError):  # not listening yet (the port refused the last one), or not answered yet
            continue
        if any(msg.get_type() == "HEARTBEAT" for msg in parser.parse_buffer(datagram) or []):
            return True
    return False


# -- --mavlink / --gcs -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("option", "url", "why"),
    [
        ("--mavlink", "udp:127.0.0.1:14550x", "port '14550x' is not a number 0-65535"),
        ("--mavlink", "foo://bar", "unknown kind of endpoint 'foo'; use udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT"),
        ("--mavlink", "/dev/ttyACM0,fast", "baud rate 'fast' is not a positive whole number"),
        ("--mavlink", "tcp:5760", "tcp needs HOST:PORT, e.g. tcp:127.0.0.1:14550"),
        ("--gcs", "udpout:127.0.0.1:0", "port '0' is not a number 1-65535"),
    ],
)
def test_a_malformed_endpoint_says_what_is_wrong_and_exits_2(option, url, why, capsys):
    assert main(["run", SQUARE, option, url, "--socket", "none"]) == 2
    assert capsys.readouterr().err.startswith(f"executive: run: {option} {url}: {why}")


def test_an_endpoint_that_cannot_be_reached_says_so_and_exits_3(capsys):
    assert main(["run", SQUARE, "--mavlink", "/dev/ttyNOPE,57600", "--socket", "none"]) == 3
    err = capsys.readouterr().err
    assert err == "executive: run: --mavlink /dev/ttyNOPE,57600: cannot open the serial device /dev/ttyNOPE: No such file or directory\n"
    assert main(["run", SQUARE, "--mavlink", "udpin:127.0.0.1:0", "--gcs", "udpin:192.0.2.1:14551", "--socket", "none"]) == 3
    assert "--gcs udpin:192.0.2.1:14551: cannot listen on 192.0.2.1:14551: Cannot assign requested address" in capsys.readouterr().err


def test_nothing_listening_on_a_tcp_endpoint_is_exit_3_without_a_traceback(capsys):
    port = free_port()
    code = main(["run", SQUARE, "--mavlink", f"tcp:127.0.0.1:{port}", "--socket", "none"])  # in this process: exit code and output checked
    out, err = capsys.readouterr()
    assert code == 3, err
    where = f"127.0.0.1:{port}"
    assert err.endswith(f"--mavlink tcp:{where}: cannot connect to {where}: Connection refused (is the autopilot, SITL or router listening there?)\n")
    assert "Traceback" not in err and "sleeping" not in out  # pymavlink's retries printed on stdout


# -- the control socket ------------------------------------------------------------------------------


def test_an_explicit_socket_another_executive_serves_is_an_error(tmp_path, capsys):
    path = tmp_path / "ctl.sock"
    other = ControlServer(str(path), lambda _request: {"ok": True})
    try:
        assert main(["run", SQUARE, "--socket", str(path), "--mavlink", "udpin:127.0.0.1:0"]) == 2
    finally:
        other.close()
    assert capsys.readouterr().err == f"executive: run: --socket {path}: another executive is listening there (stop it, or choose another path)\n"


def test_a_busy_default_socket_makes_the_second_executive_take_its_own_and_say_which(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    first = ControlServer(default_socket_path(), lambda _request: {"ok": True, "first": True})
    second = executive_process("run", SQUARE, "--wait", "--speedup", "5", stdout=subprocess.PIPE, env={"XDG_RUNTIME_DIR": str(tmp_path)})
    try:
        own = default_socket_path(second.pid)
        assert second.stderr is not None
        for line in second.stderr:
            if "another executive serves" in line:
                break
        assert line.rstrip().endswith(
            f"executive: run: another executive serves {tmp_path}/executive.sock; this one listens on {own} (executive ctl --socket {own} ...)"
        )
        deadline = time.monotonic() + 30
        while not os.path.exists(own) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert request(own, "status")["state"] == "READY"  # the second executive, waiting for `ctl start`
    finally:
        second.send_signal(signal.SIGTERM)
        second.communicate(timeout=30)
        first.close()


# -- Ctrl-C, closed pipes ------------------------------------------------------------------------------


def test_ctrl_c_while_waiting_for_the_first_heartbeat_exits_130_with_a_message():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcs:
        gcs.bind(("127.0.0.1", 0))
        port = free_udp_port()
        run = executive_process("run", SQUARE, "--mavlink", f"udpin:127.0.0.1:{port}", "--socket", "none", "-v", stdout=subprocess.PIPE)
        try:
            # its HEARTBEAT comes back to whoever spoke to it only from the wait for the autopilot: then Ctrl-C lands in that wait
            assert heartbeat_back(gcs, port), "the executive never announced itself while waiting for the autopilot"
            run.send_signal(signal.SIGINT)
            _, err = run.communicate(timeout=30)
        finally:
            run.kill()
            run.communicate()
    assert run.returncode == 130
    _, loaded, waited = err.partition("IDLE -> READY")  # the last word before it listens for the autopilot; then only this
    assert (
        loaded
        and waited.split("\n", 1)[1]
        == f"executive: run: interrupted while waiting for the autopilot's first heartbeat on udpin:127.0.0.1:{port}: nothing was commanded\n"
    )


@pytest.fixture
def long_journal(tmp_path, square_mission) -> Path:
    """A journal whose report runs to far more than a pipe holds (64 KiB)."""
    path = tmp_path / "j.db"
    journal = Journal(path, ManualClock())
    journal.begin_run(square_mission)
    for n in range(40):
        journal.event("note", f"event {n}: " + "a long event " * 300)
    journal.close()
    return path


@pytest.fixture
def long_can_log(tmp_path) -> Path:
    path = tmp_path / "long.log"
    path.write_text(CAN_LOG.read_text() * 20)
    return path


@pytest.mark.parametrize(("command", "long_file"), [("report", "long_journal"), ("report --json", "long_journal"), ("can decode", "long_can_log")])
def test_a_reader_that_stops_reading_ends_the_output_quietly(command, long_file, request):
    proc = executive_process(*command.split(), str(request.getfixturevalue(long_file)), stdout=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.read(200)  # `| head`: a little, then the pipe is closed
    proc.stdout.close()
    err = proc.stderr.read()
    assert (proc.wait(timeout=30), err) == (0, "")


def test_a_closed_status_output_ends_the_status_never_the_mission(caplog):
    read_end, write_end = os.pipe()
    os.close(read_end)  # `executive run ... | head`: head has gone
    with io.FileIO(write_end, "w") as pipe:
        progress = Progress(io.TextIOWrapper(pipe), ManualClock())
        progress.update()  # the first write fails, and is the last: no exception reaches the loop
        progress.update(force=True)
    warnings = [r.getMessage() for r in caplog.records if r.name == "executive.progress"]
    assert warnings == ["the status output was closed ([Errno 32] Broken pipe): the mission goes on without it; `executive ctl status` still answers"]


# -- replay ----------------------------------------------------------------------------------------------


def test_replay_of_a_journal_says_it_is_one_and_what_reads_it(long_journal, capsys):
    assert main(["replay", str(long_journal)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{long_journal}:1:1: (snapshot): this is a journal (SQLite), not a snapshot file: `executive report {long_journal}`")


def test_replay_of_a_tick_not_recorded_states_the_ticks_there_are(tmp_path, capsys):
    path = tmp_path / "run.snap"
    root = py_trees.behaviours.Running("Wait")
    recorder = SnapshotRecorder(path)
    recorder.attach(root)
    for tick in (3, 4, 5, 9, 10):  # two runs: the executive served between them
        root.tick_once()
        recorder.record(tick, tick / 10)
    recorder.close()
    assert main(["replay", str(path), "--tick", "999999"]) == 2
    assert capsys.readouterr().err == f"executive: replay: {path}: tick 999999 is not in the recording; it holds ticks 3-5, 9-10\n"
    assert main(["replay", str(path), "--tick", "7"]) == 2


# -- report ------------------------------------------------------------------------------------------------


def test_report_numbers_waypoints_from_1_and_says_when_every_one_was_reached(tmp_path, square_mission, capsys):
    journal = Journal(tmp_path / "j.db", ManualClock())
    state = MissionState()
    journal.attach(state)
    state.upload(square_mission)
    journal.begin_run(square_mission)
    state.start()
    for _ in range(4):
        journal.observe_leg(state, None, None)
        state.advance_leg()
    journal.observe_leg(state, None, None)
    journal.close()
    assert main(["report", str(tmp_path / "j.db")]) == 0
    legs = capsys.readouterr().out.split("legs:\n")[1].split("samples")[0].splitlines()
    assert [line.split("] ")[1] for line in legs] == [
        "heading for waypoint 1 of 4",
        "heading for waypoint 2 of 4",
        "heading for waypoint 3 of 4",
        "heading for waypoint 4 of 4",
        "every waypoint reached (4 of 4)",
    ]
    assert main(["report", "--json", str(tmp_path / "j.db")]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [(leg["waypoint"], leg["waypoints"]) for leg in report["legs"]] == [(1, 4), (2, 4), (3, 4), (4, 4), (None, 4)]
