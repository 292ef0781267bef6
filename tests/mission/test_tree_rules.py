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
