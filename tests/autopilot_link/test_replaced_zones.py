"""A paused mission replaced (``ctl upload``) by one with other zones: the autopilot's fence and rally points follow before it resumes.

Lock-step runs of the zoned line mission of ``tests/behaviours/test_zones_on_autopilot.py`` (4 waypoints,
100 m due north, a keep-out 'pier' and 'buoy', two rally points), paused heading for waypoint 2 and
replaced by the same route with other zones, with a fence the autopilot refuses, or with none.
"""

from __future__ import annotations

import math

from executive.autopilot.fence import fence_items, rally_items
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import Lockstep
from executive.world import blackboard
from tests.behaviours.test_zones_on_autopilot import FENCE, RALLY, at, box, held, wanted, zoned_mission
from tests.runtime.test_runtime_reload import pause_on_leg, run_for, text
from tests_support import line_mission


def replace_with(sim: Lockstep, new: Mission) -> str:
    """``ctl upload`` of ``new`` while paused: replaced, still PAUSED; the reply's reason."""
    reply = sim.runtime.operator.request("upload", source="ctl", filename="v2.yaml", text=text(new))
    assert (reply.ok, reply.state) == (True, "PAUSED"), reply.reason
    assert sim.runtime.mission_state.mission.name == new.name
    return reply.reason


def test_the_new_zones_are_uploaded_read_back_and_enforced_before_the_replacing_mission_may_resume(lockstep) -> None:
    sim = lockstep(zoned_mission())
    pause_on_leg(sim, 1)
    ap = sim.autopilot
    assert len(ap.zone_stores[FENCE].commands) == 9 and ap.params["FENCE_ENABLE"] == 0  # the old mission's, not enforced
    geofence = {"keep_out": [{"name": "moorings", "polygon": box(70, 80, 8, 16)}], "autopilot": "enforce"}
    new = line_mission("zones-v2", geofence=geofence, rally_points=[{"name": "beach", **at(30, -15)}])
    said = replace_with(sim, new)
    waits = "the new mission's zones are not yet on the autopilot (waiting for another mission transfer to end)"  # the route goes first
    assert said.endswith(f"paused until resumed; {waits}: resume once they are read back")
    refused = sim.runtime.operator.request("resume", source="ctl")
    assert (refused.ok, refused.state) == (False, "PAUSED")  # at once: nothing of the new mission runs before its zones are up
    assert refused.reason.startswith("cannot resume: the new mission's zones are not yet on the autopilot")
    assert sim.run(limit_s=60, until=lambda: ap.params["FENCE_ENABLE"] == 1) is None
    assert held(ap.zone_stores[FENCE].commands) == wanted(fence_items(new.geofence).items)  # the moorings alone, read back
    assert held(ap.zone_stores[RALLY].commands) == wanted(rally_items(new.rally_points).items)
    assert ap.mode == "HOLD" and sim.status is MissionStatus.PAUSED
    run_for(sim, 1.0)
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason


def test_a_fence_the_autopilot_refuses_keeps_the_mission_paused_with_the_reason_and_nothing_runs(lockstep) -> None:
    sim = lockstep(zoned_mission())
    pause_on_leg(sim, 1)
    ap = sim.autopilot
    old_fence = ap.zone_stores[FENCE].commands
    # 90 corners: ArduPilot's SITL fence storage holds 84 items (MAV_MISSION_NO_SPACE)
    ring = [at(50 + 6 * math.cos(a), 25 + 6 * math.sin(a)) for a in (2 * math.pi * k / 90 for k in range(90))]
    replace_with(sim, zoned_mission(pier=ring).model_copy(update={"name": "ring"}))
    run_for(sim, 20.0)
    here = (ap.vehicle.lat, ap.vehicle.lon)  # braked to a stop by then
    reply = sim.runtime.operator.request("resume", source="ctl")
    assert (reply.ok, reply.state) == (False, "PAUSED")
    assert reply.reason.startswith("cannot resume: the new mission's zones are not on the autopilot: the autopilot did not take the fence")
    assert "MAV_MISSION_NO_SPACE" in reply.reason and "Only 84 items are supported" in reply.reason
    assert ap.zone_stores[FENCE].commands == old_fence  # refused whole: the autopilot keeps the fence it had
    status = sim.runtime.operator.request("status", source="ctl")
    assert status.reason.startswith("mission replaced: 'zones' -> 'ring'") and reply.reason in status.reason
    run_for(sim, 5.0)
    assert sim.status is MissionStatus.PAUSED and ap.mode == "HOLD"
    assert (ap.vehicle.lat, ap.vehicle.lon) == here  # held: nothing of the new mission ran


def test_a_replacing_mission_without_zones_clears_the_fence_and_rally_points_the_old_one_put_there(lockstep) -> None:
    sim = lockstep(zoned_mission())
    pause_on_leg(sim, 1)
    ap = sim.autopilot
    assert len(ap.zone_stores[FENCE].commands) == 9 and len(ap.zone_stores[RALLY].commands) == 2
    replace_with(sim, line_mission("open-water"))
    assert not sim.runtime.operator.request("resume", source="ctl").ok
    assert sim.run(limit_s=60, until=lambda: ap.zone_stores[FENCE].commands == () and ap.zone_stores[RALLY].commands == ()) is None
    run_for(sim, 1.0)  # the empty lists read back
    assert blackboard.reader("t", ["/vehicle/fence_items"]).get("/vehicle/fence_items") == ()
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
