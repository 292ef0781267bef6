"""drive: auto on the waypoints tree of a PX4 vtol: AUTO.MISSION flies (a multicopter), the executive supervises, PX4 holds only the horizon.

Lock-step against the simulated PX4 standard VTOL. PX4 takes no partial writes: the horizon grows by the window uploaded again,
and PX4 keeps the item it flies to (tests/sim/px4/test_px4.py); at the end of what it holds it hovers in AUTO.LOITER.
"""

from __future__ import annotations

from typing import Any

from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import Lockstep
from tests_support import LINE_HOME, LinkCut, set_currents

#: 4 waypoints zig-zagging north, 100 m apart (north, east, north, west); PX4 flies them at MPC_XY_CRUISE (5 m/s) as a multicopter, 30 m up.
STEP_DEG = 0.000899
ZIGZAG = ((1, 0), (1, 1), (2, 1), (2, 0))


def vtol_mission(name: str, simulator: dict[str, Any] | None = None) -> Mission:
    fields: dict[str, Any] = {
        "version": 1,
        "name": name,
        "vehicle": "vtol",
        "autopilot": "px4",
        "tree": "waypoints",
        "drive": "auto",
        "auto_arm": True,
        "home": {"lat": LINE_HOME[0], "lon": LINE_HOME[1], "heading_deg": 0.0},
        "limits": {"acceptance_radius_m": 70, "leg_timeout_s": 120, "auto_horizon_legs": 1},
        "simulator": {"ekf_ready_after_s": 2.0, "params": {"MIS_TKO_LAND_REQ": 0.0}} | (simulator or {}),
        "waypoints": [{"lat": LINE_HOME[0] + STEP_DEG * n, "lon": LINE_HOME[1] + STEP_DEG * e / 0.8155, "alt_m": 30.0} for n, e in ZIGZAG],
    }
    return Mission.model_validate(fields)


def test_auto_mission_flies_the_route_holding_only_the_horizon(lockstep) -> None:
    mission = vtol_mission("px4 auto")
    sim = lockstep(mission, autopilot="px4")
    state = sim.runtime.mission_state
    most_ahead = [0]
    uploads: list[int] = []

    def watch(s: Lockstep) -> None:
        store = s.autopilot.mission
        if store.running and store.current_seq is not None:
            most_ahead[0] = max(most_ahead[0], store.count - 1 - store.current_seq)
        if not uploads or uploads[-1] != store.count:
            uploads.append(store.count)

    sim.observers.append(watch)
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert most_ahead[0] <= 1  # never more than the horizon beyond the item flown to
    assert uploads == sorted(uploads) and uploads[-1] == 4  # the window uploaded again as legs are reached, never cut
    last = mission.waypoints[-1]
    assert sim.autopilot.vehicle.distance_to(last.lat, last.lon) <= mission.limits.acceptance_radius_m
    assert state.legs.leg_index == len(mission.waypoints) and sim.autopilot.mode == "AUTO.LOITER"  # the vtol's safe mode at the end


def test_a_dead_executive_leaves_the_vtol_hovering_at_the_end_of_the_horizon(lockstep) -> None:
    """The executive stops ticking on leg 2: PX4 flies what it holds, then hovers in AUTO.LOITER (Commander.cpp), never flying on."""
    mission = vtol_mission("px4 auto killed")
    sim = lockstep(mission, autopilot="px4")
    state = sim.runtime.mission_state
    second = mission.waypoints[1]
    assert sim.run(until=lambda: state.legs.leg_index == 1 and sim.autopilot.vehicle.distance_to(second.lat, second.lon) < 60.0) is None
    held = sim.autopilot.mission.count
    assert held == 3  # legs 1 and 2, and one beyond
    last_held, beyond = mission.waypoints[held - 1], mission.waypoints[held]
    nearest_beyond = [float("inf")]

    def watch(s: Lockstep) -> None:
        nearest_beyond[0] = min(nearest_beyond[0], s.autopilot.vehicle.distance_to(beyond.lat, beyond.lon))

    sim.observers.append(watch)
    for _ in range(900):  # 90 s of the vehicle's time, nobody ticking
        sim.step(0.1)
    vehicle = sim.autopilot.vehicle
    assert sim.autopilot.mode == "AUTO.LOITER" and vehicle.speed_m_s < 0.2
    assert vehicle.distance_to(last_held.lat, last_held.lon) < 12.0 and nearest_beyond[0] > 80.0


