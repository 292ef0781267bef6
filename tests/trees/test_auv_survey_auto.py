"""drive: auto on the AUV survey: the simulated ArduSub's AUTO flies the waypoints at their depths, the executive supervises.

Lock-step (manual clock) against the simulated ArduSub: the route as ArduSub's own mission (a NAV_WAYPOINT per
waypoint at minus its depth above home), no more than the horizon held, ArduSub holding position and depth at
the end of what it holds (Sub::exit_mission), the seabed floor bounding every depth it is given.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from test_waypoints_auto import LinkCut

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.mission.resume import ResumePoint
from executive.sim.physics.underwater import Seabed
from executive.testing import Lockstep
from executive.world import blackboard
from executive.world.dialect import mavlink
from tests_support import set_currents

ROOT = Path(__file__).parents[2]


def auto_survey(**limits: Any) -> Mission:
    """missions/auv_survey.yaml with ``drive: auto``, its altitude leg flown at a depth (AUTO takes depth legs only)."""
    mission = load_mission(ROOT / "missions" / "auv_survey.yaml")
    third = mission.waypoints[2].model_copy(update={"control_mode": "depth", "depth_m": 12.0, "altitude_m": None})
    return mission.model_copy(
        update={
            "drive": "auto",
            "waypoints": [*mission.waypoints[:2], third, mission.waypoints[3]],
            "limits": mission.limits.model_copy(update=limits),
        }
    )


class Watch:
    """After each step: the items the autopilot holds beyond the one it flies, the mode, the depths it was given, the deepest reached."""

    def __init__(self) -> None:
        self.ahead: list[int] = []
        self.modes: list[str] = []
        self.depths_given: set[float] = set()
        self.deepest = 0.0

    def __call__(self, sim: Lockstep) -> None:
        store = sim.autopilot.mission
        if store.running and store.current_seq is not None:
            self.ahead.append(store.count - 1 - store.current_seq)
        self.modes.append(sim.autopilot.mode)
        self.depths_given |= {-store.command(seq).alt_cm / 100 for seq in range(1, store.count)}
        self.deepest = max(self.deepest, sim.autopilot.vehicle.depth_m)


def test_the_survey_is_flown_in_arduSubs_auto_at_each_waypoints_depth_and_completes(lockstep) -> None:
    mission = auto_survey(auto_horizon_legs=2)  # 3 of the 4 waypoints held at the start, the 4th appended on leg 2
    sim = lockstep(mission)
    watch = Watch()
    sim.observers.append(watch)
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert max(watch.ahead) == 2 and sim.autopilot.mission.count - 1 == 4  # the horizon, extended to the end
    assert watch.depths_given == {0.01, 5.0, 12.0, 8.0}  # the surface just under it: an altitude of 0 keeps the depth (do_nav_wp)
    assert "AUTO" in watch.modes and watch.modes[-1] == "POSHOLD"  # then surfaced and held for the pick-up, as in GUIDED
    assert 11.5 <= watch.deepest <= 12.6


def test_a_dead_executive_leaves_the_sub_holding_position_and_depth_at_the_end_of_the_horizon(lockstep) -> None:
    """The executive stops ticking on leg 2 (kill -9): ArduSub flies what it holds (items 1-3 here: horizon 1),
    then holds the last one's position and depth in AUTO (Sub::exit_mission, ModeAuto::auto_loiter_start)."""
    mission = auto_survey(auto_horizon_legs=1)
    sim = lockstep(mission)
    state = sim.runtime.mission_state
    assert sim.run(until=lambda: state.legs.leg_index == 1 and sim.autopilot.mission.count - 1 == 3) is None  # legs 1, 2 and one beyond
    held = 3
    for _ in range(1800):  # three minutes of the vehicle's time, nobody ticking
        sim.step(0.1)
    ap = sim.autopilot
    last_held = mission.waypoints[held - 1]
    assert ap.mode == "AUTO" and not ap.mission.running  # its mission complete, held in AUTO
    assert ap.vehicle.speed_m_s < 0.1 and ap.vehicle.distance_to(last_held.lat, last_held.lon) < 2.5
    assert abs(ap.vehicle.depth_m - 12.0) < 0.5  # at the depth of the last item it holds
    fourth = mission.waypoints[3]
    assert ap.vehicle.distance_to(fourth.lat, fourth.lon) > 20.0  # never flew on to a waypoint it was not given
    # its words, unheard, as the real ArduSub's (tests/data/ardusub/auv_survey-auto-killed.tlog): each item reached with a
    # STATUSTEXT and MISSION_ITEM_REACHED, the end only in MISSION_CURRENT (its last item, COMPLETE), nothing said
    said = list(sim.link.incoming)
    texts = [m.text for m in said if m.get_type() == "STATUSTEXT"]
    assert [t for t in texts if t.startswith("Reached")] == ["Reached command #2", "Reached command #3"]
    assert not any("Complete" in t for t in texts)
    assert [m.seq for m in said if m.get_type() == "MISSION_ITEM_REACHED"] == [2, 3]
    last = [m for m in said if m.get_type() == "MISSION_CURRENT"][-1]
    assert (last.seq, last.mission_state) == (3, mavlink.MISSION_STATE_COMPLETE)


