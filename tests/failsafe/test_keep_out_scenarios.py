"""Keep-out zones while the mission runs, on the lock-step simulated ArduRover.

A pier stands between the far end of the route and home. The route goes round it (the checks at
every door saw to that); the return, the take-over and the route edit are where the vehicle meets it.
"""

from __future__ import annotations

from typing import Any

import shapely
from tlog_replay import DATA as RECORDINGS
from tlog_replay import records

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.mission.zones import Plane, Zones
from executive.sim.faults import BatterySag, RcInput, RcTakeover
from executive.world import geo
from executive.world.vehicles import ROVER_MODES
from tests_support import LINE_HOME, line_mission

DATA = RECORDINGS / "ardurover"

PIER_NORTH_M, PIER_RADIUS_M = 30.0, 8.0
BOAT_EAST_M, BOAT_RADIUS_M = 58.0, 8.0  # a moored boat just past the first waypoint: 10 m off it and off the second leg


def at(north_m: float, east_m: float) -> tuple[float, float]:
    lat, lon = geo.destination(*LINE_HOME, 0.0, north_m)
    return geo.destination(lat, lon, 90.0, east_m)


def point(north_m: float, east_m: float, **more: Any) -> dict[str, Any]:
    lat, lon = at(north_m, east_m)
    return {"lat": lat, "lon": lon, **more}


def round_the_pier(**changes: Any) -> Mission:
    """East 40 m, north 60 m, back west over home's meridian: the way home from there runs straight through the pier; a moored
    boat lies 10 m beyond the first waypoint, where a rover driven straight on would go."""
    pier, boat = point(PIER_NORTH_M, 0.0, radius_m=PIER_RADIUS_M), point(0.0, BOAT_EAST_M, radius_m=BOAT_RADIUS_M)
    fields: dict[str, Any] = {
        "waypoints": [point(0, 40, name="east"), point(60, 40, name="north-east"), point(60, 0, name="north")],
        "geofence": {"keep_out": [{"name": "pier", "circle": pier}, {"name": "moored boat", "circle": boat}]},
    }
    return line_mission("round the pier", **(fields | changes))


class Track:
    """The simulated vehicle's true positions, every step of the world, and how deep into the pier it ever went."""

    def __init__(self, sim: Any, mission: Mission) -> None:
        self.vehicle = sim.autopilot.vehicle
        self.zones = Zones(mission, Plane(LINE_HOME))
        self.points: list[tuple[float, float]] = []
        self.modes_while_switch_high: list[str] = []
        self.modes: list[tuple[float, str]] = []  # (vehicle time, mode) at each step
        sim.observers.append(self._step)

    def _step(self, sim: Any) -> None:
        self.points.append((self.vehicle.lat, self.vehicle.lon))
        self.modes.append((sim.clock.now(), sim.autopilot.mode))
        if sim.autopilot.rc_channels[5] > 1700:
            self.modes_while_switch_high.append(sim.autopilot.mode)

    def first_move_after(self, t_s: float) -> float:
        """The vehicle time the mode first changed after ``t_s``."""
        before = next(mode for t, mode in reversed(self.modes) if t <= t_s)
        return next(t for t, mode in self.modes if t > t_s and mode != before)

    def deepest_in(self, zone: str) -> float:
        """How far inside ``zone`` the vehicle ever went, metres (0: never in it)."""
        xy = self.zones.plane.xy([p[0] for p in self.points], [p[1] for p in self.points])
        shape = next(a.shape for a in self.zones.keep_out if a.label == f"keep-out zone {zone!r}")
        inside = shapely.contains_xy(shape, xy[:, 0], xy[:, 1])
        return float(max((shapely.distance(shapely.points(p), shape.exterior) for p in xy[inside]), default=0.0))


def test_the_battery_return_goes_round_the_pier_to_home_not_through_it(lockstep) -> None:
    mission = round_the_pier(limits={**line_mission("x").limits.model_dump(), "battery_min_pct": 20})
    # on the last leg, heading west at the north end: the battery sags under the floor for good (battery_low: rtl, abort)
    sim = lockstep(mission, events=[BatterySag(kind="battery_sag", at_s=75.0, drop_v=1.0, drop_pct=85)])
    track = Track(sim, mission)
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason.startswith("Wait for guards: Battery above floor? battery 14% below 20%; returned to home, ")
    v = track.vehicle
    assert geo.distance(v.lat, v.lon, *LINE_HOME) <= 1.5 + 0.5  # at home, within the acceptance radius (and a stop)
    assert sim.autopilot.mode == "HOLD"  # the executive's own return ends held, not in RTL
    north_of_pier = [p for p in track.points if geo.distance(*LINE_HOME, *p) > 50.0]
    assert north_of_pier, "the return started from the far end"
    assert track.deepest_in("pier") == 0.0  # never inside the pier


