"""The journal, the snapshots and the tlog on a disk that fills up: the mission goes on, the loss is said once, nothing written is damaged.

Tested on real write failures, not mocked ones: a file-size limit (RLIMIT_FSIZE: the kernel refuses
the write past it with EFBIG, as a full disk does with ENOSPC) on an ``executive run`` of its own,
and, where the machine lets us mount one, a tiny tmpfs that fills up and then has room again.
"""

from __future__ import annotations

import contextlib
import json
import resource
import sqlite3
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.cli import main
from executive.io.storage import Storage
from executive.mission.lifecycle import MissionState
from executive.observers.journal import RETRY_EVERY_S, Journal
from executive.world.clock import ManualClock
from executive.world.dialect import mavutil
from tests_support import executive_process, line_mission, mission_text

ROOT = Path(__file__).parents[2]


def test_a_run_on_a_disk_that_fills_up_completes_and_keeps_what_was_written(tmp_path: Path) -> None:
    """Every file may grow to 64 kB: the journal, snapshots and tlog all hit it mid-run; the mission COMPLETES all the same."""
    mission = tmp_path / "m.yaml"
    legs = ("{lat: -35.36308, lon: 149.16523}", "{lat: -35.36308, lon: 149.16545}", "{lat: -35.36326, lon: 149.16545}")
    mission.write_text(mission_text("full-disk", *legs))

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (64_000, 64_000))  # Python ignores SIGXFSZ: a write past it fails with EFBIG

    files = ["--journal", "j.db", "--snapshots", "s.snap", "--tlog", "t.tlog"]
    run = executive_process(
        "run", str(mission), "--speedup", "20", "--socket", "none", *files, cwd=tmp_path, env={"PYTHONPATH": str(ROOT)}, preexec_fn=limit
    )  # preexec_fn: a limit of the child's own
    stderr = run.communicate(timeout=120)[1]
    assert run.returncode == 0, stderr
    assert stderr.splitlines()[-1].startswith("executive: mission 'full-disk' COMPLETED: every waypoint reached")
    for said in ("journal cannot write: progress will not survive a restart", "snapshots cannot write:", "tlog cannot write:"):
        assert stderr.count(said) == 1, (said, stderr)  # said once, however many writes failed
    assert "Traceback" not in stderr
    db = sqlite3.connect(tmp_path / "j.db")
    assert db.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    assert db.execute("SELECT after FROM transitions WHERE run = 1").fetchone() == ("RUNNING",)  # what was written before is kept
    lines = (tmp_path / "s.snap").read_text().split("\n")
    assert lines[-1] == "" and all(json.loads(line) for line in lines[:-1])  # the last record whole: no half line at the end
    tlog = mavutil.mavlink_connection(str(tmp_path / "t.tlog"), dialect="ardupilotmega")
    kinds = [msg.get_type() for msg in iter(tlog.recv_msg, None)]
    assert kinds and "BAD_DATA" not in kinds
    data = (tmp_path / "t.tlog").read_bytes()
    assert len(data) <= 64_000 and tlog_record_ends(data)[-1] == len(data)  # whole records only: the file ends at one's end


def tlog_record_ends(data: bytes) -> list[int]:
    """Where each .tlog record ends: 8 bytes of time, then a MAVLink v2 (0xFD) or v1 (0xFE) frame of the length it declares."""
    ends, at = [0], 0
    while at + 10 <= len(data):
        start, length = at + 8, data[at + 9]
        if data[start] == 0xFD:
            at = start + 12 + length + (13 if data[start + 2] & 0x01 else 0)  # header 10, checksum 2, signature 13 if signed
        elif data[start] == 0xFE:
            at = start + 8 + length  # header 6, checksum 2
        else:
            break
        ends.append(at)
    return ends