def test_a_depth_the_water_cannot_hold_is_given_at_the_seabed_floor(lockstep) -> None:
    """A flat seabed 10 m down: leg 3's 12 m is given at the floor (2 m above the seabed by the sonar), never deeper; as GUIDED holds it."""
    mission = auto_survey()
    mission = mission.model_copy(update={"limits": mission.limits.model_copy(update={"water_depth_m": None})})
    sim = lockstep(mission, firmware={"seabed": Seabed(depth_m=10.0, slope=0.0)})
    watch = Watch()
    sim.observers.append(watch)
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert max(watch.depths_given) <= 8.0 + 0.05  # 10 m seabed less limits.altitude_m.min
    assert watch.deepest <= 8.3


def test_with_seabed_floor_fail_a_depth_the_water_cannot_hold_fails_the_mission(lockstep) -> None:
    mission = auto_survey(seabed_floor="fail")
    mission = mission.model_copy(update={"limits": mission.limits.model_copy(update={"water_depth_m": None})})
    sim = lockstep(mission, firmware={"seabed": Seabed(depth_m=10.0, slope=0.0)})
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.ABORTED
    assert "deeper than the water holds" in outcome.reason and "limits.seabed_floor: fail" in outcome.reason


def test_a_person_changing_the_mode_pauses_and_auto_again_resumes_at_the_leg(lockstep) -> None:
    mission = auto_survey()
    sim = lockstep(mission.model_copy(update={"waypoints": mission.waypoints[:2]}))  # the leg set on is the last: done once resumed
    state, ap = sim.runtime.mission_state, sim.autopilot
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mode == "AUTO") is None
    assert ap.set_mode(ap.profile.modes["POSHOLD"])  # a ground station's POSHOLD
    sim.run(until=lambda: state.status is MissionStatus.PAUSED)
    assert state.reason == "POSHOLD set by the ground station"
    assert ap.set_mode(ap.profile.modes["AUTO"])
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason


def test_a_persons_alt_hold_mid_leg_still_pauses_after_the_wait_for_the_autopilots_facts(lockstep) -> None:
    """AUTO -> ALT_HOLD may be ArduSub's mission end, judged once MISSION_CURRENT and EKF_STATUS_REPORT came after it: a ground
    station's, its position good, its mission running, pauses all the same, within FACTS_WAIT_S, AUTO never asked meanwhile."""
    mission = auto_survey()
    sim = lockstep(mission)
    state, ap = sim.runtime.mission_state, sim.autopilot
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mode == "AUTO") is None
    assert ap.set_mode(ap.profile.modes["ALT_HOLD"])
    t_set = sim.clock.now()
    modes: list[str] = []
    sim.observers.append(lambda s: modes.append(s.autopilot.mode))
    sim.run(until=lambda: state.status is MissionStatus.PAUSED)
    assert state.reason == "ALT_HOLD set by the ground station"
    assert sim.clock.now() - t_set <= 2.6  # the heartbeat (1 Hz), then FACTS_WAIT_S at most
    assert set(modes) == {"ALT_HOLD"}


