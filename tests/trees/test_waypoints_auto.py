"""drive: auto on the waypoints tree: the simulated ArduRover's AUTO drives, the executive supervises, the autopilot holds only the horizon.

Lock-step (manual clock) against the simulated ArduRover, rover and motorboat.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pytest

from benchmarks.efficiency import MISSIONS, time_auto, time_supervised_auto, with_sitl_parameters
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.mission.resume import ResumePoint
from executive.runtime.loop import RunOutcome
from executive.testing import Lockstep
from tests_support import LinkCut, SharedEfficiencyRuns, line_mission, set_currents

#: drive: auto against the autopilot's own AUTO over the whole route (issue 32's target on the real firmware).
AUTO_RATIO = 1.02


def auto_mission(name: str, **limits: Any) -> Mission:
    """An example mission with ``drive: auto`` and SITL's parameters (``limits`` on top of its own)."""
    mission = with_sitl_parameters(load_mission(MISSIONS / f"{name}.yaml"))
    return mission.model_copy(update={"drive": "auto", "limits": mission.limits.model_copy(update=limits)})


class HorizonWatch:
    """After each step: how many route waypoints the autopilot holds beyond the one it drives to, and where the vehicle is."""

    def __init__(self) -> None:
        self.ahead: list[int] = []
        self.modes: list[str] = []

    def __call__(self, sim: Lockstep) -> None:
        store = sim.autopilot.mission
        if store.running and store.current_seq is not None:
            self.ahead.append(store.count - 1 - store.current_seq)
        self.modes.append(sim.autopilot.mode)


@pytest.mark.xdist_group("leg_efficiency")
def test_a_route_the_horizon_holds_whole_is_driven_as_fast_as_the_autopilots_own_auto(efficiency_runs: SharedEfficiencyRuns) -> None:
    mission = auto_mission("rover_square", auto_horizon_legs=3)  # 4 waypoints: all held from the start, nothing appended
    supervised, own = efficiency_runs.timed(time_supervised_auto, mission), efficiency_runs.timed(time_auto, mission)  # the benchmark's
    assert supervised.seconds / own.seconds <= AUTO_RATIO, (supervised, own)


def test_each_burst_of_appends_restarts_the_leg_as_the_real_firmware_does(caplog: pytest.LogCaptureFixture) -> None:
    """ArduRover restarts the current waypoint at every write to its mission in AUTO (tests/sim/ardupilot/test_supervised_against_ardurover.py):
    boat_survey's horizon of 3 is filled twice, two waypoints each time (4 restarts in 2 bursts), ~2.3 s a burst: ~1.06x the
    whole-route AUTO, as on the real firmware (80.4 s against 75.6 s)."""
    mission = auto_mission("boat_survey")
    supervised, own = time_supervised_auto(mission), time_auto(mission)
    assert [r.message for r in caplog.records].count("autopilot: Auto mission changed, restarted command") == 4
    assert 1.03 < supervised.seconds / own.seconds < 1.09, (supervised, own)


@dataclass
class HorizonRun:
    """boat_survey driven to its end in drive: auto with a horizon: its outcome, what the autopilot held after each step, the
    waypoints appended on each leg (leg number -> items), the items held after the last step and after the run."""

    mission: Mission
    outcome: RunOutcome
    watch: HorizonWatch
    grown: dict[int, list[int]]
    held: int
    items_at_end: int


@pytest.fixture(scope="module")
def boat_survey_in_auto() -> Callable[[int], HorizonRun]:
    """``boat_survey_in_auto(horizon)``: each horizon's run once per module (the tests asking for the same horizon watch the
    same lock-step run, so they run on one xdist worker: ``xdist_group("boat_survey_in_auto")``)."""
    runs: dict[int, HorizonRun] = {}

    def run(horizon: int) -> HorizonRun:
        if horizon not in runs:
            mission = auto_mission("boat_survey", auto_horizon_legs=horizon)
            with Lockstep(mission, ekf_ready_after_s=2.0) as sim:
                state = sim.runtime.mission_state
                watch = HorizonWatch()
                grown: dict[int, list[int]] = {}
                held = [0]

                def appended(s: Lockstep) -> None:
                    count = s.autopilot.mission.count - 1
                    if s.autopilot.mission.running and count > held[0]:
                        grown.setdefault(state.legs.leg_index + 1, []).extend(range(held[0] + 1, count + 1))
                    held[0] = count

                sim.observers += [watch, appended]
                outcome = sim.run_to_end()
                runs[horizon] = HorizonRun(mission, outcome, watch, grown, held[0], sim.autopilot.mission.count - 1)
        return runs[horizon]

    return run


