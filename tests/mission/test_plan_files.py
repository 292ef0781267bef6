"""QGroundControl .plan and Mission Planner QGC WPL 110 files: import, export, round trips, located errors and warnings."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.mission.errors import MissionError
from executive.mission.formats.plan_files import export_plan, export_waypoints, import_file, import_plan, import_text, import_waypoints
from executive.mission.loader import load_mission_text
from executive.mission.model import VTOL_MIN_ACCEPTANCE_RADIUS_M, Mission
from executive.mission.rules import cross_field_errors

PLANS = Path(__file__).parents[1] / "data" / "plans"
BOAT_SURVEY = PLANS / "boat_survey.plan"
ROVER_BLOCK = PLANS / "rover_block.plan"
CMAC = PLANS / "cmac_rover.waypoints"
DEG, METRE = 1e-7, 0.01


# -- helpers -----------------------------------------------------------------------------------


def text_at(text: str, line: int, column: int) -> str:
    """The rest of the line at a 1-based position."""
    return text.splitlines()[line - 1][column - 1 :]


def plan_route(plan: dict[str, Any]) -> list[tuple[float, float, float, float | None]]:
    """What matters of a plan's route: each waypoint (lat, lon, alt above home, speed in force), survey items included."""
    route: list[tuple[float, float, float, float | None]] = []
    speed: float | None = None

    def walk(items: list[dict[str, Any]]) -> None:
        nonlocal speed
        for item in items:
            if item["type"] == "ComplexItem":
                walk(item.get("TransectStyleComplexItem", {}).get("Items", []))
            elif item["command"] == 178 and item["params"][1] > 0:
                speed = item["params"][1]
            elif item["command"] == 16:
                route.append((item["params"][4], item["params"][5], item["params"][6], speed))

    walk(plan["mission"]["items"])
    return route


def plan_fence(plan: dict[str, Any]) -> tuple[list[list[float]] | None, list[tuple[list[float], float]]]:
    """The first inclusion polygon and the inclusion circles of a plan."""
    fence = plan.get("geoFence", {})
    polygon = next((p["polygon"] for p in fence.get("polygons", []) if p["inclusion"]), None)
    return polygon, [(c["circle"]["center"], c["circle"]["radius"]) for c in fence.get("circles", []) if c["inclusion"]]


def wpl_route(text: str) -> tuple[tuple[float, float], list[tuple[float, float, float, float | None]]]:
    """What matters of a WPL file: home (lat, lon) and each waypoint (lat, lon, alt, speed in force)."""
    rows = [line.split("\t") for line in text.splitlines()[1:] if line.strip()]
    home = (float(rows[0][8]), float(rows[0][9]))
    route, speed = [], None
    for row in rows[1:]:
        if int(row[3]) == 178:
            speed = float(row[5])
        elif int(row[3]) == 16:
            route.append((float(row[8]), float(row[9]), float(row[10]), speed))
    return home, route


def assert_routes_equal(got: list[tuple[float, ...]], want: list[tuple[float, ...]]) -> None:
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert g[:2] == pytest.approx(w[:2], abs=DEG) and g[2] == pytest.approx(w[2], abs=METRE) and g[3] == pytest.approx(w[3], abs=METRE)


def plan_text(**mission: Any) -> str:
    """A minimal valid .plan (a rover, one waypoint), with ``mission`` keys replaced."""
    base: dict[str, Any] = {
        "cruiseSpeed": 2,
        "firmwareType": 3,
        "hoverSpeed": 5,
        "items": [
            {"autoContinue": True, "command": 16, "doJumpId": 1, "frame": 3, "params": [0, 0, 0, None, 47.3981, 8.5456, 0], "type": "SimpleItem"}
        ],
        "plannedHomePosition": [47.3977419, 8.545594, 488.0],
        "vehicleType": 10,
        "version": 2,
    }
    return json.dumps({"fileType": "Plan", "groundStation": "QGroundControl", "mission": base | mission, "version": 1}, indent=4)


def errors_of(call: Any, *args: Any, **kwargs: Any) -> list[str]:
    with pytest.raises(MissionError) as info:
        call(*args, **kwargs)
    return [str(e) for e in info.value.errors]