def test_a_seabed_rising_under_the_leg_raises_its_depth_and_starts_it_again(lockstep) -> None:
    """The seabed rises 0.15 m per metre north (12.8 m under waypoint 3): as the sonar reads it rising under leg 3 (12 m), the
    item is written shallower and the leg started again (MISSION_SET_CURRENT): ArduSub flies the item it began with (no
    mission change detection). The sub never comes within 1.5 m of the seabed (GUIDED, the same seabed: 1.68 m)."""
    mission = auto_survey()
    mission = mission.model_copy(update={"limits": mission.limits.model_copy(update={"water_depth_m": None})})
    sim = lockstep(mission, firmware={"seabed": Seabed(depth_m=18.0, slope=0.15, downhill_deg=180.0)})
    sets = set_currents(sim)
    clearance: list[float] = []
    sim.observers.append(lambda s: clearance.append(s.autopilot.vehicle.altitude_m))
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sets[0] == 1 and sets.count(3) >= 1  # leg 3 started again at its raised depth
    assert min(clearance) >= 1.5, min(clearance)


def test_pause_holds_in_poshold_and_resume_goes_on_with_the_leg_at_its_depth(lockstep) -> None:
    """ctl pause: the sub's safe mode (POSHOLD: position and depth); ctl resume: MISSION_SET_CURRENT to the leg's item, then AUTO."""
    mission = auto_survey()
    sim = lockstep(mission)
    state, ap = sim.runtime.mission_state, sim.autopilot
    sets = set_currents(sim)
    assert sim.run(until=lambda: state.legs.leg_index == 2 and ap.vehicle.depth_m > 7.0) is None
    assert sim.runtime.operator.request("pause", source="ctl").ok
    sim.run(until=lambda: ap.mode == "POSHOLD" and ap.vehicle.speed_m_s < 0.05)
    held_at = ap.vehicle.depth_m
    assert sim.run(until=lambda: sim.clock.now() > 200.0) is None  # long past the 90 s leg timeout
    assert state.status is MissionStatus.PAUSED and abs(ap.vehicle.depth_m - held_at) < 0.3
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sets == [1, 3]  # the first leg at the start, the third at the resume


def test_a_dive_toward_a_seabed_beyond_the_sonar_goes_down_as_the_sonar_reaches_further(lockstep) -> None:
    """Leg 3 at 45 m over a 50 m seabed the 30 m sonar does not reach from the surface: given at 28 m (the surface's floor),
    deepened, and the leg started again, as the sub goes down, to its 45 m once the sonar reads the seabed."""
    mission = auto_survey(leg_timeout_s=300)
    deep = [*mission.waypoints[:2], mission.waypoints[2].model_copy(update={"depth_m": 45.0}), mission.waypoints[3]]
    sim = lockstep(mission.model_copy(update={"waypoints": deep}), firmware={"seabed": Seabed(depth_m=50.0, slope=0.0)})
    watch = Watch()
    sim.observers.append(watch)
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert min(watch.depths_given - {0.01, 5.0, 8.0}) == 28.0 and max(watch.depths_given) == 45.0
    assert 44.5 <= watch.deepest <= 45.6


