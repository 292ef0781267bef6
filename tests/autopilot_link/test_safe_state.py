"""Made safe for the kind and the phase (issue 44, item 4), on the simulated firmware in lock-step.

An AUV stopped under water surfaces (SURFACE, which the simulated ArduSub ends itself in ALT_HOLD at the surface as
ArduSub/mode_surface.cpp does) and is held there in POSHOLD; a VTOL stopped while landing, or low in its climb, lands
and disarms in QLAND (AUTO.LAND on PX4) instead of hovering; higher up it hovers as before. The executive stays until
the safe state (bounded) and its line before the last says where it left the vehicle. Before: SIGTERM left the AUV in
POSHOLD at 26 m, armed; `ctl abort` at 1.9 m in a landing left the VTOL hovering in QLOITER / AUTO.LOITER, armed.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import py_trees
import pytest

from executive.autopilot_link.safe_state import Until, plan
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.runtime.loop import RunOutcome
from executive.testing import Lockstep
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition

MISSIONS = Path(__file__).parents[2] / "missions"


def bb(key: str) -> object:
    return py_trees.blackboard.Blackboard.get(key)


def height() -> float:
    position = bb("/vehicle/position")
    return position.alt_rel_m if position is not None else float("nan")  # type: ignore[attr-defined]


def modes_asked(sim: Lockstep) -> list[str]:
    """Every mode the runtime asks of the autopilot from now on, as the autopilot names it."""
    asked: list[str] = []
    port = sim.runtime.link.autopilot
    set_mode = port.set_mode

    def spy(mode: str):
        asked.append(port.mode_name(mode))
        return set_mode(mode)

    port.set_mode = spy  # type: ignore[method-assign]
    return asked


def stopped(sim: Lockstep, *, abort: bool = False) -> tuple[RunOutcome, float]:
    """SIGTERM (or `ctl abort`) now: how the run ended and how long (vehicle time) the make-safe took."""
    start = sim.clock.now()
    if abort:
        assert sim.runtime.operator.request("abort", source="ctl").ok
    else:
        sim.runtime.request_stop("SIGTERM")
    outcome = sim.run_to_end(limit_s=300)
    return outcome, sim.clock.now() - start


def test_an_auv_stopped_under_water_surfaces_and_holds_position_there(lockstep) -> None:
    sim = lockstep(load_mission(MISSIONS / "auv_survey.yaml"), mission_dir=MISSIONS)
    assert sim.run(limit_s=600, until=lambda: sim.status is MissionStatus.RUNNING and sim.autopilot.vehicle.depth_m > 20.0) is None
    depth = sim.autopilot.vehicle.depth_m
    asked = modes_asked(sim)
    outcome, took = stopped(sim)
    assert outcome.status is MissionStatus.ABORTED
    assert asked == ["SURFACE", "POSHOLD"]
    assert sim.autopilot.vehicle.depth_m < 0.5 and sim.autopilot.mode == "POSHOLD" and sim.autopilot.armed
    report = outcome.safe or ""
    assert report.startswith("the vehicle made safe: surfaced, holding position, armed (SURFACE (confirmed), surfaced after "), report
    print(f"\nsurfaced from {depth:.1f} m in {took:.1f} s: {report}")
    assert took < 30.0 + depth / 0.5  # the bound: the depth at 0.5 m/s and a margin


def test_an_auv_just_under_the_surface_surfaces_and_holds_position(lockstep) -> None:
    """From under a metre the surface comes within a second (SURFACE, then ArduSub's own ALT_HOLD): its ALT_HOLD is nobody's."""
    sim = lockstep(load_mission(MISSIONS / "auv_survey.yaml"), mission_dir=MISSIONS)
    assert sim.run(limit_s=600, until=lambda: sim.status is MissionStatus.RUNNING and 0.6 < sim.autopilot.vehicle.depth_m < 0.9) is None
    asked = modes_asked(sim)
    outcome, _ = stopped(sim)
    assert asked[0] == "SURFACE" and asked[-1] == "POSHOLD" and sim.autopilot.mode == "POSHOLD" and sim.autopilot.vehicle.depth_m < 0.5
    assert (outcome.safe or "").startswith("the vehicle made safe: surfaced, holding position, armed (SURFACE ("), outcome.safe


def test_an_auv_a_person_holds_is_not_surfaced(lockstep) -> None:
    """A ground station's POSHOLD mid-leg pauses the mission hands off: stopping then commands nothing over it."""
    sim = lockstep(load_mission(MISSIONS / "auv_survey.yaml"), mission_dir=MISSIONS)
    # under water on leg 2 (its 5 m, ~30 s in), where stopping would otherwise surface it
    assert sim.run(limit_s=600, until=lambda: sim.status is MissionStatus.RUNNING and sim.autopilot.vehicle.depth_m > 4.0) is None
    sim.autopilot.set_mode(sim.autopilot.profile.modes["POSHOLD"])  # a person's POSHOLD (the ground station)
    assert sim.run(limit_s=5, until=lambda: sim.status is MissionStatus.PAUSED) is None
    asked = modes_asked(sim)
    outcome, _ = stopped(sim)
    assert outcome.status is MissionStatus.ABORTED and asked == [] and sim.autopilot.mode == "POSHOLD"
    assert (outcome.safe or "").startswith("not commanding SURFACE: a person holds the vehicle (the mission paused hands off: POSHOLD set by")


def test_a_rover_a_person_sent_home_is_not_held(lockstep) -> None:
    """A ground station's RTL mid-leg pauses the mission hands off: stopping then commands no HOLD over it (a person wins)."""
    sim = lockstep(load_mission(MISSIONS / "rover_square.yaml"), mission_dir=MISSIONS)
    assert sim.run(limit_s=300, until=lambda: sim.status is MissionStatus.RUNNING and sim.autopilot.mode == "GUIDED") is None
    sim.autopilot.set_mode(sim.autopilot.profile.modes["RTL"])  # a person's RTL (the ground station)
    assert sim.run(limit_s=5, until=lambda: sim.status is MissionStatus.PAUSED) is None
    asked = modes_asked(sim)
    outcome, _ = stopped(sim)
    assert outcome.status is MissionStatus.ABORTED and asked == [] and sim.autopilot.mode == "RTL"
    assert (outcome.safe or "").startswith("not commanding HOLD: a person holds the vehicle (the mission paused hands off: RTL set by")


def landing_low(sim: Lockstep) -> None:
    """Run the example transit until it is landing at home, under 2 m."""
    assert sim.run(limit_s=600, until=lambda: bb("/vehicle/landed_state") == "LANDING" and height() < 2.0) is None


def test_a_quadplane_aborted_while_landing_lands_and_disarms_in_qland(lockstep) -> None:
    sim = lockstep(load_mission(MISSIONS / "vtol_transit.yaml"))
    landing_low(sim)
    low = height()
    asked = modes_asked(sim)
    outcome, took = stopped(sim, abort=True)
    assert outcome.status is MissionStatus.ABORTED and asked == ["QLAND"]
    assert not sim.autopilot.armed and sim.autopilot.landed_state == mavlink.MAV_LANDED_STATE_ON_GROUND
    report = outcome.safe or ""
    assert report.startswith("the vehicle made safe: landed, disarmed (QLAND (confirmed), landed and disarmed after "), report
    print(f"\nQLAND from {low:.1f} m: landed and disarmed in {took:.1f} s: {report}")


def test_a_px4_vtol_aborted_while_landing_lands_and_disarms_in_auto_land(lockstep) -> None:
    sim = lockstep(load_mission(MISSIONS / "vtol_transit.yaml"), autopilot="px4")
    landing_low(sim)
    low = height()
    asked = modes_asked(sim)
    outcome, took = stopped(sim, abort=True)
    assert outcome.status is MissionStatus.ABORTED and asked[:1] == ["AUTO.LAND"]
    assert not sim.autopilot.armed and sim.autopilot.landed
    report = outcome.safe or ""
    assert report.startswith("the vehicle made safe: landed, disarmed (AUTO.LAND (confirmed), landed and disarmed after "), report
    print(f"\nAUTO.LAND from {low:.1f} m: landed and disarmed in {took:.1f} s: {report}")


def test_a_vtol_stopped_low_in_its_climb_lands_and_high_up_hovers_as_before(lockstep) -> None:
    low = lockstep(load_mission(MISSIONS / "vtol_transit.yaml"))
    assert low.run(limit_s=600, until=lambda: bb("/vehicle/landed_state") == "TAKEOFF" and 1.0 < height() < 3.0) is None
    asked = modes_asked(low)
    stopped(low)
    assert asked == ["QLAND"] and not low.autopilot.armed
    high = lockstep(load_mission(MISSIONS / "vtol_transit.yaml"))
    assert high.run(limit_s=600, until=lambda: height() > 25.0) is None
    asked = modes_asked(high)
    outcome, _ = stopped(high)
    assert asked == ["QLOITER"] and high.autopilot.armed and outcome.safe == "the vehicle made safe: QLOITER (confirmed)"


def readings(alt_rel_m: float | None = None, *, armed: bool = True, landed: str | None = None) -> Callable[[str], object]:
    position = None if alt_rel_m is None else GlobalPosition(0.0, 0.0, alt_rel_m, 0.0, 0.0, 0.0, None, 0.0)
    values = {"/vehicle/position": position, "/vehicle/armed": armed, "/vehicle/landed_state": landed}
    return values.get


@pytest.mark.parametrize(
    ("kind", "firmware", "asked", "read", "mode", "until"),
    [
        pytest.param("sub", "ardupilot", None, readings(-26.0), "SURFACE", Until.SURFACED, id="sub-deep"),
        pytest.param("sub", "ardupilot", "POSHOLD", readings(-26.0), "SURFACE", Until.SURFACED, id="sub-failsafe-hold"),
        pytest.param("sub", "ardupilot", None, readings(-0.2), "POSHOLD", Until.SHOWN, id="sub-at-surface"),
        pytest.param("sub", "ardupilot", None, readings(-26.0, armed=False), "POSHOLD", Until.SHOWN, id="sub-disarmed"),
        pytest.param("vtol", "ardupilot", None, readings(5.5, landed="IN_AIR"), "QLAND", Until.LANDED, id="quadplane-5.5m"),
        pytest.param("vtol", "px4", None, readings(5.5, landed="IN_AIR"), "QLOITER", Until.SHOWN, id="px4-5.5m"),
        pytest.param("vtol", "px4", None, readings(20.0, landed="LANDING"), "QLAND", Until.LANDED, id="px4-landing"),
        pytest.param("vtol", "ardupilot", None, readings(0.0, landed="ON_GROUND"), "QLAND", Until.LANDED, id="armed-on-ground"),
        pytest.param("vtol", "ardupilot", None, readings(0.0, armed=False, landed="ON_GROUND"), "QLOITER", Until.SHOWN, id="disarmed"),
        pytest.param("vtol", "ardupilot", "QRTL", readings(3.0, landed="IN_AIR"), "QRTL", Until.SHOWN, id="failsafe-qrtl-kept"),
        pytest.param("rover", "ardupilot", None, readings(0.0), "HOLD", Until.SHOWN, id="rover"),
    ],
)
def test_the_plan_by_kind_and_phase(kind, firmware, asked, read, mode, until) -> None:
    safe_mode = {"sub": "POSHOLD", "vtol": "QLOITER", "rover": "HOLD"}[kind]
    chosen = plan(kind, firmware, asked, safe_mode, read)
    assert (chosen.mode, chosen.until) == (mode, until)