# -- the sample files --------------------------------------------------------------------------


def test_a_qgroundcontrol_survey_plan_imports_what_a_mission_can_hold():
    imported = import_file(BOAT_SURVEY)
    mission = imported.mission
    assert mission == load_mission_text(imported.yaml_text, "again.yaml")  # the YAML is the mission, and it validates
    assert (mission.name, mission.vehicle) == ("boat_survey", "boat")  # from the file name and vehicleType 11
    assert (mission.home.lat, mission.home.lon) == (47.3977419, 8.545594)
    assert mission.geofence is not None and len(mission.geofence.polygon) == 5
    assert mission.geofence.max_distance_from_home_m == 400.0  # the inclusion circle around home
    plan = json.loads(BOAT_SURVEY.read_text())
    want = plan_route(plan)
    got = [(wp.lat, wp.lon, wp.alt_m, wp.speed_m_s) for wp in mission.waypoints]
    assert_routes_equal(got, want)
    assert len(got) == 3 + 6  # three plain waypoints and the survey's six transect ends (the loiter is not one)


def test_what_a_plan_cannot_give_is_reported_where_it_is():
    text = BOAT_SURVEY.read_text()
    warnings = {w.field: w for w in import_file(BOAT_SURVEY).warnings}
    expected = {
        "mission.items[3]": ("DO_SET_SERVO (183)", "{"),
        "mission.items[4]": ("NAV_LOITER_TIME (19)", "{"),
        "mission.items[5].params[0]": ("hold time 5 s", "5"),
        "mission.items[5].params[1]": ("acceptance radius 3 m", "3"),
        "mission.items[6]": ("survey: imported as the 8 mission items", "{"),
        "mission.items[6].TransectStyleComplexItem.Items[0]": ("DO_SET_CAM_TRIGG_DIST (206) and 1 more", "{"),
        "mission.items[7]": ("NAV_RETURN_TO_LAUNCH (20)", "{"),
    }
    assert set(warnings) == set(expected)
    for field, (message, starts) in expected.items():
        warning = warnings[field]
        assert message in warning.message and warning.file == str(BOAT_SURVEY)
        assert text_at(text, warning.line, warning.column).startswith(starts), (field, warning)
    # and the mission file says so at its top
    assert "# Not imported" in import_file(BOAT_SURVEY).yaml_text.split("version: 1")[0]


def test_a_mission_planner_file_imports_with_home_from_line_0():
    imported = import_file(CMAC, vehicle="rover")
    mission = imported.mission
    assert (mission.home.lat, mission.home.lon) == (-35.363262, 149.165237)
    assert [wp.speed_m_s for wp in mission.waypoints] == [2.5] * 5
    home, want = wpl_route(CMAC.read_text())
    assert home == (mission.home.lat, mission.home.lon)
    assert_routes_equal([(wp.lat, wp.lon, wp.alt_m, wp.speed_m_s) for wp in mission.waypoints], want)
    located = {(w.line, w.column, w.field): w.message for w in imported.warnings}
    assert located == {
        (8, 1, "item[6]"): "not imported: DO_SET_SERVO (183): a mission file holds waypoints and their speeds only",
        (10, 1, "item[8]"): "not imported: NAV_RETURN_TO_LAUNCH (20): a mission file holds waypoints and their speeds only",
    }


def test_a_mission_planner_file_needs_the_vehicle_kind():
    assert errors_of(import_file, CMAC) == [
        f"{CMAC}:1:1: (header): a .waypoints file does not say which vehicle it is for: pass --vehicle",
    ]


# -- round trips -------------------------------------------------------------------------------


@pytest.mark.parametrize("path", [BOAT_SURVEY, ROVER_BLOCK], ids=lambda p: p.name)
def test_plan_to_mission_to_plan_keeps_what_matters(path):
    original = json.loads(path.read_text())
    exported = export_plan(import_file(path).mission)
    again = json.loads(exported.text)
    assert exported.warnings == ()
    assert_routes_equal(plan_route(again), plan_route(original))
    assert again["mission"]["plannedHomePosition"][:2] == original["mission"]["plannedHomePosition"][:2]
    assert again["mission"]["vehicleType"] == original["mission"]["vehicleType"]
    assert plan_fence(again) == plan_fence(original)
    # QGroundControl 4's shape: sorted keys, doJumpIds from 1, a relative-altitude waypoint mode
    items = again["mission"]["items"]
    assert [i["doJumpId"] for i in items] == list(range(1, len(items) + 1))
    assert all(list(i) == sorted(i) and i["type"] == "SimpleItem" for i in items)
    assert {i["AltitudeMode"] for i in items if i["command"] == 16} == {1}