@pytest.fixture
def tiny_disk(tmp_path: Path) -> Iterator[Path]:
    """A 256 kB tmpfs (root only: skipped where mounting is not allowed), unmounted after."""
    mount = tmp_path / "disk"
    mount.mkdir()
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(mount)], capture_output=True, check=False)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {made.stderr.decode().strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def fill(disk: Path) -> Path:
    """Fill the disk to its last byte with one file; returns it."""
    filler = disk / "filler"
    with filler.open("wb", buffering=0) as f, contextlib.suppress(OSError):
        while True:
            f.write(b"\0" * 4096)
    return filler


def test_a_journal_on_a_full_disk_retries_and_writes_everything_once_there_is_room(tiny_disk: Path) -> None:
    clock, storage, heard = ManualClock(), Storage(), []
    storage.listeners.append(heard.append)
    journal = Journal(tiny_disk / "j.db", clock, storage)
    state = MissionState()
    journal.attach(state)
    state.upload(line_mission("sd-card"))
    journal.begin_run(state.mission)  # type: ignore[arg-type]
    state.start()
    journal.observe_leg(state, None, None)
    filler = fill(tiny_disk)
    for n in range(40):  # more than the WAL's last free page takes
        journal.event("test", f"event {n} " + "x" * 200)
    assert heard == ["journal cannot write: progress will not survive a restart"]  # said once
    assert "journal" in storage.lost
    state.advance_leg()
    journal.observe_leg(state, None, None)  # the mission goes on: nothing raised
    filler.unlink()  # room again (the operator cleared the card, a log rotated)
    clock.advance(RETRY_EVERY_S)
    journal.observe_leg(state, None, None)  # the retry, on the tick after it is due
    assert storage.lost == {}
    journal.close()
    db = sqlite3.connect(tiny_disk / "j.db")
    assert db.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    texts = [row[0] for row in db.execute("SELECT text FROM events WHERE kind = 'test' ORDER BY rowid")]
    assert texts == [f"event {n} " + "x" * 200 for n in range(40)]  # every one, in order, none twice
    assert [row[0] for row in db.execute("SELECT leg FROM legs ORDER BY rowid")] == [0, 1]


def test_a_journal_that_cannot_be_created_is_refused_before_the_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mission = tmp_path / "m.yaml"
    mission.write_text(mission_text("nowhere", "{lat: -35.36308, lon: 149.16523}"))
    assert main(["run", str(mission), "--journal", str(tmp_path / "no" / "such" / "dir" / "j.db"), "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert f"--journal {tmp_path}/no/such/dir/j.db: cannot be created or written: unable to open database file" in err
    assert "simulated rover" not in err  # refused before the vehicle (here the simulator) was opened


def test_a_loss_another_thread_meets_is_told_on_the_ticking_thread_in_its_order() -> None:
    """The MCAP encoder thread writes the snapshot file: its loss reaches the blackboard and the listeners (the ground station)
    only when the ticking thread delivers it, and a loss then a write again both arrive."""
    from executive.world import blackboard

    blackboard.reset()
    storage = Storage()
    heard: list[tuple[str, int]] = []
    storage.listeners.append(lambda text: heard.append((text, threading.get_ident())))
    lost = blackboard.reader("test storage", ["/runtime/storage_lost"])

    def encoder_thread(*calls: tuple[str, ...]) -> None:
        def run() -> None:
            for kind, what in calls:
                if kind == "failed":
                    storage.failed(what, "ticks are not recorded for replay", OSError(28, "No space left"))
                else:
                    storage.wrote(what)

        thread = threading.Thread(target=run)
        thread.start()
        thread.join()

    encoder_thread(("failed", "snapshots"))
    assert heard == [] and lost.get("/runtime/storage_lost") is None  # nothing told from the encoder thread
    storage.deliver()
    assert heard == [("snapshots cannot write: ticks are not recorded for replay", threading.get_ident())]
    assert "snapshots cannot write" in lost.get("/runtime/storage_lost")
    encoder_thread(*[("wrote", "snapshots")] * 500)  # writes again: one pending note, however many writes
    assert len(storage._from_threads) == 1
    storage.deliver()
    assert lost.get("/runtime/storage_lost") is None
    encoder_thread(("failed", "snapshots"), ("wrote", "snapshots"))  # lost and back between two ticks: both told, in order
    storage.deliver()
    assert lost.get("/runtime/storage_lost") is None and "snapshots" not in storage.lost
