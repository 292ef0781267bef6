"""The Sample action tick by tick: it starts the sampler, records the sample once, cancels when interrupted."""

from __future__ import annotations

import math

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours import NothingToSample, RcNotTakingOver, Sample
from executive.instruments.sampler import SimulatedSampler
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission, SamplingOptions
from executive.mission.port import MissionPort
from executive.testing import Harness, port_for
from executive.world import blackboard
from executive.world.state import GlobalPosition, SampleRead, SampleRecord, SamplerState, SamplerStatus

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
OPTIONS = SamplingOptions(duration_s=2.0, rate_hz=1.0, sensors=["ph", "temperature"])
RC_LOW, RC_HIGH = (1500,) * 5 + (1000,), (1500,) * 5 + (1900,)


def at(lat: float, lon: float) -> GlobalPosition:
    return GlobalPosition(lat, lon, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class FakeSampler:
    """A sampler whose status the test writes by hand; it remembers what it was asked."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.tickets = 0
        self._bb = blackboard.writer("fake sampler", ["/sampler/status"])

    def start(self, leg_index: int) -> int:
        self.tickets += 1
        self.calls.append(f"start {leg_index}")
        return self.tickets

    def cancel(self) -> None:
        self.calls.append("cancel")

    def service(self) -> None:
        pass

    def publish(self, ticket: int, state: SamplerState, reads: tuple[SampleRead, ...] = (), reason: str = "", t: float = 0.0) -> None:
        self._bb.set("/sampler/status", SamplerStatus(ticket, state, reads, reason, t))


@pytest.fixture
def running(mission_state, vehicle):
    mission_state.start()
    vehicle.set(vehicle__position=at(mission_state.legs.target.lat, mission_state.legs.target.lon), rc__channels=RC_LOW)
    return mission_state


@pytest.fixture
def make(harness, clock):
    """``make(root, sampler)``: the kit's harness with a sampler, serviced after the tree before the commands are flushed (as the runtime does)."""

    def build(root, sampler=None) -> Harness:
        sampler = sampler or SimulatedSampler(clock, OPTIONS, seed=1)
        h = harness(root, sampler=sampler)
        h.writers.append(sampler.service)
        return h

    return build


def status() -> SamplerStatus | None:
    return py_trees.blackboard.Blackboard.get("/sampler/status")


def test_samples_and_records_the_sample(make, running, vehicle):
    node = Sample()
    h = make(node)
    statuses = [h.tick(0.5) for _ in range(6)]  # started at 100.5; reads at 101.5 and 102.5, done at 102.5, seen at 103.0
    assert statuses == [R, R, R, R, R, S]
    assert h.link.take() == []  # the sampler is not the autopilot
    (recorded,) = running.sample_log.taken
    assert (recorded.leg_index, recorded.started, recorded.finished) == (0, 100.5, 102.5)
    assert (recorded.lat, recorded.lon) == (running.legs.target.lat, running.legs.target.lon)
    assert recorded.reads == status().reads and len(recorded.reads) == 4
    assert py_trees.blackboard.Blackboard.get("/mission/samples") == (recorded,)
    assert node.feedback_message == "leg 1/4: sampled, 4 reads (simulated)"


def test_feedback_while_sampling(make, running):
    node = Sample()
    h = make(node)
    for _ in range(3):
        h.tick(0.5)
    assert node.feedback_message == "leg 1/4: sampling (1 s, 0 reads)"  # the first reads are taken after this tick
    h.tick(0.5)
    assert node.feedback_message == "leg 1/4: sampling (2 s, 2 reads)"


def test_the_position_recorded_is_the_last_seen_while_sampling(make, running, vehicle):
    h = make(Sample())
    h.tick(0.5)
    vehicle.set(vehicle__position=at(47.5, 8.5))
    while h.tick(0.5) == R:
        pass
    assert (running.sample_log.taken[0].lat, running.sample_log.taken[0].lon) == (47.5, 8.5)


def test_no_position_at_all_records_nan(make, running, vehicle):
    vehicle.set(vehicle__position=None)
    h = make(Sample())
    while h.tick(0.5) == R:
        pass
    assert math.isnan(running.sample_log.taken[0].lat) and math.isnan(running.sample_log.taken[0].lon)


def test_a_leg_already_sampled_is_skipped_without_sampling(make, running):
    running.record_sample(SampleRecord(0, 1.0, 2.0, (), 0.0, 1.0))
    sampler = FakeSampler()
    node = Sample()
    h = make(node, sampler)
    assert h.tick(0.5) == S
    assert sampler.calls == [] and len(running.sample_log.taken) == 1
    assert node.feedback_message == "leg 1: already sampled"


def test_sampler_failure_fails_and_records_nothing(make, running):
    sampler = FakeSampler()
    node = Sample()
    h = make(node, sampler)
    assert h.tick(0.5) == R
    sampler.publish(1, SamplerState.FAILED, reason="pump jammed")
    assert h.tick(0.5) == F
    assert node.feedback_message == "leg 1/4: sampler failed: pump jammed"
    assert running.sample_log.taken == () and sampler.calls == ["start 0"]  # a finished request is not cancelled


def test_only_its_own_ticket_counts(make, running):
    sampler = FakeSampler()
    sampler.tickets = 6  # an earlier request's DONE is still on the blackboard
    sampler.publish(6, SamplerState.DONE, (SampleRead("ph", 8.0, "pH", 1.0),))
    h = make(Sample(), sampler)
    assert h.tick(0.5) == R
    sampler.publish(7, SamplerState.SAMPLING)
    assert h.tick(0.5) == R
    sampler.publish(7, SamplerState.DONE, (SampleRead("ph", 8.2, "pH", 101.0),), t=101.0)
    assert h.tick(0.5) == S
    assert [r.value for r in running.sample_log.taken[0].reads] == [8.2] and running.sample_log.taken[0].finished == 101.0


def test_rc_takeover_ends_the_sample_it_is_cancelled_then_retaken_once(make, running, vehicle):
    node = Sample()
    guarded = py_trees.composites.Sequence("Guarded", memory=False, children=[RcNotTakingOver(6, 1700), node])
    h = make(guarded)
    assert [h.tick(0.5), h.tick(0.5), h.tick(0.5)] == [R, R, R]
    first_ticket = status().ticket
    vehicle.set(rc__channels=RC_HIGH)
    assert h.tick(0.5) == F
    assert (status().ticket, status().state, status().reason) == (first_ticket, SamplerState.FAILED, "cancelled")
    assert node.status == Status.INVALID and running.sample_log.taken == ()
    vehicle.set(rc__channels=RC_LOW)
    assert [h.tick(0.5) for _ in range(2)] == [F, F]  # the switch back for 1 s (two ticks of 0.5 s) before the work goes on
    statuses = [h.tick(0.5) for _ in range(6)]
    assert statuses == [R, R, R, R, R, S]
    assert status().ticket == first_ticket + 1 and len(running.sample_log.taken) == 1
    assert h.tick(0.5) == S and len(running.sample_log.taken) == 1  # ticked again: already sampled, not repeated


def test_no_active_leg_fails(make, mission_state):
    sampler = FakeSampler()
    node = Sample()
    assert make(node, sampler).tick(0.5) == F
    assert node.feedback_message == "no active leg" and sampler.calls == []


def test_a_timeout_cancels_the_sampler(make, running):
    sampler = FakeSampler()
    node = Sample(timeout_s=2.0)
    h = make(node, sampler)
    statuses = [h.tick(1.0) for _ in range(4)]  # started at 101: elapsed 0 ... 3 s
    assert statuses == [R, R, R, F]
    assert sampler.calls == ["start 0", "cancel"]
    assert node.feedback_message == "leg 1/4: no sample after 2 s"


def test_setup_needs_a_sampler(clock, commander, mission_state):
    tree = py_trees.trees.BehaviourTree(Sample())
    with pytest.raises(RuntimeError, match="needs sampler"):
        tree.setup(clock=clock, autopilot=port_for(commander), mission_state=MissionPort(mission_state))


@pytest.mark.parametrize(
    ("leg", "recorded", "expected", "feedback"),
    [
        (0, (), S, "leg 1 is not a sample point"),
        (1, (), F, "leg 2: sample due"),
        (1, (1,), S, "leg 2 already sampled"),
        (1, (0,), F, "leg 2: sample due"),  # another leg's sample does not count
        (2, (), S, "no active leg"),
    ],
)
def test_nothing_to_sample_here_unless_a_sample_point_is_not_sampled_yet(leg, recorded, expected, feedback):
    points = [{"lat": 1.0, "lon": 2.0}, {"lat": 1.0, "lon": 2.001, "sample": True}]
    state = MissionState()
    state.upload(Mission.model_validate({"version": 1, "name": "s", "vehicle": "boat", "tree": "goto_sample", "waypoints": points}))
    state.start()
    state.restore_samples(SampleRecord(i, 1.0, 2.0, (), 0.0, 1.0) for i in recorded)
    for _ in range(leg):
        state.advance_leg()
    node = NothingToSample()
    py_trees.trees.BehaviourTree(node).tick()
    assert (node.status, node.feedback_message) == (expected, feedback)
