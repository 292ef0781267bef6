"""A sample is complete only with every sensor the mission names read; another sensor's readings are dropped, said once.

A partial sample (``sampling.require: all``, the default) is recorded as partial, in the mission
state, the journal and the report, naming what is missing; its sample point is not done.
``sampling.require: any``: a reading of any named sensor completes it (the missing ones recorded).
"""

from __future__ import annotations

import json
import logging
import math

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours import NothingToSample, Sample
from executive.cli import main
from executive.instruments.sampler import InstrumentSampler
from executive.mission.lifecycle import MissionState
from executive.mission.loader import load_mission_text
from executive.mission.model import SamplingOptions
from executive.observers.journal import Journal
from executive.testing import Harness, mission_errors
from executive.world.clock import ManualClock
from executive.world.state import GlobalPosition, SampleRead, SampleRecord, SamplerState, SamplerStatus

SENSORS = ["temperature", "conductivity", "ph"]


class QueuedInstrument(InstrumentSampler):
    """An instrument (as a plugin writes one) that gives, at each service, the readings the test queued."""

    def __init__(self, clock: ManualClock, sampling: SamplingOptions) -> None:
        super().__init__(clock, sampling)
        self.queue: list[tuple[str, float]] = []

    @property
    def instrument(self) -> str:
        return "queued"

    def _collect(self, now: float) -> list[SampleRead]:
        taken, self.queue = self.queue, []
        return [SampleRead(name, value, "", now) for name, value in taken]


def status() -> SamplerStatus:
    return py_trees.blackboard.Blackboard.get("/sampler/status")


def sample_of(clock: ManualClock, readings: list[tuple[str, float]], require: str = "all") -> tuple[QueuedInstrument, SamplerStatus]:
    """One 3 s sample during which the instrument gives ``readings`` each second."""
    instrument = QueuedInstrument(clock, SamplingOptions(duration_s=3.0, sensors=SENSORS, require=require))
    instrument.start(1)
    for _ in range(3):
        instrument.queue = list(readings)
        clock.advance(1.0)
        instrument.service()
    return instrument, status()


def test_a_sample_without_a_named_sensor_is_partial_naming_it(clock, vehicle):
    """Before: DONE with one reading of any name."""
    _, ended = sample_of(clock, [("temperature", 17.5), ("conductivity", 44.0)])
    assert ended.state is SamplerState.PARTIAL
    assert ended.missing == ("ph",)
    assert ended.reason == "no reading of ph from queued in 3 s (sampling.require: all)"
    assert len(ended.reads) == 6  # what it read is kept


def test_every_named_sensor_read_is_done(clock, vehicle):
    _, ended = sample_of(clock, [("temperature", 17.5), ("conductivity", 44.0), ("ph", 8.1)])
    assert (ended.state, ended.missing, ended.reason) == (SamplerState.DONE, (), "")


def test_with_require_any_one_sensor_completes_it_and_the_missing_are_named(clock, vehicle):
    _, ended = sample_of(clock, [("ph", 8.1)], require="any")
    assert (ended.state, ended.missing) == (SamplerState.DONE, ("temperature", "conductivity"))


def test_no_reading_at_all_still_fails(clock, vehicle):
    _, ended = sample_of(clock, [])
    assert (ended.state, ended.reason) == (SamplerState.FAILED, "no reading from queued in 3 s")


def test_readings_of_a_sensor_not_named_are_dropped_and_said_once(clock, vehicle, caplog):
    """Before: 'depth', which the mission never named, was recorded with the sample (and counted it done)."""
    caplog.set_level(logging.WARNING, logger="executive")
    instrument, ended = sample_of(clock, [("temperature", 17.5), ("depth", 3.2), ("conductivity", 44.0), ("ph", 8.1)])
    assert ended.state is SamplerState.DONE
    assert {r.sensor for r in ended.reads} == set(SENSORS)
    instrument.start(2)
    instrument.queue = [("depth", 3.3), ("temperature", 17.4)]
    clock.advance(1.0)
    instrument.service()
    assert [r.sensor for r in status().reads] == ["temperature"]
    said = [r.getMessage() for r in caplog.records if "depth" in r.getMessage()]
    assert said == ["sampler: queued gives readings of 'depth', which sampling.sensors does not name (temperature, conductivity, ph): dropped"]


def test_a_sample_of_only_unnamed_sensors_is_no_sample(clock, vehicle):
    _, ended = sample_of(clock, [("depth", 3.2)])
    assert (ended.state, ended.reads) == (SamplerState.FAILED, ())


# -- the Sample action and the mission state: a partial sample is recorded, its point not done ----------------------------------------


@pytest.fixture
def sampling_mission():
    return load_mission_text(
        """\
version: 1
name: two-points
vehicle: boat
tree: goto_sample
sampling: {duration_s: 3, sensors: [temperature, conductivity, ph]}
waypoints:
  - {lat: 47.0, lon: 8.0, sample: true}
  - {lat: 47.0, lon: 8.001, sample: true}
""",
        "two-points.yaml",
    )


