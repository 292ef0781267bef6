"""The lock-step simulation: whole missions on one manual clock, deterministic, with faults, a CAN base, a camera and operator events."""

from __future__ import annotations

import itertools
import threading
import time
from pathlib import Path

import py_trees
import pytest

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.sensing import heading
from executive.sim.faults import LinkLoss
from executive.testing import Lockstep, Overload, VehicleTimeLimit

MISSIONS = Path(__file__).parents[2] / "missions"


def first_two_legs() -> Mission:
    """rover_square's first two legs (north 30 m, then east 30 m): a whole mission with a turn, in half the square's vehicle time."""
    square = load_mission(MISSIONS / "rover_square.yaml")
    return square.model_copy(update={"waypoints": square.waypoints[:2]})


@pytest.mark.parametrize("as_bytes", [False, True])
def test_the_same_mission_twice_is_the_same_run_tick_for_tick(lockstep, as_bytes: bool) -> None:
    mission = first_two_legs()
    runs = []
    for _ in range(2):
        sim = lockstep(mission, as_bytes=as_bytes, ekf_ready_after_s=2.0)  # the 40 s EKF wait adds nothing to compare
        outcome = sim.run_to_end(limit_s=300)
        v = sim.autopilot.vehicle
        runs.append((outcome, sim.clock.now(), v.lat, v.lon, sim.autopilot.mode))
    assert runs[0][0].status is MissionStatus.COMPLETED
    assert runs[0] == runs[1]


def test_a_run_starts_once_the_heading_filter_can_judge_so_its_first_verdict_is_on_the_same_tick_in_every_process(lockstep, monkeypatch) -> None:
    # filterpy loads in a thread and is ready at a moment of wall time: as in a fresh process, not yet here, and slow
    monkeypatch.setattr(heading, "_filterpy_ready", threading.Event())
    monkeypatch.setattr(heading, "_load_kalman_filter_module", lambda: time.sleep(0.3))
    sim = lockstep(load_mission(MISSIONS / "rover_square.yaml"), ekf_ready_after_s=2.0)
    assert heading._filterpy_ready.is_set()
    assert sim.clock.now() == 0.0


def test_an_overloaded_run_is_late_and_skips_ticks_as_the_pacer_counts_them_and_one_seed_is_one_run(lockstep) -> None:
    mission = load_mission(MISSIONS / "rover_square.yaml")
    runs = []
    for seed in (3, 3, 4):
        sim = lockstep(mission, ekf_ready_after_s=2.0, overload=Overload(seed=seed))
        stepped: list[float] = []
        sim.observers.append(lambda s, stepped=stepped: stepped.append(s.clock.now()))
        outcome = sim.run_to_end(limit_s=300)
        pacer = sim.runtime.pacer
        assert outcome.status is MissionStatus.COMPLETED
        assert pacer.late > pacer.ticks / 5 and pacer.skipped > 0 and pacer.worst_late_s > 0.5
        steps = [b - a for a, b in itertools.pairwise(stepped)]
        assert max(steps) > 0.3  # the world stepped coarsely, not once a tick
        runs.append((outcome, sim.clock.now(), pacer.summary(), sim.autopilot.vehicle.lat, sim.autopilot.vehicle.lon))
    assert runs[0] == runs[1]
    assert runs[0] != runs[2]


def test_a_link_loss_from_a_fault_object_cuts_both_ways_on_the_vehicle_clock(lockstep) -> None:
    mission = first_two_legs()  # at 60 s, 20 s after the EKF is ready, the rover drives its second leg
    sim = lockstep(mission, events=[LinkLoss(kind="link_loss", at_s=60.0, for_s=8.0)])
    heard: list[tuple[float, int]] = []
    sim.observers.append(lambda s: heard.append((s.clock.now(), len(s.link.incoming))))
    assert sim.run(limit_s=300, until=lambda: sim.clock.now() >= 66.0) is None  # stopped at a moment of interest
    assert all(n == 0 for t, n in heard if 60.1 <= t <= 66.0)  # nothing arrived while the link was down
    assert py_trees.blackboard.Blackboard.get("/link/up") is False  # and the runtime noticed
    outcome = sim.run(limit_s=300)  # and on to the end
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED


