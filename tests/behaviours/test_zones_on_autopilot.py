"""The mission's zones and rally points on the (simulated) autopilot at pre-flight: sent, read back, its own fence switched on.

Lock-step runs of the line mission (4 waypoints, 100 m due north) inside an inclusion polygon, with a
keep-out polygon ('pier', 10-20 m east of the route), a keep-out circle ('buoy', 20 m west) and two
rally points.
"""

from __future__ import annotations

import math
from typing import Any

from executive.autopilot.fence import fence_items, rally_items
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.sim.mission_store import StoredCommand
from executive.testing import Lockstep
from executive.world import blackboard, geo
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.frames import local_to_global
from tests_support import LINE_HOME, line_mission

_M = mavlink
FENCE, RALLY = _M.MAV_MISSION_TYPE_FENCE, _M.MAV_MISSION_TYPE_RALLY
_GCS = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)


def at(north_m: float, east_m: float) -> dict[str, float]:
    """The point ``north_m``, ``east_m`` from the line mission's home."""
    lat, lon = local_to_global(*LINE_HOME, north_m, east_m)
    return {"lat": round(lat, 7), "lon": round(lon, 7)}


def box(south: float, north: float, west: float, east: float) -> list[dict[str, float]]:
    return [at(south, west), at(north, west), at(north, east), at(south, east)]


PIER = box(40, 60, 10, 20)


def zoned_mission(on_autopilot: str = "upload", *, pier: list[dict[str, float]] = PIER, inclusion: tuple[Any, ...] = (), **changes: Any) -> Mission:
    geofence = {
        "polygon": box(-20, 130, -40, 40),
        "inclusion": list(inclusion),
        "keep_out": [{"name": "pier", "polygon": pier}, {"name": "buoy", "circle": {**at(50, -20), "radius_m": 8}}],
        "autopilot": on_autopilot,
    }
    rally = [{"name": "slipway", **at(-10, 5)}, {"name": "jetty", **at(110, -5)}]
    return line_mission("zones", geofence=geofence, rally_points=rally, **changes)


def sent_by_executive(sim: Lockstep) -> list[MAVLinkMessage]:
    """Every message the executive sends, in order (the link's ``send`` spied)."""
    sent: list[MAVLinkMessage] = []
    send = sim.link.send

    def spy(msg: MAVLinkMessage) -> None:
        sent.append(msg)
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    return sent


def held(commands: tuple[StoredCommand, ...]) -> list[tuple[int, float, float, float]]:
    return [(c.command, round(c.params[0], 3), round(c.lat, 7), round(c.lon, 7)) for c in commands]


def wanted(items: tuple[Any, ...]) -> list[tuple[int, float, float, float]]:
    return [(i.command, round(i.param1, 3), round(i.x, 7), round(i.y, 7)) for i in items]


def test_ardurover_takes_and_reads_back_the_zones_and_enforces_its_fence_before_arming(lockstep) -> None:
    mission = zoned_mission("enforce")
    sim = lockstep(mission)
    sent = sent_by_executive(sim)
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    ap = sim.autopilot
    assert held(ap.zone_stores[FENCE].commands) == wanted(fence_items(mission.geofence).items)
    assert [c.command for c in ap.zone_stores[FENCE].commands] == [5001] * 4 + [5002] * 4 + [5004]
    assert held(ap.zone_stores[RALLY].commands) == wanted(rally_items(mission.rally_points).items)
    # Rover/fence.cpp's Hold, the polygon type alone (no circle: no max_distance_from_home_m), on
    assert {n: ap.params[n] for n in ("FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION")} == {"FENCE_ENABLE": 1, "FENCE_TYPE": 4, "FENCE_ACTION": 2}
    kinds = [(m.get_type(), getattr(m, "mission_type", None), getattr(m, "command", None)) for m in sent]
    arm = kinds.index(("COMMAND_LONG", None, _M.MAV_CMD_COMPONENT_ARM_DISARM))
    last_read = max(i for i, k in enumerate(kinds) if k[0] == "MISSION_REQUEST_INT" and k[1] in (FENCE, RALLY))
    last_set = max(i for i, k in enumerate(kinds) if k[0] == "PARAM_SET")
    assert last_read < arm and last_set < arm  # read back and set before anything is armed


def test_without_enforce_the_zones_go_up_and_the_fence_is_left_off(lockstep) -> None:
    sim = lockstep(zoned_mission())
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert len(sim.autopilot.zone_stores[FENCE].commands) == 9 and len(sim.autopilot.zone_stores[RALLY].commands) == 2
    assert sim.autopilot.params["FENCE_ENABLE"] == 0  # read, said, not changed
    assert blackboard.reader("t", ["/vehicle/params"]).get("/vehicle/params")["FENCE_ACTION"] == 1


def test_px4_takes_and_reads_back_the_zones_and_holds_at_its_gf_action(lockstep) -> None:
    mission = zoned_mission("enforce", autopilot="px4")
    sim = lockstep(mission, autopilot="px4")
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert held(sim.autopilot.zone_stores[FENCE].commands) == wanted(fence_items(mission.geofence).items)
    assert len(sim.autopilot.zone_stores[RALLY].commands) == 2
    assert sim.autopilot.params["GF_ACTION"] == 2