def test_the_sample_action_records_a_partial_sample_and_fails_its_point_not_done(sampling_mission, clock):
    node = Sample()
    instrument = QueuedInstrument(clock, sampling_mission.sampling)
    h = Harness.build(sampling_mission, root=node, clock=clock, sampler=instrument)
    state = h.mission_state
    h.writers.append(instrument.service)
    h.vehicle.set(vehicle__position=GlobalPosition(47.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    statuses = []
    for _ in range(40):
        instrument.queue = [("temperature", 17.5), ("conductivity", 44.0)]
        statuses.append(h.tick())
        if statuses[-1] != Status.RUNNING:
            break
    assert statuses[-1] == Status.FAILURE
    assert node.feedback_message == "leg 1/2: partial sample, 62 reads: no reading of ph from queued in 3 s (sampling.require: all)"
    (recorded,) = state.sample_log.taken
    assert (recorded.leg_index, recorded.partial, recorded.missing, len(recorded.reads)) == (0, True, ("ph",), 62)
    assert not state.sample_log.sampled(0)  # its point is not done: a resume samples it again
    assert state.sample_log.work_left(state.mission) == "no sample was recorded at leg 2; the sample of leg 1 is partial (no reading of ph)"
    due = NothingToSample()
    due.tick_once()
    assert (due.status, due.feedback_message) == (Status.FAILURE, "leg 1: sample due")


def test_the_journal_and_the_report_say_a_sample_is_partial_and_what_it_lacked(sampling_mission, tmp_path, clock, capsys):
    db = tmp_path / "journal.db"
    journal = Journal(db, clock)
    state = MissionState()
    journal.attach(state)
    state.upload(sampling_mission)
    journal.begin_run(sampling_mission)
    state.start()
    reads = (SampleRead("temperature", 17.5, "degC", 101.0), SampleRead("conductivity", 44.0, "mS/cm", 101.0))
    state.record_sample(SampleRecord(0, 47.0, 8.0, reads, 100.0, 103.0, "queued", ("ph",), True))
    state.record_sample(SampleRecord(1, 47.0, 8.001, (*reads, SampleRead("ph", 8.1, "pH", 101.0)), 110.0, 113.0, "queued"))
    resume = journal.resume_point(sampling_mission)
    journal.close()
    assert resume is not None
    restored = MissionState()
    restored.upload(sampling_mission)
    restored.start()
    restored.continue_from(resume.leg_index, resume.samples)
    assert (restored.sample_log.sampled(0), restored.sample_log.sampled(1)) == (False, True)  # the partial one is taken again after a crash
    assert main(["report", str(db)]) == 0
    text = capsys.readouterr().out
    partial = "2 reads, mean temperature (degC) 17.50, conductivity (mS/cm) 44.00 (queued): PARTIAL, no reading of ph"
    assert f"waypoint 1 at 47.0000000, 8.0000000: {partial}" in text
    assert "waypoint 2 at 47.0000000, 8.0010000: 3 reads" in text and text.count("PARTIAL") == 1
    assert main(["report", str(db), "--json"]) == 0
    samples = json.loads(capsys.readouterr().out)["samples"]
    assert [(s["waypoint"], s["partial"], s["missing"]) for s in samples] == [(1, True, ["ph"]), (2, False, [])]


def test_a_journal_written_before_partial_samples_is_read(tmp_path, clock, sampling_mission):
    """An older journal's samples table has no missing/partial columns: they are added, its samples complete."""
    import sqlite3

    db = tmp_path / "old.db"
    old = sqlite3.connect(db)
    old.executescript(
        "CREATE TABLE samples (run INTEGER NOT NULL, leg INTEGER NOT NULL, lat REAL, lon REAL, started REAL, finished REAL, "
        "reads TEXT NOT NULL, UNIQUE (run, leg));"
        "INSERT INTO samples VALUES (1, 0, 47.0, 8.0, 1.0, 2.0, '[]');"
    )
    old.close()
    (sample,) = Journal(db, clock).samples(1)
    assert (sample.partial, sample.missing, sample.instrument, sample.complete) == (False, (), "", True)
    assert not math.isnan(sample.lat)


# -- the mission file ----------------------------------------------------------------------------------------------------------------


def test_sampling_require_is_all_by_default_any_on_request_and_nothing_else():
    head = "version: 1\nname: m\nvehicle: boat\ntree: goto_sample\n"
    wp = "waypoints:\n  - {lat: 47.0, lon: 8.0, sample: true}\n"
    assert load_mission_text(head + "sampling: {duration_s: 3}\n" + wp, "m.yaml").sampling.require == "all"
    assert load_mission_text(head + "sampling: {require: any}\n" + wp, "m.yaml").sampling.require == "any"
    errors = mission_errors(head + "sampling: {require: most}\n" + wp)
    assert len(errors) == 1 and errors[0].startswith("m.yaml:5:21: sampling.require: 'most'") and "'all' or 'any'" in errors[0]