def test_waypoints_to_mission_to_waypoints_keeps_what_matters():
    original = CMAC.read_text()
    again = export_waypoints(import_file(CMAC, vehicle="rover").mission).text
    assert again.startswith("QGC WPL 110\n0\t1\t0\t16\t")
    home, route = wpl_route(again)
    want_home, want_route = wpl_route(original)
    assert home == want_home
    assert_routes_equal(route, want_route)
    assert all(len(line.split("\t")) == 12 for line in again.splitlines()[1:])


def test_a_mission_export_imports_back_equal(minimal_yaml):
    mission = load_mission_text(minimal_yaml, "m.yaml")
    for exported, reader in ((export_plan(mission), import_plan), (export_waypoints(mission), import_waypoints)):
        back = reader(exported.text, "x", vehicle="rover", name=mission.name).mission
        assert back.waypoints == mission.waypoints


def _carry_speeds(mission: Mission) -> list[float | None]:
    """Each waypoint's speed as a DO_CHANGE_SPEED sequence says it: an unset speed after a set one keeps it."""
    speeds, speed = [], None
    for wp in mission.waypoints:
        speed = wp.speed_m_s if wp.speed_m_s is not None else speed
        speeds.append(speed)
    return speeds


def _kept_speeds(mission: Mission) -> list[tuple[str, int, str]]:
    """The waypoints whose unset speed an export must report: a set speed before them stays in force."""
    set_before = [any(w.speed_m_s is not None for w in mission.waypoints[:i]) for i in range(len(mission.waypoints))]
    return [("waypoints", i, "speed_m_s") for i, wp in enumerate(mission.waypoints) if wp.speed_m_s is None and set_before[i]]


@st.composite
def missions(draw: st.DrawFn) -> Mission:
    """Valid missions of every kind near a random place: waypoints, maybe a home, a geofence, speeds, sub depths and altitudes."""
    kind = draw(st.sampled_from(["rover", "boat", "sub", "vtol"]))
    lat0, lon0 = draw(st.floats(-80.0, 80.0)), draw(st.floats(-179.0, 179.0))
    near = st.floats(-0.003, 0.003)  # any two points under 1000 m apart (limits.max_goal_distance_m from home): 0.006° is 667 m
    waypoints = []
    for _ in range(draw(st.integers(1, 6))):
        wp: dict[str, Any] = {"lat": lat0 + draw(near), "lon": lon0 + draw(near)}
        if draw(st.booleans()):
            wp["speed_m_s"] = draw(st.floats(0.1, 1.0 if kind == "sub" else 5.0))  # a sub's default limit: 1 m/s
        if kind == "sub":
            mode = draw(st.sampled_from([None, "depth", "altitude"]))
            if mode == "depth":
                wp |= {"control_mode": "depth", "depth_m": draw(st.floats(0.0, 100.0))}
            elif mode == "altitude":
                wp |= {"control_mode": "altitude", "altitude_m": draw(st.floats(2.0, 100.0))}
            else:
                wp["alt_m"] = draw(st.floats(0.0, 10.0))  # a sub's altitude below zero is a depth
        elif kind == "vtol":  # within the default limits.alt_m, or 0: flown at the height it is at
            wp["alt_m"] = draw(st.just(0.0) | st.floats(10.0, 120.0))
        else:
            wp["alt_m"] = draw(st.floats(-50.0, 500.0))
        waypoints.append(wp)
    doc: dict[str, Any] = {"version": 1, "name": "round trip", "vehicle": kind, "waypoints": waypoints}
    if draw(st.booleans()):
        doc["home"] = {"lat": lat0 + draw(near), "lon": lon0 + draw(near)}
    fence: dict[str, Any] = {}
    if draw(st.booleans()):
        d = 0.01
        fence["polygon"] = [{"lat": lat0 + a, "lon": lon0 + b} for a, b in ((-d, -d), (d, -d), (d, d), (-d, d))]
    if "home" in doc and draw(st.booleans()):
        fence["max_distance_from_home_m"] = draw(st.floats(2000.0, 10_000.0))
    if draw(st.booleans()):  # keep-out zones 3 km off the route, an inclusion circle holding it
        away = [{"lat": lat0 - 0.03 + a, "lon": lon0 + b} for a, b in ((0.0, 0.0), (0.001, 0.0), (0.0, 0.001))]
        fence["keep_out"] = [{"polygon": away}, {"circle": {"lat": lat0 + 0.03, "lon": lon0, "radius_m": draw(st.floats(1.0, 300.0))}}]
        fence["inclusion"] = [{"circle": {"lat": lat0 + 0.000123, "lon": lon0, "radius_m": 3000.0}}]  # not on a home: that is a distance
    if draw(st.booleans()):
        doc["rally_points"] = [{"lat": lat0 + draw(near), "lon": lon0 + draw(near), "alt_m": draw(st.floats(0.0, 100.0))}]
    if fence:
        doc["geofence"] = fence
    if kind == "vtol":
        doc["limits"] = {"acceptance_radius_m": VTOL_MIN_ACCEPTANCE_RADIUS_M}
    else:  # legs of up to 1.3 km at 0.1 m/s
        doc["limits"] = {"leg_timeout_s": 86400.0}
    mission = Mission.model_validate(doc)
    assert cross_field_errors(mission) == []
    return mission