def test_the_vtol_default_mis_tko_land_req_is_refused_at_preflight(lockstep) -> None:
    """MIS_TKO_LAND_REQ 2 (ROMFS rc.vtol_defaults) would reject every horizon: refused before anything is sent or armed."""
    sim = lockstep(vtol_mission("px4 auto refused", simulator={"params": {"MIS_TKO_LAND_REQ": 2.0}}), autopilot="px4")
    outcome = sim.run_to_end()
    assert outcome.status is not MissionStatus.COMPLETED
    assert "MIS_TKO_LAND_REQ is 2: set it to 0 or 4" in outcome.reason
    assert sim.autopilot.mission.count == 0 and not sim.autopilot.armed


def test_pause_hovers_in_auto_loiter_and_resume_sets_the_leg_then_auto_mission(lockstep) -> None:
    """ctl pause: the vtol's safe mode (AUTO.LOITER, a hover); ctl resume: MISSION_SET_CURRENT to the leg's item (PX4 takes it,
    tests/data/px4/auto-mission-window.tlog), then AUTO.MISSION: the route goes on at leg 3, not at the first waypoint."""
    mission = vtol_mission("px4 auto pause")
    sim = lockstep(mission, autopilot="px4")
    state, ap = sim.runtime.mission_state, sim.autopilot
    sets = set_currents(sim)
    assert sim.run(until=lambda: state.legs.leg_index == 2) is None
    assert sim.runtime.operator.request("pause", source="ctl").ok
    sim.run(until=lambda: ap.mode == "AUTO.LOITER" and ap.vehicle.speed_m_s < 0.2)
    assert state.status is MissionStatus.PAUSED
    ap.mission.set_current(0)  # a ground station moved the mission while paused: resume puts it back
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sets == [0, 2]  # the first leg's item at the start, the third leg's at the resume


def test_a_person_changing_the_mode_pauses_the_mission(lockstep) -> None:
    mission = vtol_mission("px4 auto person")
    sim = lockstep(mission, autopilot="px4")
    state, ap = sim.runtime.mission_state, sim.autopilot
    assert sim.run(until=lambda: state.legs.leg_index == 1 and ap.mode == "AUTO.MISSION") is None
    assert ap.request_mode("AUTO.RTL")  # a ground station's Return
    sim.run(until=lambda: state.status is MissionStatus.PAUSED)
    sim.step(5.0)
    assert ap.mode == "AUTO.RTL" and state.status is MissionStatus.PAUSED  # a person wins: nothing undone


def test_a_cut_link_leaves_the_vtol_hovering_at_the_end_of_the_horizon_and_the_route_goes_on_when_it_is_back(lockstep) -> None:
    """The link silent 60 s from leg 1 (horizon 1: waypoints 1-2 held): PX4 flies to waypoint 2 and hovers in AUTO.LOITER. Back,
    the legs it flew unheard are caught up from MISSION_CURRENT (COMPLETE at item 1) and the route goes on at waypoint 3: flown
    to, not skipped, although PX4 says COMPLETE with the item set until AUTO.MISSION runs (real SIH)."""
    mission = vtol_mission("px4 auto link cut")
    sim = lockstep(mission, autopilot="px4", injector=lambda faults, clock: LinkCut(faults, clock))
    cut = sim.faults
    assert isinstance(cut, LinkCut)
    ap = sim.autopilot
    first, second, third = mission.waypoints[:3]
    assert sim.run(until=lambda: ap.vehicle.alt_m > 25.0 and ap.vehicle.distance_to(first.lat, first.lon) < 60.0) is None
    cut.cut = True
    t_cut = sim.clock.now()
    assert sim.run(until=lambda: sim.clock.now() > t_cut + 60.0) is None
    assert ap.mode == "AUTO.LOITER" and ap.vehicle.speed_m_s < 0.2 and ap.vehicle.distance_to(second.lat, second.lon) < 12.0
    back_to_first: list[float] = []
    to_third: list[float] = []
    sim.observers.append(lambda s: (back_to_first.append(s.autopilot.vehicle.distance_to(first.lat, first.lon)),
                                    to_third.append(s.autopilot.vehicle.distance_to(third.lat, third.lon))))  # fmt: skip
    cut.cut = False
    outcome = sim.run_to_end()
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert min(back_to_first) > 80.0  # not sent back along the horizon it flew unheard
    assert min(to_third) < 12.0  # waypoint 3 flown to (PX4's NAV_ACC_RAD 10 m), not skipped
