"""Issue 44: every height a vtol is sent to within limits.alt_m above home, and a sub's depth within the water the mission
states (limits.water_depth_m); each error located, at every door (the file, an upload, a route edit)."""

from __future__ import annotations

import pytest

from executive import trees
from executive.mission.lifecycle import MissionState, Refused
from executive.mission.route import new_waypoint
from executive.testing import mission_errors as errors_of


@pytest.fixture(autouse=True)
def built_in_trees(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trees, "available", lambda: ["waypoints", "vtol_transit", "auv_survey"])


VTOL = "version: 1\nname: m\nvehicle: vtol\ntree: vtol_transit\nlimits: {acceptance_radius_m: 100}\n"
OUTSIDE = "above home is outside limits.alt_m [10, 120]"


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("waypoints:\n  - {lat: 1.0, lon: 2.0, alt_m: 40}\n", []),
        ("waypoints:\n  - {lat: 1.0, lon: 2.0}\n", []),  # alt_m 0: flown at the height the aircraft is at
        ("waypoints:\n  - {lat: 1.0, lon: 2.0, alt_m: -50}\n", [f"m.yaml:7:33: waypoints[0].alt_m: -50 m {OUTSIDE} (waypoint 1)"]),
        ("waypoints:\n  - {lat: 1.0, lon: 2.0, alt_m: 9000}\n", [f"m.yaml:7:33: waypoints[0].alt_m: 9000 m {OUTSIDE} (waypoint 1)"]),
        ("waypoints:\n  - {lat: 1.0, lon: 2.0, alt_m: 9.5}\n", [f"m.yaml:7:33: waypoints[0].alt_m: 9.5 m {OUTSIDE} (waypoint 1)"]),
        ("vtol: {takeoff_alt_m: 150}\nwaypoints:\n  - {lat: 1.0, lon: 2.0}\n", [f"m.yaml:6:23: vtol.takeoff_alt_m: 150 m {OUTSIDE}"]),
        (
            "vtol: {hover_enu: {east_m: 3, north_m: 4, up_m: 6}}\nwaypoints:\n  - {lat: 1.0, lon: 2.0}\n",
            [f"m.yaml:6:49: vtol.hover_enu.up_m: 6 m {OUTSIDE}"],
        ),
        (  # the mission's own limits: a 400 m ceiling where the law allows it
            "limits: {acceptance_radius_m: 100, alt_m: {min: 5, max: 400}}\nvtol: {takeoff_alt_m: 150}\nwaypoints:\n"
            "  - {lat: 1.0, lon: 2.0, alt_m: 300}\n",
            [],
        ),
    ],
    ids=["40-m", "no-height", "below-home", "9000-m", "under-10-m", "take-off-150-m", "hover-6-m", "own-limits"],
)
def test_every_height_a_vtol_is_sent_to_is_within_limits_alt_m(body: str, expected: list[str]) -> None:
    text = VTOL.replace("limits: {acceptance_radius_m: 100}\n", "") if body.startswith("limits") else VTOL
    assert errors_of(text + body) == expected


SUB = "version: 1\nname: m\nvehicle: sub\ntree: auv_survey\nlimits: {water_depth_m: 50}\nwaypoints:\n"


@pytest.mark.parametrize(
    ("waypoint", "expected"),
    [
        ("{lat: 1.0, lon: 2.0, control_mode: depth, depth_m: 48}", []),
        (
            "{lat: 1.0, lon: 2.0, control_mode: depth, depth_m: 80}",
            [
                "m.yaml:7:56: waypoints[0].depth_m: 80 m is deeper than the water holds: limits.water_depth_m 50 m less "
                "limits.altitude_m.min 2 m above the seabed: at most 48 m (waypoint 1)"
            ],
        ),
        (
            "{lat: 1.0, lon: 2.0, depth_m: 49}",
            [
                "m.yaml:7:35: waypoints[0].depth_m: 49 m is deeper than the water holds: "
                "limits.water_depth_m 50 m less limits.altitude_m.min 2 m above the seabed: at most 48 m (waypoint 1)"
            ],
        ),
        ("{lat: 1.0, lon: 2.0, control_mode: altitude, altitude_m: 40}", []),
        (
            "{lat: 1.0, lon: 2.0, control_mode: altitude, altitude_m: 60}",
            ["m.yaml:7:62: waypoints[0].altitude_m: 60 m above the seabed is above the surface: limits.water_depth_m is 50 m (waypoint 1)"],
        ),
    ],
    ids=["48-m", "80-m", "49-m-no-control-mode", "40-m-above", "60-m-above"],
)
def test_a_depth_the_water_cannot_hold_is_refused_where_the_mission_states_the_water_depth(waypoint: str, expected: list[str]) -> None:
    assert errors_of(f"{SUB}  - {waypoint}\n") == expected


def test_without_a_water_depth_an_80_m_leg_is_left_to_the_seabed_floor_in_flight() -> None:
    assert errors_of("version: 1\nname: m\nvehicle: sub\ntree: auv_survey\nwaypoints:\n  - {lat: 1.0, lon: 2.0, depth_m: 80}\n") == []


def test_a_route_edit_to_a_height_outside_the_limits_is_refused_and_changes_nothing() -> None:
    from executive.admission.checks import load_mission_text

    state = MissionState()
    state.upload(load_mission_text(VTOL + "waypoints:\n  - {lat: 1.0, lon: 2.0, alt_m: 40}\n", "m.yaml"))
    before = state.mission
    with pytest.raises(Refused, match=r"waypoints\[1\].alt_m: -50 m above home is outside limits.alt_m \[10, 120\]"):
        state.set_route([*before.waypoints, new_waypoint(1.001, 2.0, -50.0)], "operator: add")  # type: ignore[union-attr]
    assert state.mission is before


def test_an_upload_of_a_mission_built_in_code_is_held_to_the_same_heights() -> None:
    """The loader is one door; a mission handed to the lifecycle (an upload, a replacement) is checked again."""
    from executive.mission.model import Mission

    mission = Mission.model_validate(
        {"version": 1, "name": "m", "vehicle": "vtol", "limits": {"acceptance_radius_m": 100}, "waypoints": [{"lat": 1.0, "lon": 2.0, "alt_m": -50}]}
    )
    state = MissionState()
    with pytest.raises(Refused, match=r"waypoints\[0\].alt_m: -50 m above home is outside limits.alt_m \[10, 120\]"):
        state.upload(mission)
    assert state.mission is None