def assert_missions_equal(back: Mission, mission: Mission, *, fence: bool) -> None:
    assert back.vehicle == mission.vehicle
    assert (back.home is None) == (mission.home is None)
    if mission.home is not None:
        assert (back.home.lat, back.home.lon) == pytest.approx((mission.home.lat, mission.home.lon), abs=DEG)
    assert len(back.waypoints) == len(mission.waypoints)
    for b, w, speed in zip(back.waypoints, mission.waypoints, _carry_speeds(mission), strict=True):
        assert (b.lat, b.lon) == pytest.approx((w.lat, w.lon), abs=DEG)
        assert b.alt_m == pytest.approx(w.alt_m, abs=METRE)
        assert b.speed_m_s == pytest.approx(speed, abs=METRE)
        assert (b.control_mode, b.depth_m is None, b.altitude_m is None) == (w.control_mode, w.depth_m is None, w.altitude_m is None)
        assert (b.depth_m or 0.0, b.altitude_m or 0.0) == pytest.approx((w.depth_m or 0.0, w.altitude_m or 0.0), abs=METRE)
    if fence:
        assert back.geofence == mission.geofence
        assert back.rally_points == mission.rally_points  # JSON carries a float exactly


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_random_missions_round_trip_through_a_plan(mission):
    exported = export_plan(mission)
    back = import_plan(exported.text, "x.plan", name=mission.name).mission
    assert [p for p, _ in exported.warnings] == [*_kept_speeds(mission), *([("home",)] if mission.home is None else [])]
    if mission.home is None:  # the plan's planned home is then the first waypoint, and comes back as the home
        assert (back.home.lat, back.home.lon) == (mission.waypoints[0].lat, mission.waypoints[0].lon)
        back = back.model_copy(update={"home": None})
    assert_missions_equal(back, mission, fence=True)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_random_missions_round_trip_through_a_waypoints_file(mission):
    exported = export_waypoints(mission)
    back = import_waypoints(exported.text, "x.waypoints", vehicle=mission.vehicle, name=mission.name).mission
    home_at_zero = mission.home is not None and round(mission.home.lat, 8) == round(mission.home.lon, 8) == 0.0
    if home_at_zero:  # Mission Planner's "no home"
        mission = mission.model_copy(update={"home": None})
    assert_missions_equal(back, mission, fence=False)
    expected = [
        *_kept_speeds(mission),
        *([("home",)] if home_at_zero else []),
        *([("geofence",)] if mission.geofence is not None else []),
        *([("rally_points",)] if mission.rally_points else []),
    ]
    assert [p for p, _ in exported.warnings] == expected


# -- what maps how -----------------------------------------------------------------------------