def test_a_cut_link_leaves_the_sub_at_the_end_of_its_horizon_and_the_failsafe_acts_when_the_link_is_back(lockstep) -> None:
    """Cut on leg 2 (horizon 1: items 1-3): ArduSub flies to waypoint 3 and holds it at 12 m in AUTO. Link back: the mission's
    link-loss failsafe (the survey's: hold in POSHOLD, then resume), legs 2-3 caught up from MISSION_CURRENT (COMPLETE at
    item 3), item 4 set: not sent back to waypoint 2."""
    mission = auto_survey(auto_horizon_legs=1, recovery_timeout_s=180)  # the link down 120 s
    sim = lockstep(mission, injector=lambda faults, clock: LinkCut(faults, clock))
    cut = sim.faults
    assert isinstance(cut, LinkCut)
    state, ap = sim.runtime.mission_state, sim.autopilot
    second, third = mission.waypoints[1], mission.waypoints[2]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mission.count - 1 == 3) is None
    cut.cut = True
    t_cut = sim.clock.now()
    assert sim.run(until=lambda: sim.clock.now() > t_cut + 120.0) is None
    assert ap.mode == "AUTO" and not ap.mission.running and ap.vehicle.distance_to(third.lat, third.lon) < 1.0
    assert abs(ap.vehicle.depth_m - 12.0) < 0.3
    modes: list[str] = []
    back: list[float] = []
    sim.observers.append(lambda s: (modes.append(s.autopilot.mode), back.append(s.autopilot.vehicle.distance_to(second.lat, second.lon))))
    cut.cut = False
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    changes = [m for i, m in enumerate(modes) if i == 0 or modes[i - 1] != m]
    assert changes[:3] == ["AUTO", "POSHOLD", "AUTO"]  # the failsafe's hold, then the route resumed
    assert min(back) > 15.0  # resumed after waypoint 3: never sent back along its horizon


def test_a_run_resumed_after_a_crash_starts_arduSubs_mission_at_the_journals_leg(lockstep) -> None:
    """`executive run --resume` at leg 3: the horizon uploaded, MISSION_SET_CURRENT 3, then AUTO; items 1-2 never flown to."""
    sim = lockstep(auto_survey())
    sets = set_currents(sim)
    flown: set[int] = set()
    sim.observers.append(lambda s: flown.add(s.autopilot.mission.current_seq) if s.autopilot.mission.running else None)
    outcome = sim.run(400, resume=ResumePoint(run=1, leg_index=2, samples=()))
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sets[0] == 3 and flown == {3, 4}


def test_arduSubs_alt_hold_at_the_end_of_its_horizon_without_a_position_is_the_autopilots_and_the_sub_is_taken_on(lockstep) -> None:
    """The link cut on leg 2 (horizon 1: items 1-3) and the position lost short of waypoint 3: ArduSub ends its mission in
    ALT_HOLD, not AUTO (Sub::exit_mission: auto_loiter_start fails without a position). When the link is back, that ALT_HOLD
    is the autopilot's (its last item reached, no position), not a person's: no pause; once the position is back the
    executive appends waypoint 4, sets the leg and AUTO again, to COMPLETED."""
    mission = auto_survey(auto_horizon_legs=1, recovery_timeout_s=180)
    sim = lockstep(mission, injector=lambda faults, clock: LinkCut(faults, clock))
    cut = sim.faults
    assert isinstance(cut, LinkCut)
    state, ap = sim.runtime.mission_state, sim.autopilot
    third = mission.waypoints[2]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mission.count - 1 == 3) is None
    cut.cut = True
    assert sim.run(until=lambda: ap.vehicle.distance_to(third.lat, third.lon) < 4.0) is None
    ap.ekf_position_lost = True
    assert sim.run(until=lambda: ap.mode == "ALT_HOLD") is None
    assert not ap.mission.running and ap.mission.current_seq == 3  # ended at item 3 of 4
    bb = blackboard.reader("mission end test", ["/vehicle/mode_set_by"])
    reasons: list[str | None] = []
    sim.observers.append(lambda s: reasons.append(bb.get("/vehicle/mode_set_by")))
    cut.cut = False
    t_back = sim.clock.now()
    assert sim.run(until=lambda: sim.clock.now() > t_back + 5.0) is None
    assert state.status is MissionStatus.RUNNING, state.reason  # not paused: the autopilot's own end
    assert "autopilot" in reasons and "others" not in reasons
    ap.ekf_position_lost = False
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    fourth = mission.waypoints[3]
    assert ap.mission.count - 1 == 4 and ap.vehicle.distance_to(fourth.lat, fourth.lon) < 30.0