def test_a_person_who_hands_back_inside_a_zone_is_left_alone_while_driving_then_brought_out_and_home(lockstep, caplog) -> None:
    mission = round_the_pier()
    # on the first leg (east), a person takes over (switch 6 high, MANUAL) and drives straight on into the moored boat;
    # sticks released at 37 s, the switch back at 38 s: the rover stands ~2 m inside the boat's circle, still in MANUAL (a
    # person's mode: still theirs); at 45 s they hand it back, out of MANUAL (their mode switch to GUIDED)
    takeover = RcTakeover(kind="rc_takeover", at_s=20.0, for_s=18.0, channel=6, pwm=1900, mode="MANUAL")
    throttle = RcInput(kind="rc_input", at_s=20.0, for_s=17.0, channels={3: 1700, 1: 1500})
    sim = lockstep(mission, events=[takeover, throttle])
    sim.at(45.0, lambda s: s.autopilot.set_mode(s.autopilot.profile.modes["GUIDED"]))
    track = Track(sim, mission)
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.ABORTED, outcome.reason
    assert outcome.reason == (
        "Wait for guards: Outside keep-out zones? inside keep-out zone 'moored boat'; returned to home, 53 m by 2 legs around the keep-out zones"
    )
    v = track.vehicle
    assert geo.distance(v.lat, v.lon, *LINE_HOME) <= 2.0 and sim.autopilot.mode == "HOLD"
    # the person won while they drove: MANUAL throughout, and the condition only reported then
    assert set(track.modes_while_switch_high) == {"MANUAL"}
    assert track.first_move_after(38.0) >= 45.0  # nothing commanded after the switch went back, while MANUAL stayed theirs
    assert track.deepest_in("moored boat") > 1.0  # they did drive in
    warnings = [r.getMessage() for r in caplog.records if r.name == "executive.behaviours.failsafe"]
    assert any("moored boat" in w and "a person has the vehicle: judged when they hand back" in w for w in warnings)


def test_a_rover_handed_back_heading_into_a_zone_is_held_before_it_enters(lockstep) -> None:
    # a person drives on past the first waypoint toward the moored boat and hands back at 33 s, 3 m short of it at 1.4 m/s:
    # switch low and their mode switch to GUIDED. It is held at once (it stops in 3.3 m: HOLD coasts, Rover/mode_hold.cpp) and
    # goes home round the boat. (Before this failsafe the resumed leg turned it back, braking in GUIDED, within 0.2 m of the
    # circle: the track alone does not tell the two apart, the reason does.)
    takeover = RcTakeover(kind="rc_takeover", at_s=20.0, for_s=13.0, channel=6, pwm=1900, mode="MANUAL")
    throttle = RcInput(kind="rc_input", at_s=20.0, for_s=13.0, channels={3: 1700, 1: 1500})
    mission = round_the_pier()
    sim = lockstep(mission, events=[takeover, throttle])
    sim.at(33.0, lambda s: s.autopilot.set_mode(s.autopilot.profile.modes["GUIDED"]))
    track = Track(sim, mission)
    outcome = sim.run_to_end(limit_s=300)
    assert track.deepest_in("moored boat") == 0.0  # it stood 0.4 m short of the circle
    assert outcome.reason.startswith(
        "Wait for guards: Outside keep-out zones? heading into keep-out zone 'moored boat': 2.9 m ahead at 1.4 m/s (stops in 3.3 m); returned to home"
    )