def test_a_sub_keeps_depths_and_altitudes_above_the_seabed():
    mission = Mission.model_validate(
        {
            "version": 1,
            "name": "dive",
            "vehicle": "sub",
            "tree": "auv_survey",
            "waypoints": [
                {"lat": 44.1, "lon": 9.8, "depth_m": 12.5, "control_mode": "depth"},
                {"lat": 44.1001, "lon": 9.8, "altitude_m": 4.0, "control_mode": "altitude"},
                {"lat": 44.1002, "lon": 9.8, "depth_m": 0.0, "control_mode": "depth"},
            ],
        }
    )
    rows = [(i["frame"], i["params"][6]) for i in json.loads(export_plan(mission).text)["mission"]["items"]]
    assert rows == [(3, -12.5), (10, 4.0), (3, -0.0)]  # ArduSub: below zero is a depth; terrain frame is above the seabed
    assert import_plan(export_plan(mission).text, "x", name="dive").mission.waypoints == mission.waypoints
    assert import_waypoints(export_waypoints(mission).text, "x", vehicle="sub", name="dive").mission.waypoints == mission.waypoints


def test_an_amsl_altitude_becomes_one_above_home_with_a_warning():
    item = {"autoContinue": True, "command": 16, "doJumpId": 1, "frame": 0, "params": [0, 0, 0, None, 47.3981, 8.5456, 518.0], "type": "SimpleItem"}
    imported = import_plan(plan_text(items=[item], vehicleType=20), "v.plan")
    assert imported.mission.vehicle == "vtol" and imported.mission.waypoints[0].alt_m == pytest.approx(30.0)
    assert [w.message for w in imported.warnings] == ["altitude 518 m above mean sea level imported as 30 m above home (home at 488 m)"]


def test_a_speed_above_the_default_limits_widens_them_with_a_warning():
    speed = {"autoContinue": True, "command": 178, "doJumpId": 1, "frame": 2, "params": [1, 8, -1, 0, 0, 0, 0], "type": "SimpleItem"}
    items = [speed, *json.loads(plan_text())["mission"]["items"]]
    imported = import_plan(plan_text(items=items), "fast.plan")
    assert imported.mission.waypoints[0].speed_m_s == 8.0
    assert imported.mission.limits.speed_m_s.max == 8.0
    assert [(w.field, w.message) for w in imported.warnings] == [
        ("mission.items[0].params[1]", "speed 8 m/s is outside the default limits: limits.speed_m_s.max set to it")
    ]


def test_a_fence_circle_not_around_home_and_a_second_inclusion_polygon_are_inclusion_zones():
    square = [[47.39, 8.54], [47.41, 8.54], [47.41, 8.56], [47.39, 8.56]]
    fence = {
        "circles": [{"circle": {"center": [47.40, 8.55], "radius": 300}, "inclusion": True, "version": 1}],
        "polygons": [{"inclusion": True, "polygon": square, "version": 1}, {"inclusion": True, "polygon": square, "version": 1}],
        "version": 2,
    }
    text = json.dumps(json.loads(plan_text()) | {"geoFence": fence}, indent=4)
    imported = import_plan(text, "f.plan")
    geofence = imported.mission.geofence
    assert geofence.polygon is not None and geofence.max_distance_from_home_m is None
    assert [(z.circle.lat, z.circle.lon, z.circle.radius_m) if z.circle else len(z.polygon) for z in geofence.inclusion] == [4, (47.40, 8.55, 300)]
    assert imported.warnings == ()


