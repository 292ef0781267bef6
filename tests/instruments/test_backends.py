"""The instrument back ends: chosen by the mission, checked where the file says them, plugged in through entry points."""

from __future__ import annotations

import pytest
from pydantic import BaseModel, ConfigDict

from executive import registry
from executive.instruments import backends as instruments
from executive.instruments.sampler import InstrumentError, InstrumentSampler, SimulatedSampler
from executive.mission.lifecycle import MissionState
from executive.mission.loader import load_mission_text
from executive.mission.model import Mission
from executive.operator import Operator
from executive.testing.missions import mission_errors
from executive.world.clock import ManualClock
from executive.world.state import SampleRead

HEAD = "version: 1\nname: s\nvehicle: boat\ntree: goto_sample\n"
POINT = "waypoints:\n  - {lat: 1.0, lon: 1.0, sample: true}\n"


def mission(instrument: str | None) -> Mission:
    sampling = f"sampling:\n  instrument: {instrument}\n" if instrument else ""
    return load_mission_text(HEAD + sampling + POINT, "m.yaml")


class SondeOptions(BaseModel):
    model_config = ConfigDict(strict=True, extra="forbid", frozen=True)
    address: int


class Sonde(InstrumentSampler):
    """A plugin's instrument: one reading of 'depth' per collect."""

    Options = SondeOptions

    @property
    def instrument(self) -> str:
        return f"sonde@{self.instrument_options.address}"

    def _collect(self, now: float) -> list[SampleRead]:
        return [SampleRead("depth", 2.0, "m", now)]


class EntryPoint:
    name, group = "sonde", instruments.GROUP

    def load(self) -> type:
        return Sonde


@pytest.fixture
def sonde_plugin(monkeypatch):
    monkeypatch.setattr(registry, "entry_points", lambda group: [EntryPoint()] if group == instruments.GROUP else [])


@pytest.fixture(autouse=True)
def goto_sample_tree(monkeypatch):
    from executive import trees

    monkeypatch.setattr(trees, "available", lambda: ["goto_sample", "waypoints"])


def test_a_plugin_is_an_instrument_type_checked_and_opened_like_the_built_in_ones(sonde_plugin):
    assert instruments.known() == ["serial", "simulated", "sonde"]
    assert mission_errors(HEAD + "sampling:\n  instrument: {type: sonde, address: x1}\n" + POINT) == [
        "m.yaml:6:38: sampling.instrument.address: 'x1': Input should be a valid integer"
    ]
    sampler = instruments.open_sampler(mission("{type: sonde, address: 3}"), ManualClock(), simulator=False)
    assert isinstance(sampler, Sonde) and sampler.instrument == "sonde@3"


def test_instrument_fields_are_checked_where_the_file_says_them():
    assert mission_errors(HEAD + "sampling:\n  instrument: {type: ctd9}\n" + POINT) == [
        "m.yaml:6:22: sampling.instrument.type: unknown instrument type 'ctd9' (known: serial, simulated)"
    ]
    assert mission_errors(HEAD + "sampling:\n  instrument: {type: serial, bauds: 9600}\n" + POINT) == [
        "m.yaml:6:15: sampling.instrument: port: required field is missing (type serial)",
        "m.yaml:6:37: sampling.instrument.bauds: unknown field (allowed for type serial: type, port, baud, columns, units)",
    ]


def test_the_simulated_instrument_only_with_the_built_in_simulator():
    assert isinstance(instruments.open_sampler(mission(None), ManualClock(), simulator=True), SimulatedSampler)
    with pytest.raises(InstrumentError, match="names no instrument"):
        instruments.open_sampler(mission(None), ManualClock(), simulator=False)
    with pytest.raises(InstrumentError, match="makes readings up"):
        instruments.open_sampler(mission("{type: simulated}"), ManualClock(), simulator=False)
    no_samples = load_mission_text("version: 1\nname: r\nvehicle: rover\nwaypoints:\n  - {lat: 1.0, lon: 1.0}\n", "r.yaml")
    assert instruments.open_sampler(no_samples, ManualClock(), simulator=False) is None


def test_an_upload_whose_samples_could_not_be_real_is_refused():
    state = MissionState()
    operator = Operator(state, "boat", refuse=lambda m: instruments.refusal(m, simulator=False))
    reply = operator.request("upload", filename="s.yaml", text=HEAD + POINT)
    assert not reply.ok and reply.reason.startswith("s.yaml: sampling.instrument: the mission takes samples and names no instrument")
    assert state.mission is None
