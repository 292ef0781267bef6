"""Samples in the mission state: recorded once per leg, published, heard by listeners, restored after a restart."""

from __future__ import annotations

import py_trees
import pytest

from executive.mission.events import SampleTaken
from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.world.state import SampleRead, SampleRecord


def sample(leg: int, t: float = 10.0) -> SampleRecord:
    return SampleRecord(leg, 47.0, 8.0, (SampleRead("ph", 8.1, "pH", t),), t - 5.0, t)


def published() -> tuple[SampleRecord, ...]:
    return py_trees.blackboard.Blackboard.get("/mission/samples")


@pytest.fixture
def running(square_mission) -> MissionState:
    state = MissionState()
    state.upload(square_mission)
    state.start()
    return state


def test_recorded_samples_are_published_oldest_first(running):
    assert published() == () and not running.sample_log.sampled(0)
    running.record_sample(sample(1, 10.0))
    running.record_sample(sample(0, 20.0))
    assert published() == (sample(1, 10.0), sample(0, 20.0))
    assert running.sample_log.taken == published()
    assert [running.sample_log.sampled(i) for i in range(4)] == [True, True, False, False]


def test_listeners_hear_each_sample_once(running):
    heard: list[SampleRecord] = []
    running.events.subscribe(SampleTaken, heard.append)
    running.record_sample(sample(2))
    assert heard == [sample(2)]


def test_a_leg_is_never_sampled_twice(running):
    heard: list[SampleRecord] = []
    running.events.subscribe(SampleTaken, heard.append)
    running.record_sample(sample(0, 10.0))
    with pytest.raises(Refused, match="leg 1 is already sampled"):
        running.record_sample(sample(0, 30.0))
    assert published() == (sample(0, 10.0),) and heard == [sample(0, 10.0)]


@pytest.mark.parametrize("leg", [-1, 4])
def test_a_leg_the_mission_does_not_have_is_refused(running, leg):
    with pytest.raises(Refused, match="the mission has 4"):
        running.record_sample(sample(leg))
    assert published() == ()


def test_no_mission_no_sample():
    with pytest.raises(Refused, match="no mission loaded"):
        MissionState().record_sample(sample(0))


def test_samples_survive_pause_resume_and_leg_changes(running):
    running.record_sample(sample(0))
    running.advance_leg()
    running.pause()
    running.resume()
    assert running.sample_log.sampled(0) and published() == (sample(0),)


def test_a_new_run_or_a_new_mission_starts_without_samples(running, square_mission):
    running.record_sample(sample(0))
    running.complete()
    assert running.sample_log.sampled(0)  # the finished run keeps them until the next starts
    running.start()
    assert running.sample_log.taken == () and published() == () and not running.sample_log.sampled(0)
    running.record_sample(sample(0))
    running.abort("test")
    running.upload(square_mission)
    assert published() == ()
    running.start()
    running.record_sample(sample(3))
    running.delete()
    assert published() == () and running.status is MissionStatus.IDLE


def test_a_restarted_executive_restores_samples_without_telling_listeners_and_does_not_resample(square_mission):
    before = MissionState()
    before.upload(square_mission)
    before.start()
    before.record_sample(sample(1))
    journal = before.sample_log.taken  # what a journal kept
    after = MissionState()  # the process restarted
    after.upload(square_mission)
    after.start()
    heard: list[SampleRecord] = []
    after.events.subscribe(SampleTaken, heard.append)
    after.restore_samples(journal)
    assert after.sample_log.sampled(1) and published() == journal and heard == []
    with pytest.raises(Refused):
        after.record_sample(sample(1))
    after.restore_samples(journal)  # restoring twice does not duplicate
    assert published() == journal