def test_exclusion_shapes_and_rally_points_as_qgroundcontrol_writes_them_round_trip():
    """QGroundControl 4's geoFence (GeoFenceController::save: polygons and circles, each with its inclusion flag) and
    rallyPoints (RallyPointController::save: [latitude, longitude, altitude]) come in as keep-out zones and rally points and
    go out as they came."""
    island = [[47.3979, 8.5457], [47.3980, 8.5457], [47.3980, 8.5458]]
    fence = {
        "circles": [{"circle": {"center": [47.3990, 8.5470], "radius": 15.5}, "inclusion": False, "version": 1}],
        "polygons": [{"inclusion": False, "polygon": island, "version": 1}],
        "version": 2,
    }
    rally = {"points": [[47.3978, 8.5455, 0], [47.3985, 8.5460, 12.5]], "version": 2}
    text = json.dumps(json.loads(plan_text()) | {"geoFence": fence, "rallyPoints": rally}, indent=4)
    imported = import_plan(text, "f.plan")
    mission = imported.mission
    assert imported.warnings == ()
    shapes = [
        [[v.lat, v.lon] for v in z.polygon] if z.polygon else [z.circle.lat, z.circle.lon, z.circle.radius_m] for z in mission.geofence.keep_out
    ]
    assert shapes == [island, [47.3990, 8.5470, 15.5]]
    assert [[p.lat, p.lon, p.alt_m] for p in mission.rally_points] == rally["points"]
    plan = json.loads(export_plan(mission).text)
    assert sorted(map(json.dumps, plan["geoFence"]["polygons"] + plan["geoFence"]["circles"])) == sorted(
        map(json.dumps, fence["polygons"] + fence["circles"])
    )
    assert plan["rallyPoints"] == rally
    back = import_plan(export_plan(mission).text, "again.plan", name=mission.name).mission
    assert (back.geofence, back.rally_points) == (mission.geofence, mission.rally_points)


def test_a_zone_or_rally_point_name_is_reported_where_a_format_cannot_carry_it(minimal_yaml: str):
    mission = load_mission_text(
        minimal_yaml + "geofence:\n  keep_out: [{name: pier, circle: {lat: 47.3, lon: 8.5, radius_m: 10}}]\n"
        "rally_points: [{lat: 47.3977, lon: 8.5456, name: slipway}]\n",
        "m.yaml",
    )
    assert [path for path, _ in export_plan(mission).warnings] == [("home",), ("geofence", "keep_out", 0, "name"), ("rally_points", 0, "name")]
    assert [path for path, _ in export_waypoints(mission).warnings] == [("geofence",), ("rally_points",)]


def test_a_slow_plan_gets_a_leg_time_limit_it_can_keep_with_a_warning():
    """A 60 m line at 0.5 m/s (QGroundControl's DO_CHANGE_SPEED) takes 116 s past the acceptance radius: over the
    default 120 s? no; 300 m takes 596 s: limits.leg_timeout_s becomes twice that, said where the leg is."""
    speed = {"autoContinue": True, "command": 178, "doJumpId": 1, "frame": 2, "params": [1, 0.5, -1, 0, 0, 0, 0], "type": "SimpleItem"}
    far = {"autoContinue": True, "command": 16, "doJumpId": 2, "frame": 3, "params": [0, 0, 0, None, 47.4004419, 8.545594, 0], "type": "SimpleItem"}
    imported = import_plan(plan_text(items=[speed, far]), "slow.plan")
    assert imported.mission.limits.leg_timeout_s == 1193.0
    assert [(w.field, w.message) for w in imported.warnings] == [
        ("mission.items[1]", "this leg takes at least 596 s: limits.leg_timeout_s set to 1193 (the default 120 would refuse it)")
    ]


def test_the_vehicle_option_wins_over_the_plans_vehicle_type_with_a_warning():
    imported = import_plan(plan_text(), "r.plan", vehicle="boat")
    assert imported.mission.vehicle == "boat"
    assert [w.field for w in imported.warnings] == ["mission.vehicleType"]


def test_a_byte_order_mark_and_crlf_lines_are_fine():
    assert import_text("\ufeff" + plan_text().replace("\n", "\r\n"), "bom.plan").mission.vehicle == "rover"
    assert import_text("\ufeff" + CMAC.read_text(), "bom.waypoints", vehicle="rover").mission.home is not None


# -- bad input, located --------------------------------------------------------------------------


def test_malformed_json_is_located_by_the_decoder():
    text = plan_text().replace('"fileType": "Plan",', '"fileType": "Plan"', 1)
    line = next(n for n, row in enumerate(text.splitlines(), start=1) if '"groundStation"' in row)
    assert errors_of(import_plan, text, "bad.plan") == [f"bad.plan:{line}:5: (json): Expecting ',' delimiter"]


