"""The mission guards (RC, distances, limits, heading, battery, geofence), tick by tick: status and why."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from executive.behaviours import (
    AllWaypointsWithin,
    AltitudeWithin,
    BatteryAbove,
    DepthWithin,
    HeadingSane,
    InsideGeofence,
    RcAutoMode,
    RcFresh,
    RcNotTakingOver,
    SpeedWithin,
    TargetWithin,
    inside_geofence,
    position_guards,
    rc_auto_mode,
)
from executive.mission.model import Mission, Range, RcConfig, Waypoint
from executive.world import blackboard
from executive.world.geo import destination
from executive.world.geofence import Geofence
from executive.world.state import Battery, GlobalPosition, HomePosition, RcSwitches, SwitchPosition

HOME = (47.397742, 8.545594)
UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def at(north_m: float, east_m: float = 0.0) -> tuple[float, float]:
    lat, lon = destination(*HOME, 0.0, north_m)
    return destination(lat, lon, 90.0, east_m)


def position(north_m: float = 0.0, east_m: float = 0.0, alt_rel_m: float = 0.0, vn: float = 0.0, ve: float = 0.0) -> GlobalPosition:
    return GlobalPosition(*at(north_m, east_m), alt_rel_m, vn, ve, 0.0, None, 0.0)


def switches(swc: SwitchPosition | None) -> RcSwitches:
    return RcSwitches(UP, MIDDLE, swc, DOWN, 0, 0.0)


def waypoint(north_m: float, east_m: float = 0.0, name: str | None = None) -> Waypoint:
    lat, lon = at(north_m, east_m)
    return Waypoint(lat=lat, lon=lon, name=name)


def battery(volts: float | None, pct: int | None) -> Battery:
    return Battery(volts, None, pct, 0.0)


SQUARE_200 = Geofence(tuple(at(n, e) for n, e in [(-100, -100), (100, -100), (100, 100), (-100, 100)]), max_distance_m=120.0)
SPEED = Range(min=0.1, max=2.0)  # allowed up to 2.3 m/s: 2.0 + max(0.3, 10 %)
DEPTH = Range(min=0.0, max=100.0)
ALTITUDE = Range(min=2.0, max=100.0)
TAKEOVER = (1500,) * 5 + (1900, 1500, 1500)

CASES = [
    # guard, blackboard facts (the Vehicle fixture's spelling; mission__target too), expected status, exact feedback
    (lambda: RcAutoMode(), {}, Status.SUCCESS, "ok"),  # no RC report: not a take-over
    (lambda: RcAutoMode(), {"rc__channels": (1500,) * 8}, Status.SUCCESS, "ok"),
    (lambda: RcAutoMode(), {"rc__channels": TAKEOVER}, Status.FAILURE, "RC channel 6 high (1900 µs): manual take-over"),
    (lambda: RcAutoMode(), {"rc__channels": (0,) * 8}, Status.SUCCESS, "ok"),  # transmitter gone: RcFresh's business
    (
        lambda: RcAutoMode(takeover_channel=3, takeover_above_us=1600),
        {"rc__channels": (1500, 1500, 1650)},
        Status.FAILURE,
        "RC channel 3 high (1650 µs): manual take-over",
    ),
    (lambda: RcAutoMode(), {"rc__channels": (1500,) * 8, "rc__switches": switches(UP)}, Status.SUCCESS, "ok"),  # mavlink ignores switch C
    (lambda: RcAutoMode("can"), {}, Status.FAILURE, "no RC switch C position yet"),
    (lambda: RcAutoMode("can"), {"rc__switches": switches(None)}, Status.FAILURE, "no RC switch C position yet"),
    (lambda: RcAutoMode("can"), {"rc__switches": switches(MIDDLE)}, Status.SUCCESS, "ok"),
    (lambda: RcAutoMode("can"), {"rc__switches": switches(UP)}, Status.FAILURE, "RC switch C UP (MANUAL), not MIDDLE (AUTO)"),
    (lambda: RcAutoMode("can"), {"rc__switches": switches(DOWN)}, Status.FAILURE, "RC switch C DOWN (aux mode), not MIDDLE (AUTO)"),
    (lambda: RcAutoMode("can"), {"rc__switches": switches(MIDDLE), "rc__channels": TAKEOVER}, Status.SUCCESS, "ok"),  # can ignores channels
    (lambda: RcFresh(), {}, Status.FAILURE, "no RC report yet"),
    (lambda: RcFresh(), {"rc__fresh": True, "rc__stale_reason": ""}, Status.SUCCESS, "ok"),
    (
        lambda: RcFresh(),
        {"rc__fresh": False, "rc__stale_reason": "RC transmitter gone (every channel 0)"},
        Status.FAILURE,
        "RC transmitter gone (every channel 0)",
    ),
    (lambda: RcFresh(), {"rc__fresh": False, "rc__stale_reason": ""}, Status.FAILURE, "RC is stale"),
    (lambda: TargetWithin(5000.0), {"mission__target": waypoint(4900)}, Status.FAILURE, "no position"),
    (lambda: TargetWithin(5000.0), {"vehicle__position": position()}, Status.FAILURE, "no target: no leg is active"),
    (lambda: TargetWithin(5000.0), {"vehicle__position": position(), "mission__target": waypoint(4900)}, Status.SUCCESS, "ok"),
    (
        lambda: TargetWithin(5000.0),
        {"vehicle__position": position(), "mission__target": waypoint(5100)},
        Status.FAILURE,
        "target is 5100 m away, over 5000 m",
    ),
    (
        lambda: TargetWithin(5000.0),
        {"vehicle__position": position(3000), "mission__target": waypoint(-3000)},
        Status.FAILURE,
        "target is 6000 m away, over 5000 m",
    ),
    (lambda: AllWaypointsWithin([waypoint(10)], 1000.0), {}, Status.FAILURE, "no position"),
    (lambda: AllWaypointsWithin([waypoint(500), waypoint(0, 999)], 1000.0), {"vehicle__position": position()}, Status.SUCCESS, "ok"),
    (
        lambda: AllWaypointsWithin([waypoint(500), waypoint(1200), waypoint(-1500)], 1000.0),
        {"vehicle__position": position()},
        Status.FAILURE,
        "waypoint 2 is 1200 m away, over 1000 m",
    ),
    (
        lambda: AllWaypointsWithin([waypoint(0), waypoint(0, 1001, "far")], 1000.0),
        {"vehicle__position": position()},
        Status.FAILURE,
        "waypoint 2 'far' is 1001 m away, over 1000 m",
    ),
    (lambda: AllWaypointsWithin([], 1000.0), {"vehicle__position": position()}, Status.SUCCESS, "ok"),
    (lambda: SpeedWithin(SPEED), {}, Status.FAILURE, "speed not reported yet (no GLOBAL_POSITION_INT, no VFR_HUD)"),  # unknown: not healthy
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position(vn=2.0)}, Status.SUCCESS, "ok"),
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position(vn=1.6, ve=1.6)}, Status.SUCCESS, "ok"),  # 2.26 m/s: inside the tolerance
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position(vn=2.4)}, Status.FAILURE, "speed 2.4 m/s over the limit 2 m/s"),
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position(vn=1.8, ve=1.8)}, Status.FAILURE, "speed 2.5 m/s over the limit 2 m/s"),
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position()}, Status.SUCCESS, "ok"),  # slower than min: never a failure
    (lambda: SpeedWithin(SPEED), {"vehicle__ground_speed_m_s": 3.0}, Status.FAILURE, "speed 3.0 m/s over the limit 2 m/s"),  # VFR_HUD alone
    (lambda: SpeedWithin(SPEED), {"vehicle__ground_speed_m_s": 2.2}, Status.SUCCESS, "ok"),
    (lambda: SpeedWithin(SPEED), {"vehicle__position": position(vn=1.0), "vehicle__ground_speed_m_s": 3.0}, Status.SUCCESS, "ok"),  # EKF first
    (lambda: SpeedWithin(Range(min=10, max=20)), {"vehicle__position": position(vn=21.9)}, Status.SUCCESS, "ok"),  # 10 % of 20
    (lambda: SpeedWithin(Range(min=10, max=20)), {"vehicle__position": position(vn=22.1)}, Status.FAILURE, "speed 22.1 m/s over the limit 20 m/s"),
    (lambda: DepthWithin(DEPTH), {}, Status.FAILURE, "no position"),
    (lambda: DepthWithin(DEPTH), {"vehicle__position": position(alt_rel_m=-42.0)}, Status.SUCCESS, "ok"),
    (lambda: DepthWithin(DEPTH), {"vehicle__position": position(alt_rel_m=0.3)}, Status.SUCCESS, "ok"),  # a wave over the surface
    (lambda: DepthWithin(DEPTH), {"vehicle__position": position(alt_rel_m=1.0)}, Status.FAILURE, "depth -1.0 m outside [0, 100] m"),
    (lambda: DepthWithin(DEPTH), {"vehicle__position": position(alt_rel_m=-100.4)}, Status.SUCCESS, "ok"),
    (lambda: DepthWithin(DEPTH), {"vehicle__position": position(alt_rel_m=-101.0)}, Status.FAILURE, "depth 101.0 m outside [0, 100] m"),
    (
        lambda: DepthWithin(Range(min=5, max=10), tolerance_m=0.0),
        {"vehicle__position": position(alt_rel_m=-4.9)},
        Status.FAILURE,
        "depth 4.9 m outside [5, 10] m",
    ),
    (lambda: AltitudeWithin(ALTITUDE), {}, Status.FAILURE, "no altitude above the seabed (no valid rangefinder reading)"),
    (lambda: AltitudeWithin(ALTITUDE), {"vehicle__altitude_above_bottom_m": 12.5}, Status.SUCCESS, "ok"),
    (lambda: AltitudeWithin(ALTITUDE), {"vehicle__altitude_above_bottom_m": 1.6}, Status.SUCCESS, "ok"),
    (
        lambda: AltitudeWithin(ALTITUDE),
        {"vehicle__altitude_above_bottom_m": 1.4},
        Status.FAILURE,
        "altitude 1.4 m above the seabed outside [2, 100] m",
    ),
    (
        lambda: AltitudeWithin(ALTITUDE),
        {"vehicle__altitude_above_bottom_m": 101.0},
        Status.FAILURE,
        "altitude 101.0 m above the seabed outside [2, 100] m",
    ),
    (lambda: HeadingSane(), {}, Status.SUCCESS, "not judged yet"),
    (lambda: HeadingSane(), {"heading__ok": True, "heading__bias_deg": 2.0}, Status.SUCCESS, "ok"),
    (
        lambda: HeadingSane(),
        {"heading__ok": False, "heading__bias_deg": 20.4, "heading__reason": "compass reads +20.4° off the course over ground"},
        Status.FAILURE,
        "compass reads +20.4° off the course over ground",
    ),
    (
        lambda: HeadingSane(),
        {"heading__ok": False, "heading__reason": "compass rejected in 25% of its readings over 5 s"},
        Status.FAILURE,
        "compass rejected in 25% of its readings over 5 s",
    ),
    (lambda: HeadingSane(), {"heading__ok": False}, Status.FAILURE, "the heading filter does not trust the compass"),
    (lambda: BatteryAbove(20.0, 10.5), {}, Status.FAILURE, "battery not reported yet (no SYS_STATUS)"),  # unknown: not healthy
    (lambda: BatteryAbove(20.0, 10.5), {"vehicle__battery": battery(12.0, 50)}, Status.SUCCESS, "ok"),
    (lambda: BatteryAbove(20.0, 10.5), {"vehicle__battery": battery(12.0, 20)}, Status.SUCCESS, "ok"),  # at the floor is not below it
    (lambda: BatteryAbove(20.0, 10.5), {"vehicle__battery": battery(12.0, 19)}, Status.FAILURE, "battery 19% below 20%"),
    (lambda: BatteryAbove(20.0, 10.5), {"vehicle__battery": battery(10.2, 50)}, Status.FAILURE, "battery 10.20 V below 10.5 V"),
    (
        lambda: BatteryAbove(20.0, 10.5),
        {"vehicle__battery": battery(None, None)},
        Status.FAILURE,
        "battery remaining % (battery_remaining) and voltage unknown: the floor cannot be checked",
    ),
    (
        lambda: BatteryAbove(20.0, 10.5),
        {"vehicle__battery": battery(12.0, None)},
        Status.FAILURE,
        "battery remaining % (battery_remaining) unknown: the floor cannot be checked",
    ),
    (lambda: BatteryAbove(20.0, 10.5), {"vehicle__battery": battery(None, 10)}, Status.FAILURE, "battery 10% below 20%"),
    (lambda: BatteryAbove(20.0), {"vehicle__battery": battery(None, 30)}, Status.SUCCESS, "ok"),  # voltage not checked: not missed
    (lambda: BatteryAbove(None, 10.5), {"vehicle__battery": battery(12.0, 1)}, Status.SUCCESS, "ok"),
    (lambda: BatteryAbove(None, None), {"vehicle__battery": battery(1.0, 0)}, Status.SUCCESS, "ok"),
    (lambda: InsideGeofence(SQUARE_200, HOME), {}, Status.FAILURE, "no position"),
    (lambda: InsideGeofence(SQUARE_200, HOME), {"vehicle__position": position(50, 50)}, Status.SUCCESS, "ok"),
    (lambda: InsideGeofence(SQUARE_200, HOME), {"vehicle__position": position(50, 130)}, Status.FAILURE, "30 m outside the fence polygon"),
    (lambda: InsideGeofence(SQUARE_200, HOME), {"vehicle__position": position(90, 90)}, Status.FAILURE, "127 m from home, over the fence's 120 m"),
    (
        lambda: InsideGeofence(SQUARE_200, HOME),  # the autopilot's home wins over the mission's
        {"vehicle__position": position(90, 90), "vehicle__home": HomePosition(*at(80, 80), 0.0, 0.0)},
        Status.SUCCESS,
        "ok",
    ),
    (
        lambda: InsideGeofence(SQUARE_200, HOME),
        {"vehicle__position": position(0, 0), "vehicle__home": HomePosition(*at(-90, -90), 0.0, 0.0)},
        Status.FAILURE,
        "127 m from home, over the fence's 120 m",
    ),
    (lambda: InsideGeofence(SQUARE_200), {"vehicle__position": position(0, 0)}, Status.FAILURE, "no home to measure the distance from"),
    (lambda: InsideGeofence(Geofence(SQUARE_200.polygon)), {"vehicle__position": position(0, 0)}, Status.SUCCESS, "ok"),  # no distance rule
]


@pytest.fixture
def facts(vehicle):
    """Sets blackboard facts, including /mission/target (which the Vehicle fixture does not write)."""
    mission = blackboard.writer("test mission", ["/mission/target"])

    def put(**values: object) -> None:
        target = values.pop("mission__target", None)
        if target is not None:
            mission.set("/mission/target", target)
        vehicle.set(**values)

    return put


@pytest.mark.parametrize(("make", "given", "expected", "why"), CASES)
def test_guard(harness, facts, make, given, expected, why):
    facts(**given)
    node = make()
    h = harness(node)
    assert h.tick() == expected
    assert node.feedback_message == why
    assert h.link.take() == []  # a guard never sends anything


def test_a_note_does_not_outlive_its_tick(harness, facts):
    node = BatteryAbove(20.0)
    h = harness(node)
    notes = []
    for b in (battery(12.0, 50), battery(12.0, 10), battery(12.0, 50)):
        facts(vehicle__battery=b)
        h.tick()
        notes.append(node.feedback_message)
    assert notes == ["ok", "battery 10% below 20% for 0.0/2 s: not yet", "ok"]  # debounced


def test_rc_guards_say_whether_a_person_has_the_vehicle():
    assert RcAutoMode.pilot_in_control and RcNotTakingOver.pilot_in_control
    assert not RcFresh.pilot_in_control  # stale RC: nobody has it, the executive holds the vehicle


@pytest.mark.parametrize(
    ("rc", "given", "expected"),
    [
        (RcConfig(), {"rc__channels": TAKEOVER}, Status.FAILURE),
        (RcConfig(takeover_channel=7), {"rc__channels": TAKEOVER}, Status.SUCCESS),
        (RcConfig(takeover_above_us=1950), {"rc__channels": TAKEOVER}, Status.SUCCESS),
        (RcConfig(source="can"), {"rc__channels": TAKEOVER, "rc__switches": switches(MIDDLE)}, Status.SUCCESS),
        (RcConfig(source="can"), {"rc__channels": (1500,) * 8, "rc__switches": switches(UP)}, Status.FAILURE),
    ],
)
def test_rc_auto_mode_from_the_missions_rc_section(harness, facts, rc, given, expected):
    facts(**given)
    node = rc_auto_mode(rc)
    assert harness(node).tick() == expected


def test_rc_auto_mode_follows_switch_c_tick_by_tick(harness, facts):
    h = harness(RcAutoMode("can"))
    statuses = []
    for swc, dt in ((UP, 0.1), (MIDDLE, 0.1), (MIDDLE, 0.1), (DOWN, 0.1), (MIDDLE, 0.1), (MIDDLE, 1.0), (None, 0.1)):
        facts(rc__switches=switches(swc))
        statuses.append(h.tick(dt))
    # back in AUTO after being out of it: AUTO for 1 s first (a bouncing switch does not restart the work)
    assert statuses == [Status.FAILURE, Status.SUCCESS, Status.SUCCESS, Status.FAILURE, Status.FAILURE, Status.SUCCESS, Status.FAILURE]


def test_all_waypoints_within_follows_the_vehicle(harness, facts):
    """The route 900 m north; the vehicle backs away south 50 m a tick: the verdict turns past 1000 m."""
    h = harness(AllWaypointsWithin([waypoint(900), waypoint(0)], 1000.0))
    statuses = []
    for south in (0, 50, 100, 150, 100):
        facts(vehicle__position=position(-south))
        statuses.append(h.tick())
    assert statuses == [Status.SUCCESS, Status.SUCCESS, Status.SUCCESS, Status.FAILURE, Status.SUCCESS]
    assert h.root.feedback_message == "ok"


def test_all_waypoints_within_measures_a_long_route_once_while_the_vehicle_stays(harness, facts, monkeypatch):
    route = [waypoint(n % 500, n % 300) for n in range(1000)]
    calls = []
    real = position_guards.distance
    monkeypatch.setattr(position_guards, "distance", lambda *a: calls.append(a) or real(*a))
    h = harness(AllWaypointsWithin(route, 1000.0))
    facts(vehicle__position=position())
    assert h.tick() == Status.SUCCESS
    assert len(calls) == 1000
    for step in range(1, 4):
        facts(vehicle__position=position(step))
        assert h.tick() == Status.SUCCESS
    assert len(calls) == 1003  # one distance a tick: how far the vehicle went from where it was measured
    facts(vehicle__position=position(-1100))
    assert h.tick() == Status.FAILURE
    assert h.root.feedback_message == "waypoint 1 is 1100 m away, over 1000 m"
    assert len(calls) == 1005  # moved too far to trust the verdict: measured again, up to the first offender


def test_inside_geofence_from_the_mission(square_mission):
    assert inside_geofence(square_mission) is None
    fenced = Mission.model_validate(
        square_mission.model_dump() | {"home": {"lat": HOME[0], "lon": HOME[1]}, "geofence": {"max_distance_from_home_m": 500.0}}
    )
    node = inside_geofence(fenced)
    assert node is not None
    assert (node.fence, node.mission_home) == (Geofence(max_distance_m=500.0), HOME)


def test_inside_geofence_tick_by_tick(harness, facts):
    h = harness(InsideGeofence(SQUARE_200, HOME))
    seen = []
    for north, east, dt in ((0, 0, 0.1), (50, 50, 0.1), (0, 110, 0.1), (0, 90, 0.1), (0, 90, 2.0), (0, 130, 0.1), (0, 0, 0.1)):
        facts(vehicle__position=position(north, east))
        seen.append((h.tick(dt), h.root.feedback_message))
    assert seen == [
        (Status.SUCCESS, "ok"),
        (Status.SUCCESS, "ok"),
        (Status.FAILURE, "10 m outside the fence polygon"),  # at once
        (Status.FAILURE, "recovering (holds for 0.0/2 s)"),  # back inside: for 2 s first
        (Status.SUCCESS, "ok"),
        (Status.FAILURE, "30 m outside the fence polygon"),
        (Status.FAILURE, "recovering (holds for 0.0/2 s)"),
    ]
