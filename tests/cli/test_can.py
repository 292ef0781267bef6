"""``executive can decode`` on the shipped candump log, and ``executive can monitor`` on a virtual bus in the same process."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from executive.cli import main
from executive.io.can.agilex import RcState, SystemState
from executive.world.state import SwitchPosition

LOG = Path(__file__).parents[1] / "data" / "can" / "bunker_rc.log"
UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def test_decode_the_captured_log(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["can", "decode", str(LOG)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert err == ""
    assert lines[0] == "    0.000000 241 [8] A6 00 00 B0 00 00 00 7E RC SWA=UP SWB=MIDDLE SWC=UP SWD=UP right=(0,0) left=(-80,0) VRA=0 counter=126"
    assert "    0.001000 211 [8] 00 00 01 E6 00 00 00 00 SYSTEM state=NORMAL mode=RC battery=48.6V faults=none (0x0000) counter=0" in lines
    assert "    0.311000 241 [5] A6 00 00 CC 00          [wrong length 5]" in lines  # bytes padded to a column
    assert "    0.051000 251 [8] 00 00 00 0A 00 00 01 2C [id not read by the executive]" in lines
    assert "    0.705000 111 [8] 01 F4 00 00 00 00 00 00 COMMAND linear=+0.500m/s angular=+0.000rad/s" in lines
    assert sum(line.endswith("[RC counter frozen]") for line in lines) == 50
    assert lines[-2:] == [
        "summary: 230 frames (0x111 x20, 0x211 x13, 0x221 x25, 0x241 x126, 0x251 x1, 0x311 x25, 0x421 x20); bad 1; other ids 1; RC counter freezes 1",
        "  RC counter froze at 175 (0xAF): 50 repeated frames, t=0.980000..1.980000 (1.000 s)",
    ]
    assert len(lines) == 230 + 2


def test_decode_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["can", "decode", "--json", str(LOG)]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    first, summary = records[0], records[-1]["summary"]
    assert first["id"] == "0x241" and first["data"] == "A60000B00000007E" and first["valid"] is True
    switches = {"swa": "UP", "swb": "MIDDLE", "swc": "UP", "swd": "UP"}
    assert first["fields"] == switches | {"right_lr": 0, "right_ud": 0, "left_lr": -80, "left_ud": 0, "knob": 0, "counter": 126}
    assert sum(r.get("counter_frozen", False) for r in records[:-1]) == 50
    assert summary["rc_counter_freezes"] == [{"counter": 175, "from_t": 0.98, "to_t": 1.98, "repeats": 50}]
    assert (summary["frames"], summary["bad"], summary["other"], summary["per_id"]["0x241"]) == (230, 1, 1, 126)


def test_decode_a_missing_file_or_an_unknown_format(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["can", "decode", str(tmp_path / "nope.log")]) == 2
    assert capsys.readouterr().err == f"executive: can: {tmp_path / 'nope.log'}: cannot read: No such file or directory\n"
    odd = tmp_path / "capture.foo"
    odd.write_text("x")
    assert main(["can", "decode", str(odd)]) == 2
    assert capsys.readouterr().err == (
        f"executive: can: {odd}: not a CAN log python-can reads by its name or first bytes: give --format asc|blf|candump|csv|trc\n"
    )


def test_decode_a_damaged_log_names_the_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    damaged = tmp_path / "damaged.log"
    damaged.write_text("(1.000000) can0 241#A60000B00000007E\n\ncan0 241 [8] A6 00 00 B0 00 00 00 7F\n", encoding="utf-8")  # candump without -L
    assert main(["can", "decode", str(damaged)]) == 1
    out, err = capsys.readouterr()
    assert out.splitlines()[0].endswith("counter=126")
    assert err.startswith(f"executive: can: {damaged}: 1 line not understood: 3 (line 3: ")


def test_bad_lines_of_a_candump_log_are_skipped_and_counted_the_frames_after_them_decoded_exit_1(tmp_path: Path, capsys) -> None:
    """Issue 43: one garbage line ended the decode (exit 2, python-can's `could not convert string to float`), the frames after it lost."""
    lines = LOG.read_text(encoding="utf-8").splitlines()
    for number in (6, 19, 40):  # 1-based lines of the file
        lines[number - 1] = "garbage (the logger was restarted mid-line)"
    damaged = tmp_path / "damaged.log"
    damaged.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert main(["can", "decode", str(damaged)]) == 1
    out, err = capsys.readouterr()
    assert out.splitlines()[-2].startswith("summary: 227 frames")  # 230 less the 3 lines
    assert err.startswith(f"executive: can: {damaged}: 3 lines not understood: 6, 19, 40 (line 6: ")
    assert main(["can", "decode", "--json", str(damaged)]) == 1
    assert json.loads(capsys.readouterr().out.splitlines()[-1])["summary"]["not_understood"] == [6, 19, 40]


def test_a_candump_log_is_read_whatever_its_name(tmp_path: Path, capsys) -> None:
    renamed = tmp_path / "bus-capture.txt"
    renamed.write_bytes(LOG.read_bytes())
    assert main(["can", "decode", str(renamed)]) == 0  # sniffed: a candump -L line starts with its (timestamp)
    assert capsys.readouterr().out.splitlines()[-2].startswith("summary: 230 frames")
    odd = tmp_path / "capture.foo"
    odd.write_bytes(b"  \n" + LOG.read_bytes())
    assert main(["can", "decode", "--format", "candump", str(odd)]) == 0
    assert capsys.readouterr().out.splitlines()[-2].startswith("summary: 230 frames")


def test_monitor_a_bad_spec_or_a_bus_that_will_not_open(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["can", "monitor", "can0"]) == 2
    assert "expected IFACE:CHANNEL" in capsys.readouterr().err
    assert main(["can", "monitor", "nosuchiface:can0"]) == 2
    assert "unknown CAN interface 'nosuchiface'" in capsys.readouterr().err
    assert main(["can", "monitor", "slcan:/nonexistent/ttyACM9", "--duration", "0.1"]) == 3
    assert capsys.readouterr().err.startswith("executive: can: cannot open CAN bus slcan:/nonexistent/ttyACM9: ")


@pytest.fixture
def base_sending() -> Iterator[tuple[str, threading.Event]]:
    """A simulated base on a virtual channel: 0x241 every 10 ms with its counter frozen at 0x42, 0x211 every 50 ms; stops after 10 s at most."""
    channel = f"test-cli-monitor-{time.monotonic_ns()}"
    stop = threading.Event()

    def send() -> None:
        with can.Bus(interface="virtual", channel=channel) as bus:
            deadline = time.monotonic() + 10.0
            n = 0
            while not stop.is_set() and time.monotonic() < deadline:
                bus.send(RcState(UP, UP, MIDDLE, DOWN, 0, 0, 0, 0, 0, 0x42).encode())
                if n % 5 == 0:
                    bus.send(SystemState(0, 1, 486, 0, n & 0xFF).encode())
                n += 1
                stop.wait(0.01)

    thread = threading.Thread(target=send, daemon=True)
    thread.start()
    yield channel, stop
    stop.set()
    thread.join(timeout=2.0)


def test_monitor_a_live_virtual_bus(base_sending: tuple[str, threading.Event], capsys: pytest.CaptureFixture[str]) -> None:
    channel, _ = base_sending
    started = time.monotonic()
    assert main(["can", "monitor", f"virtual:{channel}", "--duration", "0.5"]) == 0
    assert 0.5 <= time.monotonic() - started < 3.0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    # issue 43: beside another process it printed `0 frames` with no word of why
    assert f"executive: can: virtual:{channel}: python-can's virtual bus lives inside one process" in err
    rc_lines = [line for line in lines if " 241 [8] " in line]
    assert len(rc_lines) >= 5
    assert rc_lines[0].endswith("RC SWA=UP SWB=UP SWC=MIDDLE SWD=DOWN right=(0,0) left=(0,0) VRA=0 counter=66")
    assert all(line.endswith("[RC counter frozen]") for line in rc_lines[1:])
    assert any("SYSTEM state=NORMAL mode=CAN battery=48.6V" in line for line in lines)
    assert lines[-2].startswith("summary: ") and lines[-2].endswith("RC counter freezes 1")
    assert lines[-1].startswith("  RC counter froze at 66 (0x42): ")


def test_monitor_json(base_sending: tuple[str, threading.Event], capsys: pytest.CaptureFixture[str]) -> None:
    channel, _ = base_sending
    assert main(["can", "monitor", f"virtual:{channel}", "--duration", "0.3", "--json"]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    summary = records[-1]["summary"]
    assert summary["rc_frames"] >= 3
    assert summary["frames"] == len(records) - 1
    assert summary["rc_counter_freezes"][0]["counter"] == 0x42