def test_a_non_numeric_coordinate_is_located_at_its_value():
    text = plan_text().replace("47.3981", '"47.3981"')
    line = next(n for n, row in enumerate(text.splitlines(), start=1) if '"47.3981"' in row)
    column = text.splitlines()[line - 1].index('"47.3981"') + 1
    assert errors_of(import_plan, text, "bad.plan") == [
        f'bad.plan:{line}:{column}: mission.items[0].params[4]: expected a number or null, got string "47.3981"'
    ]


@pytest.mark.parametrize(
    ("change", "field", "message"),
    [
        (lambda d: d | {"fileType": "Fence"}, "fileType", "'Fence': not a QGroundControl plan (fileType must be 'Plan')"),
        (lambda d: {k: v for k, v in d.items() if k != "mission"}, "(plan)", "mission: required field is missing"),
        (
            lambda d: d | {"mission": d["mission"] | {"version": 1}},
            "mission.version",
            "mission version 1: only version 2 (the current format) is read",
        ),
        (
            lambda d: d | {"mission": d["mission"] | {"vehicleType": 2}},
            "mission.vehicleType",
            "vehicleType 2 (QUADROTOR) is not a vehicle the executive drives",
        ),
        (lambda d: _item(d, command="16"), "mission.items[0].command", 'expected an integer, got string "16"'),
        (lambda d: _item(d, params=[0, 0, 0, None, 47.3981, 8.5456]), "mission.items[0].params", "expected 7 params"),
        (lambda d: _item(d, frame=1), "mission.items[0].frame", "LOCAL_NED (1): a waypoint needs a global frame"),
        (lambda d: _item(d, params=[0, 0, 0, None, None, 8.5456, 0]), "mission.items[0].params[4]", "a waypoint needs a latitude and a longitude"),
        (lambda d: _item(d, params=[0, 0, 0, None, 95.0, 8.5456, 0]), "mission.items[0].params[4]", "(as waypoints[0].lat of the mission)"),
        (lambda d: _item(d, command=20), "mission.items", "at least one waypoint is needed (as waypoints of the mission)"),
        (lambda d: _item(d, frame=0, home=None), "mission.items[0].frame", "needs the home's altitude, and there is none"),
    ],
    ids=["file type", "no mission", "version", "vehicle type", "command", "params", "frame", "no latitude", "latitude", "no waypoint", "amsl"],
)
def test_each_bad_plan_is_located(change, field, message):
    text = json.dumps(change(json.loads(plan_text())), indent=4)
    errors = errors_of(import_plan, text, "bad.plan")
    assert len(errors) == 1 and f": {field}: " in errors[0] and message in errors[0], errors
    _, line, column = errors[0].split(":")[:3]
    assert text_at(text, int(line), int(column))  # a real place in the file


def _item(doc: dict[str, Any], home: Any = "keep", **fields: Any) -> dict[str, Any]:
    mission = doc["mission"]
    item = mission["items"][0] | fields
    mission = mission | {"items": [item]}
    if home is None:
        mission.pop("plannedHomePosition")
    return doc | {"mission": mission}


def test_a_waypoint_outside_the_geofence_and_a_crossed_fence_are_located_in_the_plan():
    outside = [[47.30, 8.40], [47.31, 8.40], [47.31, 8.41], [47.30, 8.41]]
    doc = json.loads(plan_text()) | {"geoFence": {"polygons": [{"inclusion": True, "polygon": outside, "version": 1}], "circles": [], "version": 2}}
    fields = [e.split(": ")[1] for e in errors_of(import_plan, json.dumps(doc, indent=4), "f.plan")]
    assert fields == ["mission.items[0]", "mission.plannedHomePosition"]  # in file order
    crossed = [[47.39, 8.54], [47.41, 8.56], [47.41, 8.54], [47.39, 8.56]]
    doc["geoFence"]["polygons"][0]["polygon"] = crossed
    errors = errors_of(import_plan, json.dumps(doc, indent=4), "f.plan")
    assert len(errors) == 1 and ": geoFence.polygons[0].polygon[2]: " in errors[0] and "intersects itself" in errors[0]


def test_a_json_document_that_is_not_a_plan():
    assert errors_of(import_plan, "[1, 2]", "list.plan") == ["list.plan:1:1: (plan): expected a JSON object (a QGroundControl plan), got an array"]


