"""The serial line-protocol instrument, on a pseudo-terminal: what a CTD prints becomes the sample, and nothing else does."""

from __future__ import annotations

import os
import select
from collections.abc import Iterator

import py_trees
import pytest

from executive.instruments.sampler import InstrumentError
from executive.instruments.serial import SerialOptions, SerialSampler
from executive.mission.model import SamplingOptions
from executive.world.clock import ManualClock
from executive.world.state import SamplerState, SamplerStatus


class Ctd:
    """The instrument's end of a pseudo-terminal: what it prints, the sampler reads on ``port``."""

    def __init__(self) -> None:
        self.master, self._slave = os.openpty()
        self.port = os.ttyname(self._slave)

    def print(self, *lines: str) -> None:
        self.write("".join(f"{line}\r\n" for line in lines).encode())

    def write(self, data: bytes) -> None:
        """Send ``data`` and wait until the terminal has passed it on (the kernel does it a moment later)."""
        os.write(self.master, data)
        assert select.select([self._slave], [], [], 2.0)[0], "the pseudo-terminal passed nothing on"

    def close(self) -> None:
        os.close(self.master)
        os.close(self._slave)


@pytest.fixture
def ctd() -> Iterator[Ctd]:
    instrument = Ctd()
    yield instrument
    instrument.close()


def status() -> SamplerStatus:
    return py_trees.blackboard.Blackboard.get("/sampler/status")


def sampler(clock: ManualClock, ctd: Ctd, sensors: tuple[str, ...] = ("temperature", "conductivity", "ph"), **options: object) -> SerialSampler:
    sampling = SamplingOptions(duration_s=3.0, rate_hz=1.0, sensors=list(sensors))
    return SerialSampler(clock, sampling, SerialOptions.model_validate({"port": ctd.port, "baud": 9600, **options}))


def serviced(s: SerialSampler, clock: ManualClock, dt: float) -> SamplerStatus:
    clock.advance(dt)
    s.service()
    return status()


def test_each_line_is_a_reading_of_the_columns_stamped_when_read(clock, ctd):
    s = sampler(clock, ctd)
    ctd.print("17.00,40.00,8.00")  # before the sample: dropped
    s.service()
    ticket = s.start(1)
    ctd.print("# temperature conductivity ph", "17.52, 44.10, 8.05")
    assert serviced(s, clock, 1.0).state is SamplerState.SAMPLING
    ctd.print("17.60;44.20;8.04", "temperature=17.70 ph=8.03")
    serviced(s, clock, 1.0)
    ctd.print("")
    done = serviced(s, clock, 1.0)
    assert (done.ticket, done.state, done.instrument) == (ticket, SamplerState.DONE, f"serial:{ctd.port}")
    assert [(r.sensor, r.value, r.unit, r.time) for r in done.reads] == [
        ("temperature", 17.52, "degC", 101.0), ("conductivity", 44.10, "mS/cm", 101.0), ("ph", 8.05, "pH", 101.0),
        ("temperature", 17.60, "degC", 102.0), ("conductivity", 44.20, "mS/cm", 102.0), ("ph", 8.04, "pH", 102.0),
        ("temperature", 17.70, "degC", 102.0), ("ph", 8.03, "pH", 102.0),
    ]  # fmt: skip
    s.close()


def test_a_line_split_across_reads_and_lines_it_cannot_read(clock, ctd, caplog):
    s = sampler(clock, ctd, sensors=("depth", "temperature"), columns=["depth", "temperature"], units={"depth": "m"})
    s.start(0)
    ctd.write(b"12.5,1")
    serviced(s, clock, 0.5)
    ctd.write(b"8.25\n12.5\nnan,3\n13.0,18.5\n")
    serviced(s, clock, 0.5)
    assert [(r.sensor, r.value, r.unit) for r in status().reads] == [("depth", 12.5, "m"), ("temperature", 18.25, "degC"),
                                                                     ("depth", 13.0, "m"), ("temperature", 18.5, "degC")]  # fmt: skip
    assert s.bad_lines == 2
    assert "line '12.5' not understood (1 values for 2 columns (depth, temperature))" in caplog.text
    s.close()


def test_a_sensor_the_mission_does_not_name_is_dropped_and_said_once(clock, ctd, caplog):
    """Before: ``salinity=31.2`` (not in sampling.sensors) was recorded, and a line of it alone counted as the sample."""
    s = sampler(clock, ctd)
    s.start(0)
    ctd.print("temperature=17.5 salinity=31.2 conductivity=44.1 ph=8.05", "salinity=31.3")
    serviced(s, clock, 1.0)
    ctd.print("salinity=31.4, temperature=17.6")
    serviced(s, clock, 1.0)
    assert [r.sensor for r in status().reads] == ["temperature", "conductivity", "ph", "temperature"]
    assert caplog.text.count("'salinity'") == 1
    assert (
        f"serial:{ctd.port} gives readings of 'salinity', which sampling.sensors does not name (temperature, conductivity, ph): dropped"
        in caplog.text
    )
    done = serviced(s, clock, 1.0)
    assert (done.state, done.missing) == (SamplerState.DONE, ())
    s.close()


def test_a_column_that_never_reads_makes_the_sample_partial(clock, ctd):
    s = sampler(clock, ctd)
    s.start(0)
    ctd.print("temperature=17.5 conductivity=44.1")
    ended = serviced(s, clock, 3.0)
    assert (ended.state, ended.missing) == (SamplerState.PARTIAL, ("ph",))
    assert ended.reason == f"no reading of ph from serial:{ctd.port} in 3 s (sampling.require: all)"
    s.close()


def test_a_silent_instrument_fails_the_sample_it_does_not_invent_one(clock, ctd):
    s = sampler(clock, ctd)
    s.start(0)
    failed = serviced(s, clock, 3.0)
    assert (failed.state, failed.reads) == (SamplerState.FAILED, ())
    assert failed.reason == f"no reading from serial:{ctd.port} in 3 s"
    s.close()


def test_a_cancel_ends_the_sample_and_later_lines_are_dropped(clock, ctd):
    s = sampler(clock, ctd)
    s.start(0)
    s.cancel()
    ctd.print("17.5,44.1,8.05")
    assert serviced(s, clock, 1.0).state is SamplerState.FAILED and status().reason == "cancelled"
    s.start(0)
    assert serviced(s, clock, 0.1).reads == ()  # the line printed while idle is not this sample's
    s.close()


def test_a_port_that_cannot_be_opened_is_an_instrument_error(clock, tmp_path):
    with pytest.raises(InstrumentError, match=r"serial instrument: cannot open .*/nothing"):
        SerialSampler(clock, SamplingOptions(), SerialOptions(port=str(tmp_path / "nothing")))