def test_a_route_edit_that_would_take_the_rover_through_a_buoy_from_where_it_is_is_refused_and_the_route_kept(lockstep) -> None:
    # the line north (waypoints 25 m apart); a 3 m buoy 44 m north, 13 m east. On leg 2 the operator moves waypoint 2 30 m east:
    # from waypoint 1 the new leg passes 6 m from the buoy, but the rover is already 10 m on, and from there it runs through it
    buoy = point(44.0, 13.0, radius_m=3.0)
    mission = line_mission("line past a buoy", geofence={"keep_out": [{"name": "buoy", "circle": buoy}]})
    sim = lockstep(mission)
    replies: list[Any] = []
    sim.run(until=lambda: sim.runtime.mission_state.legs.leg_index == 1 and geo.distance(*LINE_HOME, *_at(sim)) >= 35.0)
    replies.append(sim.runtime.operator.request("route", source="ctl", operation="offset", waypoint=2, distance_m=30, bearing_deg=90))
    assert not replies[0].ok
    assert "the vehicle -> waypoints[1] (-): crosses keep-out zone 'buoy'" in replies[0].reason
    assert list(sim.runtime.mission_state.legs.route.waypoints) == mission.waypoints  # nothing changed, nothing sent
    assert sim.run_to_end(limit_s=200).status is MissionStatus.COMPLETED


def _at(sim: Any) -> tuple[float, float]:
    return sim.autopilot.vehicle.lat, sim.autopilot.vehicle.lon


def test_on_the_real_ardurover_the_battery_return_went_round_the_pier_and_home() -> None:
    """tests/data/ardurover/round_the_pier-rover-battery-return.tlog: ArduRover 4.7-dev SITL driven by `executive run` of
    round_the_pier.yaml beside it; a ground station sagged the battery (SIM_BATT_VOLTAGE 11.0) on the last leg."""
    mission = load_mission(DATA / "round_the_pier.yaml")
    zones = Zones(mission, Plane(LINE_HOME))
    pier = zones.keep_out[0].shape
    positions, modes = [], []
    for _, msg in records(DATA / "round_the_pier-rover-battery-return.tlog"):
        if msg.get_type() == "GLOBAL_POSITION_INT":
            positions.append((msg.lat / 1e7, msg.lon / 1e7))
        elif msg.get_type() == "HEARTBEAT" and msg.get_srcComponent() == 1:
            mode = next(name for name, number in ROVER_MODES.items() if number == msg.custom_mode)
            if not modes or modes[-1] != mode:
                modes.append(mode)
    xy = zones.plane.xy([p[0] for p in positions], [p[1] for p in positions])
    clearance = min(float(shapely.distance(shapely.points(p), pier)) for p in xy)
    assert clearance >= 3.5  # the track's closest to the pier: 4.0 m (the way's edges keep the 2 m acceptance radius off it)
    assert modes[-4:] == ["GUIDED", "HOLD", "GUIDED", "HOLD"]  # the legs; the hold; the executive's return; held at home
    assert geo.distance(*positions[-1], *LINE_HOME) <= 2.0 + 1.5  # the acceptance radius, and the coast in HOLD


def behind_a_breakwater(capacity_mah: float) -> Mission:
    """Out 220 m east, 240 m north, back west to home's meridian: home lies 240 m due south, but a breakwater 40 m thick
    runs from 400 m west to 200 m east between them, so the way home goes round its east end: about 500 m."""
    wall = [point(100, -400), point(100, 200), point(140, 200), point(140, -400)]
    fields: dict[str, Any] = {
        "waypoints": [point(0, 220, name="east"), point(240, 220, name="north-east"), point(240, 0, name="north")],
        "geofence": {"keep_out": [{"name": "breakwater", "polygon": wall}]},
        "limits": {**line_mission("x").limits.model_dump(), "leg_timeout_s": 400},
        "simulator": {"ekf_ready_after_s": 2, "params": {"BATT_CAPACITY": capacity_mah}},
        "energy": {"nominal_v": 11.1},
    }
    return line_mission("behind a breakwater", **fields)


def test_the_way_home_is_priced_round_the_zones_so_a_pack_that_fits_the_straight_line_home_is_refused(lockstep) -> None:
    """1800 mAh x 11.1 V = 20 Wh, 16 above the 20 % reserve: the straight line home (2.4 Wh, 14 with the route and the
    uncertainty) would fit, the way round the breakwater (the executive's own return, mission/return_path.py) does not."""
    sim = lockstep(behind_a_breakwater(1800.0))
    outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED and not sim.autopilot.armed
    assert "does not fit the battery: needs 7 Wh + 5 Wh home (+/- 6), has 16 Wh above the 20 % reserve" in outcome.reason
