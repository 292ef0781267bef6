"""Instruments are real or absent: a sampling mission against a real vehicle needs one; each sample says which took it."""

from __future__ import annotations

import contextlib
import os
import threading
import tty
from pathlib import Path

import pytest

from executive.cli import main

ROOT = Path(__file__).parents[2]
ASV = (ROOT / "missions" / "asv_sampling.yaml").read_text()
#: ...nor an EKF taking 40 s to converge: two sample points 10 m apart near the ASV's home, for a run from the command line.
NEAR_SAMPLE_POINTS = """\
simulator: {ekf_ready_after_s: 2}
waypoints:
  - {lat: -35.2959100, lon: 149.1130000, name: inlet, sample: true}
  - {lat: -35.2959100, lon: 149.1131100, name: outlet, sample: true}
"""


def asv(tmp_path: Path, instrument: str | None = None) -> Path:
    """The ASV mission without its simulator events, with ``instrument`` (a YAML flow mapping) as sampling.instrument."""
    text = ASV.replace("simulator:\n  events: events/asv_ekf_dropout.yaml\n", "")
    if instrument is not None:
        text = text.replace("  hold_mode: LOITER ", f"  instrument: {instrument}\n  hold_mode: LOITER ")
    path = tmp_path / "asv.yaml"
    path.write_text(text)
    return path


def test_a_sampling_mission_against_a_real_vehicle_needs_an_instrument(tmp_path, capsys):
    """Issue 13: against --mavlink the executive invented 40 reads of temperature; now it refuses before anything moves."""
    assert main(["run", str(asv(tmp_path)), "--mavlink", "udpout:127.0.0.1:9", "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "sampling.instrument: the mission takes samples and names no instrument" in err
    assert "autopilot" not in err  # refused before connecting: nothing was sent


def test_the_simulated_instrument_is_refused_against_a_real_vehicle(tmp_path, capsys):
    assert main(["run", str(asv(tmp_path, "{type: simulated}")), "--mavlink", "udpout:127.0.0.1:9", "--socket", "none"]) == 2
    assert "'simulated' makes readings up: only with the built-in simulator" in capsys.readouterr().err


def test_an_instrument_that_is_not_there_is_no_vehicle(tmp_path, capsys):
    mission = asv(tmp_path, f"{{type: serial, port: {tmp_path / 'ttyNONE'}}}")
    assert main(["run", str(mission), "--mavlink", "udpout:127.0.0.1:9", "--socket", "none"]) == 3
    assert f"serial instrument: cannot open {tmp_path / 'ttyNONE'}" in capsys.readouterr().err


@pytest.fixture
def ctd():
    """A CTD on a pseudo-terminal printing ``17.25,44.5,8.1,7.75`` (the mission's four sensors) every 10 ms, until the test ends."""
    master, slave = os.openpty()
    tty.setraw(slave)  # no echo: what the CTD prints is only read
    os.set_blocking(master, False)
    stop = threading.Event()

    def talk() -> None:
        while not stop.wait(0.01):
            with contextlib.suppress(BlockingIOError):  # nobody reading yet: the line is lost, as on a real wire
                os.write(master, b"17.25,44.5,8.1,7.75\r\n")

    thread = threading.Thread(target=talk, daemon=True)
    thread.start()
    yield os.ttyname(slave)
    stop.set()
    thread.join()
    os.close(master)
    os.close(slave)


def test_samples_from_a_serial_ctd_are_recorded_with_the_instrument(tmp_path, ctd, capsys):
    db = tmp_path / "journal.db"
    mission = asv(tmp_path, f"{{type: serial, port: {ctd}}}")
    text = mission.read_text()
    mission.write_text(text[: text.index("waypoints:\n")] + NEAR_SAMPLE_POINTS)  # what it shows needs no more of the lake...
    code = main(["run", str(mission), "--speedup", "20", "--socket", "none", "--journal", str(db)])  # in this process: nothing needs another
    err = capsys.readouterr().err
    assert code == 0, err
    assert "2 samples recorded" in err
    assert main(["report", str(db)]) == 0
    report = capsys.readouterr().out
    samples = [line for line in report.splitlines() if line.startswith("  waypoint")]
    assert len(samples) == 2, report
    for line in samples:
        assert line.endswith(f"mean temperature (degC) 17.25, conductivity (mS/cm) 44.50, ph (pH) 8.10, dissolved_oxygen (mg/L) 7.75 (serial:{ctd})")