def test_a_fence_the_autopilot_refuses_fails_the_preflight_naming_the_zones_and_nothing_is_armed(lockstep) -> None:
    # a keep-out polygon of 90 corners: ArduPilot's SITL fence storage holds 84 items (MissionItemProtocol: MAV_MISSION_NO_SPACE)
    ring = [at(50 + 6 * math.cos(a), 25 + 6 * math.sin(a)) for a in (2 * math.pi * k / 90 for k in range(90))]
    sim = lockstep(zoned_mission(pier=ring))
    armed = []
    sim.observers.append(lambda s: armed.append(s.autopilot.armed))
    outcome = sim.run_to_end(limit_s=120)
    assert outcome.status is MissionStatus.ABORTED
    assert "the autopilot did not take the fence (geofence.polygon, geofence.keep_out[0] 'pier', geofence.keep_out[1] 'buoy')" in outcome.reason
    assert "MAV_MISSION_NO_SPACE" in outcome.reason and "Only 84 items are supported" in outcome.reason
    assert not any(armed)


def test_px4_refuses_two_inclusion_shapes_before_anything_is_sent(lockstep) -> None:
    sim = lockstep(zoned_mission(autopilot="px4", inclusion=({"name": "bay", "circle": {**at(0, 0), "radius_m": 30}},)), autopilot="px4")
    outcome = sim.run_to_end(limit_s=120)
    assert outcome.status is MissionStatus.ABORTED
    assert "PX4 keeps a vehicle inside every inclusion shape at once" in outcome.reason and "geofence.inclusion[0] 'bay'" in outcome.reason
    assert sim.autopilot.zone_stores[FENCE].commands == () and not sim.autopilot.armed


def test_a_person_sending_the_rover_into_a_keep_out_zone_is_held_by_ardurovers_own_fence_and_the_executive_says_so(lockstep) -> None:
    sim = lockstep(zoned_mission("enforce"))
    sent = sent_by_executive(sim)
    bb = blackboard.reader("t", ["/vehicle/fence_status", "/vehicle/mode_set_by", "/mission/reason", "/vehicle/target_set_by"])
    pier = at(50, 15)  # its middle
    go_to = _GCS.command_int_encode(
        sim.autopilot.system_id, 1, _M.MAV_FRAME_GLOBAL, _M.MAV_CMD_DO_REPOSITION, 0, 0, -1.0, _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0.0,
        math.nan, round(pier["lat"] * 1e7), round(pier["lon"] * 1e7), 584.0,
    )  # fmt: skip
    sent_at: list[float] = []

    def person(s: Lockstep) -> None:  # QGroundControl's Go-to into the pier, mid leg 2 (the autopilot steering to our target)
        mid_leg = s.runtime.mission_state.legs.leg_index == 1 and geo.distance(*LINE_HOME, s.autopilot.vehicle.lat, LINE_HOME[1]) > 32
        if not sent_at and mid_leg and bb.get("/vehicle/target_set_by") == "us":
            s.send_from_ground_station(go_to)
            sent_at.append(s.clock.now())

    def fence_held() -> bool:
        status = bb.get("/vehicle/fence_status")
        return status is not None and status.breached and bb.get("/vehicle/mode_set_by") == "autopilot"

    sim.observers.append(person)
    assert sim.run(limit_s=200, until=fence_held) is None
    v = sim.autopilot.vehicle
    assert sim.autopilot.mode == "HOLD"  # FENCE_ACTION 2, set by enforce
    assert geo.distance(v.lat, v.lon, pier["lat"], pier["lon"]) < 9  # within the pier (10 x 20 m) when it breached
    assert sim.status is MissionStatus.PAUSED  # the person's Go-to paused it, hands off; the fence's HOLD is not undone
    assert bb.get("/mission/reason").startswith("a ground station sent it to")
    sim.run(limit_s=2, until=lambda: any(m.get_type() == "STATUSTEXT" and "fence breached" in m.text for m in sent))
    assert any(m.get_type() == "STATUSTEXT" and m.text == "autopilot's fence breached" for m in sent)


def test_a_running_mission_held_by_ardurovers_own_fence_pauses_hands_off_and_resumes_on_request(lockstep) -> None:
    sim = lockstep(zoned_mission("enforce"))
    bb = blackboard.reader("t", ["/mission/reason"])
    tightened: list[float] = []

    def ground_station(s: Lockstep) -> None:  # mid leg 2, a ground station narrows ArduRover's fence to 20 m around home
        if not tightened and s.runtime.mission_state.legs.leg_index == 1 and s.autopilot.params.get("FENCE_ENABLE") == 1:
            for name, value in (("FENCE_RADIUS", 20.0), ("FENCE_TYPE", 6.0)):
                s.send_from_ground_station(_GCS.param_set_encode(s.autopilot.system_id, 1, name.encode(), value, _M.MAV_PARAM_TYPE_REAL32))
            tightened.append(s.clock.now())

    sim.observers.append(ground_station)
    assert sim.run(limit_s=200, until=lambda: sim.status is MissionStatus.PAUSED) is None
    assert sim.autopilot.mode == "HOLD"  # FENCE_ACTION 2 on the circle's breach
    assert bb.get("/mission/reason").startswith("HOLD set by the autopilot: its own fence breached (FENCE_STATUS)")
    paused_at = sim.clock.now()
    assert sim.run(limit_s=10, until=lambda: sim.clock.now() >= paused_at + 5.0) is None
    assert sim.autopilot.mode == "HOLD" and sim.status is MissionStatus.PAUSED  # 5 s of ticks, hands off: not driven back out
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=200)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason  # a breach already acted on is not acted on again
