"""The distance rule (``limits.max_goal_distance_m``: 5 km, 1 km for a sub) for every tree, checked by the runtime before any tree runs.

Issue 28: a rover mission on the ``waypoints`` tree with a waypoint 10 km away armed, set GUIDED
and drove off; only ``goto_sample`` and ``auv_survey`` carried the check. Each built-in tree here
(and a plugin's, in tests/test_plugins.py) gets a waypoint out of reach of the simulated vehicle:
the mission ends ABORTED, saying which waypoint and how far, and the autopilot heard nothing but
the executive's heartbeat (nothing armed, no mode set, no route uploaded, no target).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission, Waypoint
from executive.mission.resume import ResumePoint
from executive.operator import Operator
from executive.testing import Lockstep
from executive.world.dialect import MAVLinkMessage
from executive.world.geo import destination
from executive.world.state import EkfFlags, EkfStatus, GlobalPosition
from tests_support import HARMLESS, LINE_HOME, acting, line_mission, run_recording, with_far_waypoint

ROOT = Path(__file__).parents[2]
MISSIONS = ROOT / "missions"


def asv() -> Mission:
    return load_mission(MISSIONS / "asv_sampling.yaml").model_copy(update={"simulator": None})


def ugv() -> Mission:
    near = destination(-35.363261, 149.165230, 0.0, 20.0)
    return load_mission(MISSIONS / "ugv_rc_route.yaml").model_copy(update={"waypoints": [Waypoint(lat=near[0], lon=near[1])]})


TREES: dict[str, tuple[Callable[[], Mission], float, str]] = {
    # tree: (a mission of it, how far the added waypoint is, the limit named)
    "waypoints": (lambda: line_mission("far-line"), 10_000.0, "5000 m"),
    "goto_sample": (asv, 6_000.0, "5000 m"),
    "auv_survey": (lambda: load_mission(MISSIONS / "auv_survey.yaml"), 1_500.0, "1000 m"),
    "vtol_transit": (lambda: load_mission(MISSIONS / "vtol_transit.yaml"), 8_000.0, "5000 m"),
    "ugv_rc_route": (ugv, 5_200.0, "5000 m"),
}


@pytest.mark.parametrize("tree", sorted(TREES))
def test_a_waypoint_out_of_reach_refuses_every_built_in_tree_before_anything_is_commanded(tree: str) -> None:
    make, metres, limit = TREES[tree]
    mission, boots_at = with_far_waypoint(make(), metres)
    assert mission.tree == tree
    outcome, sim, received = run_recording(mission, boots_at, mission_dir=MISSIONS)
    far = len(mission.waypoints) - 1
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason.startswith(
        f"refused before anything was commanded: Within reach: waypoints[{far}] (far): {metres:.0f} m from the vehicle, "
        f"over limits.max_goal_distance_m ({limit})"
    ), outcome.reason
    assert acting(received) == []
    assert received and {m.get_type() for m in received} <= HARMLESS | {"COMMAND_LONG"}
    assert not sim.autopilot.armed


def test_a_resumed_run_checks_only_the_waypoints_ahead() -> None:
    """A run continued after a crash at leg 2: the waypoint behind is a goal no more, however far it is now."""
    mission = line_mission("behind")
    far_behind, _ = with_far_waypoint(mission, 6_000.0)
    reordered = far_behind.model_copy(update={"waypoints": [far_behind.waypoints[-1], *mission.waypoints[:2]]})  # two ahead
    with Lockstep(reordered, home=(*LINE_HOME, 0.0)) as sim:
        outcome = sim.run(300, resume=ResumePoint(run=1, leg_index=1, samples=()))  # the far waypoint was reached before the crash
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED, outcome


def test_no_position_refuses_the_mission_after_the_ekf_wait_with_nothing_commanded() -> None:
    mission = line_mission("blind", limits={"acceptance_radius_m": 1.5, "ekf_wait_s": 5.0})
    with Lockstep(mission, home=(*LINE_HOME, 0.0)) as sim:
        sim.autopilot.start = (0.0, 0.0)  # the autopilot reports no fix (0, 0) until its EKF has an origin
        sim.autopilot.ekf_ready_after_s = 1000.0
        received: list[MAVLinkMessage] = []
        handle = sim.autopilot.handle
        sim.autopilot.handle = lambda msg: (received.append(msg), handle(msg))[1]  # type: ignore[method-assign]
        waiting: list[object] = []
        sim.observers.append(lambda s: waiting.append(s.runtime.status.snapshot().get("waiting")))
        outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason == (
        "refused before anything was commanded: Within reach: no position (that the EKF vouches for) within 5 s (limits.ekf_wait_s): "
        "every waypoint must be within 5000 m of the vehicle (limits.max_goal_distance_m)"
    )
    assert acting(received) == []
    shown = [w for w in waiting if w]
    assert shown and shown[-1]["node"] == "Within reach" and shown[-1]["feedback"].startswith("no position yet: every waypoint")  # type: ignore[index]


def test_a_position_the_ekf_does_not_vouch_for_is_waited_out_not_judged() -> None:
    """Real ArduPlane SITL before its GPS fix: GLOBAL_POSITION_INT 25 m from 0, 0 (DCM dead-reckoning on airspeed noise) with the
    EKF not initialised; the mission was refused as 14960 km out of reach. It waits for the EKF, then runs from home."""
    line = line_mission("before-the-fix")
    mission = line_mission("before-the-fix", waypoints=line.waypoints[:2])  # two legs: from home, run
    with Lockstep(mission, home=(*LINE_HOME, 0.0)) as sim:
        sim.autopilot.start = (0.0002246, -0.000037)  # what the aircraft reported before its EKF had an origin
        sim.autopilot.ekf_ready_after_s = 8.0
        outcome = sim.run_to_end(limit_s=600)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason


def test_ctl_start_with_the_vehicle_out_of_reach_is_refused_and_the_mission_stays_ready(vehicle) -> None:
    mission = line_mission("start-far")
    state = MissionState()
    state.upload(mission)
    operator = Operator(state, "rover")
    ekf = EkfStatus(EkfFlags(831), 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
    lat, lon = destination(*LINE_HOME, 180.0, 5_100.0)
    vehicle.set(vehicle__position=GlobalPosition(lat, lon, 0.0, 0, 0, 0, None, 0.0), vehicle__ekf=ekf)
    reply = operator.request("start", source="ctl")
    assert (reply.ok, reply.state) == (False, "READY")
    assert reply.reason.startswith("mission 'start-far' refused: waypoints[0]: 5125 m from the vehicle, over limits.max_goal_distance_m (5000 m)")
    vehicle.set(vehicle__position=GlobalPosition(*LINE_HOME, 0.0, 0, 0, 0, None, 0.0))
    assert operator.request("start", source="ctl").ok and state.status is MissionStatus.RUNNING


def test_a_waypoints_mission_out_of_reach_is_refused_at_upload(vehicle) -> None:
    state = MissionState()
    operator = Operator(state, "rover")
    ekf = EkfStatus(EkfFlags(831), 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
    lat, lon = destination(*LINE_HOME, 180.0, 6_000.0)
    vehicle.set(vehicle__position=GlobalPosition(lat, lon, 0.0, 0, 0, 0, None, 0.0), vehicle__ekf=ekf)
    text = (MISSIONS / "rover_square.yaml").read_text()
    reply = operator.request("upload", filename="rover_square.yaml", text=text)
    assert (reply.ok, reply.state) == (False, "IDLE")
    assert "over limits.max_goal_distance_m (5000 m)" in reply.reason