def wpl(*rows: str) -> str:
    home = "0\t1\t0\t16\t0\t0\t0\t0\t-35.363262\t149.165237\t584.09\t1"
    return "\n".join(["QGC WPL 110", home, *rows]) + "\n"


WP1 = "1\t0\t3\t16\t0\t0\t0\t0\t-35.3630\t149.1652\t0\t1"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("QGC WPL 120\n" + wpl(WP1).split("\n", 1)[1], "w.waypoints:1:1: (header): expected 'QGC WPL 110' on the first line"),
        ("", "w.waypoints:1:1: (header): expected 'QGC WPL 110' on the first line (a Mission Planner waypoint file), got an empty line"),
        (wpl(WP1.replace("-35.3630", "-35,3630")), "w.waypoints:3:18: item[1].latitude: expected a number, got '-35,3630'"),
        (wpl(WP1.replace("\t16\t", "\t16.5\t")), "w.waypoints:3:7: item[1].command: expected an integer, got '16.5'"),
        (wpl(WP1.replace("\t0\t1", "\t0")), "w.waypoints:3:37: item[1]: expected 12 tab-separated fields"),
        (wpl(WP1 + "\t7"), "w.waypoints:3:40: item[1]: expected 12 tab-separated fields"),
        (wpl(WP1.replace("\t0\t1", "\tinf\t1")), "w.waypoints:3:36: item[1].altitude: expected a finite number, got 'inf'"),
        (wpl(WP1.replace("-35.3630", "-95.0")), "w.waypoints:3:18: item[1].latitude: -95.0: Input should be greater than or equal to -90"),
    ],
    ids=["header", "empty", "comma", "command", "too few", "too many", "infinite", "latitude"],
)
def test_each_bad_waypoints_file_is_located(text, expected):
    errors = errors_of(import_waypoints, text, "w.waypoints", vehicle="rover")
    assert len(errors) == 1 and errors[0].startswith(expected), errors


def test_a_waypoints_item_out_of_sequence_is_a_warning():
    imported = import_waypoints(wpl(WP1.replace("1\t0", "7\t0", 1)), "w.waypoints", vehicle="rover")
    assert [str(w) for w in imported.warnings] == [
        "w.waypoints:3:1: item[1].index: index 7 out of sequence (expected 1): items are taken in file order"
    ]


def test_file_level_problems_are_located(tmp_path):
    binary = tmp_path / "b.plan"
    binary.write_bytes(b'{\n  "a": "\xff"\n}')
    assert errors_of(import_file, binary) == [f"{binary}:2:9: (file): not UTF-8 text: byte 0xff"]
    assert errors_of(import_file, tmp_path / "missing.plan") == [f"{tmp_path / 'missing.plan'}:1:1: (file): No such file or directory"]
    deep = tmp_path / "deep.plan"
    deep.write_text("[" * 100 + "]" * 100)
    assert "nested deeper than 64 levels" in errors_of(import_file, deep)[0]


def test_a_mission_with_nothing_a_format_can_say_is_reported_on_export():
    mission = Mission.model_validate(
        {
            "version": 1,
            "name": "samples",
            "vehicle": "boat",
            "tree": "goto_sample",
            "home": {"lat": 47.0, "lon": 8.0, "heading_deg": 90.0},
            "geofence": {"max_distance_from_home_m": 500.0},
            "waypoints": [{"lat": 47.001, "lon": 8.0, "name": "buoy", "sample": True, "speed_m_s": 1.0}, {"lat": 47.002, "lon": 8.0}],
        }
    )
    plan = export_plan(mission)
    assert [p for p, _ in plan.warnings] == [
        ("waypoints", 0, "name"),
        ("waypoints", 0, "sample"),
        ("waypoints", 1, "speed_m_s"),
        ("home", "heading_deg"),
    ]
    assert json.loads(plan.text)["geoFence"]["circles"] == [{"circle": {"center": [47.0, 8.0], "radius": 500.0}, "inclusion": True, "version": 1}]
    assert ("geofence",) in [p for p, _ in export_waypoints(mission).warnings]
    assert math.isclose(import_plan(plan.text, "s.plan").mission.geofence.max_distance_from_home_m, 500.0)