@pytest.mark.xdist_group("boat_survey_in_auto")
def test_the_horizon_is_filled_in_one_burst_once_the_autopilot_holds_one_waypoint_past_the_current_one(boat_survey_in_auto) -> None:
    """Horizon 3 on boat_survey's 8 waypoints: 1-4 uploaded; nothing appended while two are held past the current one; 5-6
    appended back to back on leg 3, 7-8 on leg 5: two bursts where one append a leg would restart four legs."""
    run = boat_survey_in_auto(3)  # limits.auto_horizon_legs' default
    assert run.outcome.status is MissionStatus.COMPLETED, run.outcome.reason
    assert run.held == 8 and run.grown == {3: [5, 6], 5: [7, 8]}  # 1-4 uploaded before AUTO


@pytest.mark.xdist_group("boat_survey_in_auto")
@pytest.mark.parametrize("horizon", [1, 2, 3])
def test_the_autopilot_never_holds_more_than_the_horizon_and_the_run_completes(boat_survey_in_auto, horizon: int) -> None:
    run = boat_survey_in_auto(horizon)
    assert run.outcome.status is MissionStatus.COMPLETED, run.outcome.reason
    assert max(run.watch.ahead) == horizon  # the waypoint after the next held (horizon 2 or more): AUTO plans its corners
    assert run.items_at_end == len(run.mission.waypoints)  # extended to the end as legs were reached
    assert run.watch.modes[-1] == "LOITER"  # the boat held at the end


def test_a_dead_executive_leaves_the_vehicle_stopped_at_the_end_of_the_horizon(lockstep) -> None:
    """The executive stops ticking mid leg 2 (kill -9): the autopilot drives what it holds, stops there (MIS_DONE_BEHAVE 0)."""
    mission = auto_mission("boat_survey")
    sim = lockstep(mission, ekf_ready_after_s=2.0)
    state = sim.runtime.mission_state
    second = mission.waypoints[1]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and sim.autopilot.vehicle.distance_to(second.lat, second.lon) < 30.0) is None
    held = sim.autopilot.mission.count - 1
    assert held == 1 + 1 + 2  # legs 1 and 2, and two beyond
    nearest = [float("inf")] * len(mission.waypoints)

    def watch(s: Lockstep) -> None:
        for i, wp in enumerate(mission.waypoints):
            nearest[i] = min(nearest[i], s.autopilot.vehicle.distance_to(wp.lat, wp.lon))

    sim.observers.append(watch)
    for _ in range(1200):  # two minutes of the vehicle's time, nobody ticking
        sim.step(0.1)
    vehicle = sim.autopilot.vehicle
    last_held = mission.waypoints[held - 1]
    assert vehicle.speed_m_s < 0.2 and vehicle.distance_to(last_held.lat, last_held.lon) < 5.0
    assert sim.autopilot.mode == "AUTO" and not sim.autopilot.mission.running  # its mission complete, stopped in AUTO
    assert min(nearest[held:]) > 10.0  # never drove on to a waypoint it was not given


def test_pause_holds_and_resume_continues_at_the_current_leg(lockstep) -> None:
    """ctl pause: the safe mode; ctl resume: MISSION_SET_CURRENT to the leg's item, then AUTO, not back to the first waypoint."""
    mission = line_mission("auto pause", drive="auto")
    sim = lockstep(mission)
    state = sim.runtime.mission_state
    sets = set_currents(sim)
    assert sim.run(until=lambda: state.legs.leg_index == 2) is None
    assert sim.runtime.operator.request("pause", source="ctl").ok
    sim.run(until=lambda: sim.autopilot.mode == "HOLD" and sim.autopilot.vehicle.speed_m_s < 0.05)
    assert sim.autopilot.mission.current_seq == 3 and state.status is MissionStatus.PAUSED
    sim.autopilot.mission.set_current(1)  # the autopilot's mission moved while paused (a ground station): resume puts it back
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sets == [1, 3]  # the first leg at the start, the third at the resume
    reached = sim.autopilot.vehicle
    last = mission.waypoints[-1]
    assert reached.distance_to(last.lat, last.lon) <= mission.limits.acceptance_radius_m


