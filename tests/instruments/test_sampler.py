"""The simulated sampler: reads at its rate for its duration, then DONE; cancel; values from the position."""

from __future__ import annotations

import py_trees
import pytest

from executive.behaviours import Sample
from executive.instruments.sampler import SENSOR_MODELS, SimulatedSampler
from executive.mission.model import Mission, SamplingOptions
from executive.runtime.assembly import build_runtime
from executive.testing import ObedientAutopilot
from executive.world.clock import ManualClock
from executive.world.geo import destination
from executive.world.state import GlobalPosition, SamplerState, SamplerStatus

HERE = GlobalPosition(47.397742, 8.545594, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
SENSORS = ["temperature", "conductivity", "ph", "dissolved_oxygen"]


def options(**fields: object) -> SamplingOptions:
    return SamplingOptions.model_validate({"duration_s": 3.0, "rate_hz": 1.0, **fields})


def status() -> SamplerStatus:
    return py_trees.blackboard.Blackboard.get("/sampler/status")


def sampler_at(clock: ManualClock, position: GlobalPosition | None = HERE, seed: int = 0, **fields: object) -> SimulatedSampler:
    return SimulatedSampler(clock, options(**fields), position=lambda: position, seed=seed)


def test_one_read_per_sensor_each_second_then_done(clock):
    sampler = sampler_at(clock)
    assert status() is None
    ticket = sampler.start(2)
    assert status() == SamplerStatus(ticket, SamplerState.SAMPLING, (), "", 100.0, "simulated")
    timeline = []
    for _ in range(7):  # 0.5 ... 3.5 s
        clock.advance(0.5)
        sampler.service()
        timeline.append((status().state, len(status().reads)))
    S, D = SamplerState.SAMPLING, SamplerState.DONE
    assert timeline == [(S, 0), (S, 4), (S, 4), (S, 8), (S, 8), (D, 12), (D, 12)]
    reads = status().reads
    assert [r.sensor for r in reads[:4]] == SENSORS
    assert [r.time for r in reads] == [101.0] * 4 + [102.0] * 4 + [103.0] * 4
    assert status().time == 103.0 and status().ticket == ticket


def test_units_and_plausible_values(clock):
    sampler = sampler_at(clock, sensors=[*SENSORS, "turbidity"])
    sampler.start(0)
    clock.advance(3.0)
    sampler.service()
    by_sensor = {r.sensor: r for r in status().reads}
    assert {name: r.unit for name, r in by_sensor.items()} == {
        "temperature": "degC",
        "conductivity": "mS/cm",
        "ph": "pH",
        "dissolved_oxygen": "mg/L",
        "turbidity": "NTU",
    }
    assert 10.0 < by_sensor["temperature"].value < 25.0
    assert 30.0 < by_sensor["conductivity"].value < 60.0
    assert 7.5 < by_sensor["ph"].value < 8.6
    assert 5.0 < by_sensor["dissolved_oxygen"].value < 10.0
    assert by_sensor["turbidity"].value >= 0.0


def test_a_late_service_takes_every_due_read_at_its_own_time(clock):
    sampler = sampler_at(clock, rate_hz=2.0, duration_s=1.2, sensors=["ph"])
    sampler.start(0)
    clock.advance(1.3)
    sampler.service()
    assert status().state is SamplerState.DONE
    assert [r.time for r in status().reads] == [100.5, 101.0]  # 2 rounds in 1.2 s at 2 Hz; done at 101.2


def test_a_sample_shorter_than_one_period_still_reads_once_at_the_end(clock):
    sampler = sampler_at(clock, rate_hz=0.5, duration_s=1.0, sensors=["ph"])
    sampler.start(0)
    clock.advance(0.9)
    sampler.service()
    assert (status().state, status().reads) == (SamplerState.SAMPLING, ())
    clock.advance(0.1)
    sampler.service()
    assert status().state is SamplerState.DONE and [r.time for r in status().reads] == [pytest.approx(101.0)]


def test_cancel_fails_the_sample_and_keeps_what_was_read(clock):
    sampler = sampler_at(clock)
    ticket = sampler.start(1)
    clock.advance(1.0)
    sampler.service()
    sampler.cancel()
    assert (status().ticket, status().state, status().reason, len(status().reads)) == (ticket, SamplerState.FAILED, "cancelled", 4)
    clock.advance(5.0)
    sampler.service()
    assert status().state is SamplerState.FAILED and len(status().reads) == 4  # nothing more happens


def test_cancel_when_idle_or_done_changes_nothing(clock):
    sampler = sampler_at(clock)
    sampler.cancel()
    assert status() is None
    sampler.start(0)
    clock.advance(3.0)
    sampler.service()
    done = status()
    sampler.cancel()
    assert status() is done


def test_a_new_start_supersedes_the_sample_in_progress(clock):
    sampler = sampler_at(clock)
    first = sampler.start(0)
    clock.advance(1.0)
    sampler.service()
    second = sampler.start(1)
    assert second == first + 1
    assert (status().ticket, status().state, status().reads) == (second, SamplerState.SAMPLING, ())


def test_a_fault_fails_the_sample_with_its_reason(clock):
    sampler = sampler_at(clock)
    sampler.start(0)
    sampler.fail("pump jammed")
    assert (status().state, status().reason) == (SamplerState.FAILED, "pump jammed")


def _values(clock: ManualClock, position: GlobalPosition | None, seed: int) -> list[float]:
    sampler = SimulatedSampler(clock, options(), position=lambda: position, seed=seed)
    sampler.start(0)
    clock.advance(3.0)
    sampler.service()
    return [r.value for r in status().reads]


def test_seeded_values_repeat_and_vary_with_position(clock):
    far = destination(HERE.lat, HERE.lon, 45.0, 150.0)
    elsewhere = GlobalPosition(*far, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    here = _values(clock, HERE, seed=7)
    assert _values(clock, HERE, seed=7) == here
    assert _values(clock, HERE, seed=8) != here
    there = _values(clock, elsewhere, seed=7)
    temperature = SENSOR_MODELS["temperature"]
    # the same noise, another place: the water differs by more than the noise
    assert abs(there[0] - here[0]) > 3 * temperature.noise


def test_reads_the_vehicle_position_from_the_blackboard(clock, vehicle):
    far = destination(HERE.lat, HERE.lon, 90.0, 120.0)
    elsewhere = GlobalPosition(*far, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    vehicle.set(vehicle__position=elsewhere)
    from_blackboard = SimulatedSampler(clock, options(), seed=3)
    from_blackboard.start(0)
    clock.advance(3.0)
    from_blackboard.service()
    read = [r.value for r in status().reads]
    assert read == _values(clock, elsewhere, seed=3)
    assert read != _values(clock, HERE, seed=3)


def test_an_unknown_sensor_reads_noise_without_a_unit(clock):
    sampler = sampler_at(clock, sensors=["nitrate"])
    sampler.start(0)
    clock.advance(3.0)
    sampler.service()
    assert {(r.sensor, r.unit) for r in status().reads} == {("nitrate", "")}


def test_the_runtime_services_the_sampler_of_a_sampling_mission(clock, link, square_mission):
    mission = Mission.model_validate(
        {
            "version": 1,
            "name": "one sample",
            "vehicle": "boat",
            "tree": "goto_sample",
            "sampling": {"duration_s": 1.0, "rate_hz": 2.0},
            "waypoints": [{"lat": HERE.lat, "lon": HERE.lon, "sample": True}],
        }
    )
    runtime = build_runtime(mission, link, clock, root=Sample())
    ObedientAutopilot(link, "boat", start=(HERE.lat, HERE.lon)).beat()  # where the vehicle is: no tree runs before it is known
    runtime.mission_state.start()  # the sampler comes with the mission's tree, when it starts
    assert isinstance(runtime.sampler, SimulatedSampler)
    statuses = []
    for _ in range(7):
        clock.advance(0.25)
        statuses.append(runtime.tick())
    R, S = py_trees.common.Status.RUNNING, py_trees.common.Status.SUCCESS
    assert statuses == [R] * 5 + [S, S]  # started at 100.25; reads at 100.75 and 101.25 (done), seen at 101.5; then already sampled
    (sample,) = runtime.mission_state.sample_log.taken
    assert len(sample.reads) == 8 and sample.finished == 101.25
    assert build_runtime(square_mission, link, clock, root=py_trees.behaviours.Running("idle")).sampler is None  # no sampling section, no sampler
