"""Rules tying a mission's tree to its vehicle, its options section and its waypoints."""

from __future__ import annotations

import pytest

from executive import trees
from executive.testing import mission_errors as errors_of


@pytest.fixture(autouse=True)
def every_tree(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trees, "available", lambda: ["waypoints", "goto_sample", "auv_survey", "vtol_transit", "ugv_rc_route"])


HEAD = "version: 1\nname: m\n"
WP = "waypoints:\n  - {lat: 1.0, lon: 2.0}\n"
SAMPLE_WP = "waypoints:\n  - {lat: 1.0, lon: 2.0, sample: true}\n"


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("vehicle: boat\ntree: goto_sample\nwaypoints:\n  - {lat: 1.0, lon: 2.0, sample: true}\n", []),
        (
            "vehicle: sub\ntree: goto_sample\nwaypoints:\n  - {lat: 1.0, lon: 2.0, sample: true}\n",
            ["m.yaml:4:7: tree: tree goto_sample drives boat, rover, not a sub"],
        ),
        ("vehicle: boat\ntree: goto_sample\n" + WP, ["m.yaml:6:3: waypoints: goto_sample needs at least one waypoint with sample: true"]),
        (
            "vehicle: rover\ntree: waypoints\nwaypoints:\n  - {lat: 1.0, lon: 2.0, sample: true}\n",
            ["m.yaml:6:34: waypoints[0].sample: only goto_sample takes samples (waypoint 1)"],
        ),
        ("vehicle: vtol\ntree: vtol_transit\nlimits: {acceptance_radius_m: 80}\nvtol: {takeoff_alt_m: 40}\n" + WP, []),
        (
            "vehicle: rover\ntree: waypoints\nvtol: {takeoff_alt_m: 40}\n" + WP,
            ["m.yaml:5:7: vtol: only used by tree vtol_transit (tree is waypoints)"],
        ),
        ("vehicle: rover\ntree: ugv_rc_route\nwaypoints: []\n", []),
        ("vehicle: rover\ntree: waypoints\nwaypoints: []\n", ["m.yaml:5:12: waypoints: at least one waypoint is needed"]),
        ("vehicle: sub\ntree: auv_survey\n" + WP, []),
        ("vehicle: boat\ntree: auv_survey\n" + WP, ["m.yaml:4:7: tree: tree auv_survey drives sub, not a boat"]),
    ],
)
def test_tree_rules(body: str, expected: list[str]) -> None:
    assert errors_of(HEAD + body) == expected


def test_rc_source_and_switch_channels_are_validated() -> None:
    text = HEAD + "vehicle: rover\nrc: {source: serial, switch_channels: {swc: 0}}\n" + WP
    assert errors_of(text) == [
        "m.yaml:4:14: rc.source: 'serial': Input should be 'mavlink' or 'can'",
        "m.yaml:4:45: rc.switch_channels.swc: 0: Input should be greater than or equal to 1",
    ]


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("vehicle: rover\ntree: waypoints\n" + WP, []),
        ("vehicle: rover\ntree: waypoints\ndrive: guided\n" + WP, []),
        ("vehicle: rover\ntree: waypoints\ndrive: auto\n" + WP, []),
        ("vehicle: boat\ntree: waypoints\ndrive: auto\nlimits: {auto_horizon_legs: 3}\n" + WP, []),
        (
            "vehicle: sub\ntree: waypoints\ndrive: auto\n" + WP,
            [
                "m.yaml:5:8: drive: tree waypoints is driven in AUTO on a boat or rover or vtol (ArduRover or PX4) so far, "
                "not a sub; use drive: guided"
            ],
        ),
        ("vehicle: boat\ntree: goto_sample\ndrive: auto\n" + SAMPLE_WP, []),
        ("vehicle: rover\ntree: goto_sample\ndrive: auto\n" + SAMPLE_WP, []),
        ("vehicle: sub\ntree: auv_survey\ndrive: auto\nwaypoints:\n  - {lat: 1.0, lon: 2.0, control_mode: depth, depth_m: 5}\n", []),
        (
            "vehicle: sub\ntree: auv_survey\ndrive: auto\nwaypoints:\n  - {lat: 1.0, lon: 2.0, control_mode: altitude, altitude_m: 5}\n",
            [
                "m.yaml:7:40: waypoints[0].control_mode: drive: auto flies a sub's waypoints at their depths: ArduSub's AUTO holds a "
                "height above the seabed only with the sonar reading it when the leg starts (else its terrain failsafe); "
                "use control_mode depth, or drive: guided (waypoint 1)"
            ],
        ),
        (
            "vehicle: rover\ntree: ugv_rc_route\ndrive: auto\nwaypoints: []\n",
            ["m.yaml:5:8: drive: tree ugv_rc_route: its operator puts the route in AUTO already; use drive: guided"],
        ),
        ("vehicle: rover\ndrive: sideways\n" + WP, ["m.yaml:4:8: drive: 'sideways': Input should be 'guided' or 'auto'"]),
        (
            "vehicle: rover\nlimits: {auto_horizon_legs: 0}\n" + WP,
            ["m.yaml:4:29: limits.auto_horizon_legs: 0: Input should be greater than or equal to 1"],
        ),
        (
            "vehicle: rover\nautopilot: px4\ndrive: auto\n" + WP,
            ["m.yaml:4:12: autopilot: drive: auto on PX4 flies a vtol's waypoints so far (proven on PX4's SIH, which has no rover or boat)"],
        ),
        ("vehicle: vtol\nautopilot: px4\ndrive: auto\nlimits: {acceptance_radius_m: 70}\n" + WP, []),
        (
            "vehicle: vtol\nautopilot: ardupilot\ndrive: auto\nlimits: {acceptance_radius_m: 70}\n" + WP,
            [
                "m.yaml:4:12: autopilot: drive: auto on a vtol needs PX4: ArduPlane ends its mission in RTL, flying home from the end "
                "of the horizon instead of holding there (Plane::exit_mission_callback)"
            ],
        ),
    ],
)
def test_drive_rules(body: str, expected: list[str]) -> None:
    """drive: auto only where the autopilot's AUTO can drive the tree; elsewhere refused at drive:, with the reason."""
    assert errors_of(HEAD + body) == expected


def test_drive_defaults_to_guided_with_a_horizon_of_three() -> None:
    from executive.mission import loader

    mission = loader.load_mission_text(HEAD + "vehicle: rover\n" + WP, "m.yaml")
    assert (mission.drive, mission.limits.auto_horizon_legs) == ("guided", 3)