def test_a_person_changing_the_mode_pauses_and_setting_auto_again_resumes(lockstep) -> None:
    mission = line_mission("auto person", drive="auto")
    sim = lockstep(mission)
    state = sim.runtime.mission_state
    ap = sim.autopilot
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mode == "AUTO") is None
    assert ap.set_mode(ap.profile.modes["HOLD"])  # a ground station's HOLD
    sim.run(until=lambda: state.status is MissionStatus.PAUSED)
    assert state.reason == "HOLD set by the ground station"
    sim.run(until=lambda: ap.vehicle.speed_m_s < 0.05)
    assert ap.mode == "HOLD" and state.status is MissionStatus.PAUSED  # a person wins: nothing undone
    assert ap.set_mode(ap.profile.modes["AUTO"])
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason


@pytest.mark.parametrize(("value", "completes"), [(0, True), (1, True), (2, False), (3, False)])
def test_a_mission_end_that_would_not_stop_the_vehicle_is_refused_at_preflight(lockstep, value: int, completes: bool) -> None:
    mission = line_mission("auto done", drive="auto", simulator={"ekf_ready_after_s": 2.0, "params": {"MIS_DONE_BEHAVE": float(value)}})
    sim = lockstep(mission)
    outcome = sim.run_to_end()
    assert (outcome.status is MissionStatus.COMPLETED) is completes, outcome.reason
    if not completes:
        assert f"MIS_DONE_BEHAVE is {value}: set it to 0 or 1" in outcome.reason
        assert sim.autopilot.mission.count <= 1 and not sim.autopilot.armed  # refused before anything was sent or armed


def test_a_cut_link_leaves_the_vehicle_stopped_at_the_end_of_the_horizon_and_the_failsafe_acts_when_it_is_back(lockstep) -> None:
    mission = auto_mission("boat_survey")
    sim = lockstep(mission, ekf_ready_after_s=2.0, injector=lambda faults, clock: LinkCut(faults, clock))
    cut = sim.faults
    assert isinstance(cut, LinkCut)
    state, ap = sim.runtime.mission_state, sim.autopilot
    second, fourth = mission.waypoints[1], mission.waypoints[3]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.vehicle.distance_to(second.lat, second.lon) < 30.0) is None
    cut.cut = True
    t_cut = sim.clock.now()
    assert sim.run(until=lambda: sim.clock.now() > t_cut + 60.0) is None
    assert ap.mode == "AUTO" and not ap.mission.running and ap.vehicle.speed_m_s < 0.2  # its mission done at waypoint 4
    assert ap.vehicle.distance_to(fourth.lat, fourth.lon) < 5.0 and ap.mission.count - 1 == 4
    modes: list[str] = []
    back_to_second: list[float] = []
    sim.observers.append(lambda s: (modes.append(s.autopilot.mode), back_to_second.append(s.autopilot.vehicle.distance_to(second.lat, second.lon))))
    cut.cut = False
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    changes = [m for i, m in enumerate(modes) if i == 0 or modes[i - 1] != m]
    assert changes == ["AUTO", "LOITER", "AUTO", "LOITER"]  # the link-loss failsafe (boat: loiter), the route resumed, held at the end
    assert min(back_to_second) > 20.0  # resumed after waypoint 4, which it drove to unheard: not sent back along its horizon


def test_a_run_resumed_after_a_crash_starts_the_autopilots_mission_at_the_journals_leg(lockstep) -> None:
    """`executive run --resume` at leg 3: the horizon uploaded, MISSION_SET_CURRENT 3, then AUTO; items 1-2 never driven to."""
    mission = line_mission("auto resume", drive="auto")
    sim = lockstep(mission)
    sent: list[tuple[str, int]] = []
    send = sim.link.send

    def spy(msg: Any) -> None:
        if msg.get_type() in ("MISSION_SET_CURRENT", "MISSION_COUNT"):
            sent.append((msg.get_type(), msg.seq if msg.get_type() == "MISSION_SET_CURRENT" else msg.count))
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    driven: set[int] = set()
    sim.observers.append(lambda s: driven.add(s.autopilot.mission.current_seq) if s.autopilot.mission.running else None)
    outcome = sim.run(300, resume=ResumePoint(run=1, leg_index=2, samples=()))
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sent[:2] == [("MISSION_COUNT", 1 + 4), ("MISSION_SET_CURRENT", 3)]  # home + waypoints 1-4 (leg 3 and two beyond, the route's end)
    assert driven == {3, 4}  # the autopilot's mission ran items 3 and 4 only