def test_a_mission_that_cannot_end_hits_the_vehicle_time_limit(lockstep) -> None:
    mission = load_mission(MISSIONS / "rover_square.yaml")
    sim = lockstep(mission, ekf_ready_after_s=10_000.0)  # the EKF never gets ready within the limit
    with pytest.raises(VehicleTimeLimit, match="vehicle time"):
        sim.run(limit_s=30.0)
    assert sim.clock.now() == pytest.approx(30.0, abs=0.2)


def test_the_bunker_is_driven_over_its_can_base_and_plays_the_missions_event_file(lockstep) -> None:
    mission = load_mission(MISSIONS / "ugv_rc_route.yaml")
    sim = lockstep(mission, mission_dir=MISSIONS, can=True)
    outcome = sim.run_to_end(limit_s=600)
    assert outcome.status is MissionStatus.COMPLETED
    assert sim.base is not None and sim.autopilot.vehicle.base_command is not None  # the tracks obeyed the base's motion commands
    assert sim.runtime.mission_state.legs.route is not None and len(sim.runtime.mission_state.legs.route.waypoints) >= 2  # recorded by RC switches


#: The example missions whose tree has no scenario of its own (tests/trees/ runs asv_sampling, asv_sampling_yaml_tree, auv_survey,
#: ugv_rc_route and vtol_transit).
WITHOUT_A_SCENARIO = ["boat_survey.yaml", "rover_square.yaml"]


def test_every_example_mission_is_run_by_a_scenario() -> None:
    assert {p.name for p in MISSIONS.glob("*.yaml")} == {
        *WITHOUT_A_SCENARIO,
        "asv_sampling.yaml",
        "asv_sampling_yaml_tree.yaml",
        "auv_survey.yaml",
        "ugv_rc_route.yaml",
        "vtol_transit.yaml",
    }


@pytest.mark.parametrize("name", WITHOUT_A_SCENARIO)
def test_every_example_mission_completes_and_takes_every_sample(lockstep, name: str) -> None:
    """As issue 2 checks it with ``executive run``: the example missions complete (their own event file played)."""
    path = MISSIONS / name
    mission = load_mission(path)
    sim = lockstep(mission, mission_dir=MISSIONS)
    outcome = sim.run_to_end(limit_s=900)
    assert (outcome.status, outcome.reason) == (MissionStatus.COMPLETED, "every waypoint reached")
    assert len(sim.runtime.mission_state.sample_log.taken) == sum(wp.sample for wp in mission.waypoints)


def test_an_operator_pause_at_a_vehicle_time_holds_the_mission_until_resumed(lockstep) -> None:
    mission = first_two_legs()  # at 60 s, 20 s after the EKF is ready, the rover drives its second leg
    sim = lockstep(mission)
    sim.at(60.0, lambda s: s.runtime.operator.request("pause", source="test"))
    assert sim.run(limit_s=300, until=lambda: sim.clock.now() >= 70.0) is None
    assert sim.status is MissionStatus.PAUSED
    sim.runtime.operator.request("resume", source="test")
    assert sim.run_to_end(limit_s=300).status is MissionStatus.COMPLETED


def test_the_camera_s_scans_reach_the_autopilot(lockstep) -> None:
    mission = load_mission(MISSIONS / "rover_square.yaml")
    sim = lockstep(mission, obstacles=True)
    sent: list[str] = []
    original = sim.autopilot.handle
    sim.autopilot.handle = lambda msg: (sent.append(msg.get_type()), original(msg))[1]  # type: ignore[method-assign]
    for t in (45.0, 46.0, 47.0):
        sim.at(t, lambda s: s.send_obstacles({"distances_cm": [412, 398, None, 1500], "increment_deg": 1.5}))
    assert sim.run(limit_s=300, until=lambda: sim.clock.now() >= 50.0) is None
    assert sent.count("OBSTACLE_DISTANCE") == 3


def test_a_lockstep_is_usable_as_a_context_manager() -> None:
    mission = load_mission(MISSIONS / "rover_square.yaml")
    with Lockstep(mission, can=False) as sim:
        sim.connect()
        assert sim.runtime.link.reader.autopilot is not None


def test_a_simulated_px4_answers_the_runtime(lockstep) -> None:
    mission = load_mission(MISSIONS / "vtol_transit.yaml")
    sim = lockstep(mission, autopilot="px4")
    sim.connect()
    assert type(sim.autopilot).__module__.startswith("executive.sim.px4.")
    assert py_trees.blackboard.Blackboard.get("/link/up") is True
