"""drive: auto on the goto_sample tree: a sample point is a stop of the autopilot's own mission (NAV_LOITER_UNLIM).

Lock-step against the simulated ArduRover boat: the example mission, a dead executive on the way to a
sample point, a pause during a sample.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission, SimulatorOptions
from executive.testing import Lockstep
from executive.world.dialect import mavlink
from executive.world.geo import distance
from tests_support import set_currents

ROOT = Path(__file__).parents[2]
LOITER_UNLIM, WAYPOINT = mavlink.MAV_CMD_NAV_LOITER_UNLIM, mavlink.MAV_CMD_NAV_WAYPOINT


def example(**changes: Any) -> Mission:
    """missions/asv_sampling.yaml (its EKF dropout on the way included) with ``drive: auto``."""
    return load_mission(ROOT / "missions/asv_sampling.yaml").model_copy(update={"drive": "auto", **changes})


class Watch:
    """After each step: waypoints the autopilot holds beyond the item it executes; the speed and distance when each sample began."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission
        self.ahead: list[int] = []
        self.sample_began: dict[int, tuple[float, float]] = {}  # leg -> (distance from the point m, speed m/s)

    def __call__(self, sim: Lockstep) -> None:
        store = sim.autopilot.mission
        if store.running and store.current_seq is not None:
            self.ahead.append(store.count - 1 - store.current_seq)
        sampler = sim.runtime.sampler
        leg = sim.runtime.mission_state.legs.leg_index
        if sampler is not None and sampler.sampling and leg not in self.sample_began:
            wp, vehicle = self.mission.waypoints[leg], sim.autopilot.vehicle
            self.sample_began[leg] = (vehicle.distance_to(wp.lat, wp.lon), vehicle.speed_m_s)


def test_the_example_mission_in_auto_stops_at_each_sample_point_samples_it_once_and_goes_on(lockstep) -> None:
    mission = example()
    sim = lockstep(mission, mission_dir=ROOT / "missions")
    sets, watch = set_currents(sim), Watch(mission)
    sim.observers.append(watch)
    outcome = sim.run_to_end(limit_s=900)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    commands = [item.command for item in sim.autopilot.mission._commands[1:]]
    assert commands == [LOITER_UNLIM if wp.sample else WAYPOINT for wp in mission.waypoints]  # the sample points are stops
    samples = sim.runtime.mission_state.sample_log.taken
    assert sorted(s.leg_index for s in samples) == [1, 3] and all(s.complete for s in samples)
    radius = mission.limits.acceptance_radius_m
    assert all(d <= radius for d, _ in watch.sample_began.values()), watch.sample_began  # there on the position, not on the autopilot's word
    assert all(distance(s.lat, s.lon, mission.waypoints[s.leg_index].lat, mission.waypoints[s.leg_index].lon) <= radius for s in samples)
    assert 3 in sets  # after the sample at item 2 the executive moved the autopilot's mission on to item 3
    assert max(watch.ahead) <= mission.limits.auto_horizon_legs
    assert (sim.autopilot.mode, sim.autopilot.armed) == ("LOITER", True)


def test_a_dead_executive_leaves_the_vehicle_at_the_sample_point_it_was_driving_to(lockstep) -> None:
    """The executive stops ticking on the way to the first sample point: the autopilot stops there (NAV_LOITER_UNLIM never
    completes) although its mission holds the waypoints beyond, and stays there."""
    mission = example(simulator=None)
    sim = lockstep(mission, ekf_ready_after_s=2.0)
    state, inlet, beyond = sim.runtime.mission_state, mission.waypoints[1], mission.waypoints[2]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and sim.autopilot.vehicle.distance_to(inlet.lat, inlet.lon) < 20.0) is None
    assert sim.autopilot.mission.count - 1 >= 3  # the autopilot holds waypoint 3 beyond the sample point
    nearest_beyond = float("inf")
    for _ in range(900):  # 90 s of the vehicle's time, nobody ticking
        sim.step(0.1)
        nearest_beyond = min(nearest_beyond, sim.autopilot.vehicle.distance_to(beyond.lat, beyond.lon))
    vehicle = sim.autopilot.vehicle
    assert vehicle.speed_m_s < 0.2 and vehicle.distance_to(inlet.lat, inlet.lon) < 3.0  # within WP_RADIUS, loitering in AUTO
    assert sim.autopilot.mode == "AUTO" and sim.autopilot.mission.current_seq == 2
    assert nearest_beyond > 25.0  # never drove on toward the next waypoint (30 m on)


def test_a_pause_during_a_sample_cancels_it_and_resume_takes_it_again_then_goes_on_in_auto(lockstep) -> None:
    mission = example(simulator=None)
    sim = lockstep(mission, ekf_ready_after_s=2.0)
    runtime, state = sim.runtime, sim.runtime.mission_state

    def sampling() -> bool:
        return runtime.sampler is not None and runtime.sampler.sampling

    assert sim.run(until=sampling) is None
    assert state.legs.leg_index == 1
    assert runtime.operator.request("pause", source="ctl").ok
    sim.run(until=lambda: state.status is MissionStatus.PAUSED)
    sim.run(until=lambda: sim.autopilot.mode == "LOITER" and not sampling())
    assert not state.sample_log.taken  # the cancelled sample recorded nothing
    sets = set_currents(sim)
    assert runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=900)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sorted(s.leg_index for s in state.sample_log.taken) == [1, 3]  # taken again at the resume, once
    assert sets[:2] == [2, 3]  # resumed at the sample point's item, then on at the next, never back to the first


def test_a_mission_end_that_would_not_stop_the_boat_is_refused_before_arming(lockstep) -> None:
    """The same pre-flight as waypoints' drive: auto: MIS_DONE_BEHAVE 2 (ACRO) would drive on past the horizon."""
    mission = example(simulator=SimulatorOptions(ekf_ready_after_s=2.0, params={"MIS_DONE_BEHAVE": 2.0}))
    sim = lockstep(mission)
    outcome = sim.run_to_end(limit_s=120)
    assert outcome.status is not MissionStatus.COMPLETED and "MIS_DONE_BEHAVE is 2: set it to 0 or 1" in outcome.reason
    assert not sim.autopilot.armed and sim.autopilot.mission.count <= 1  # nothing armed or uploaded
