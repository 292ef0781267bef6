"""Mission rules for a VTOL: an acceptance radius a plane can meet, a hover point it can fly on its lift motors; located errors."""

from __future__ import annotations

import pytest

from executive import trees
from executive.testing import mission_errors as errors_of


@pytest.fixture(autouse=True)
def vtol_trees(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trees, "available", lambda: ["waypoints", "vtol_transit"])


HEAD = "version: 1\nname: m\nvehicle: vtol\ntree: vtol_transit\n"
WP = "waypoints:\n  - {lat: 1.0, lon: 2.0}\n"
TOO_SMALL = "is too small for a vtol: it flies its legs as a plane, circling each point at WP_LOITER_RAD (60 m); use at least 70 m"
FAR = "ArduPlane flies a farther GUIDED target as a plane, not on its lift motors"


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("limits: {acceptance_radius_m: 70}\n" + WP, []),
        ("limits: {acceptance_radius_m: 69.5}\n" + WP, [f"m.yaml:5:31: limits.acceptance_radius_m: 69.5 m {TOO_SMALL}"]),
        (WP, [f"m.yaml:1:1: limits.acceptance_radius_m: 2 m (the default) {TOO_SMALL}"]),  # no limits: section to point at
        ("limits: {leg_timeout_s: 60}\n" + WP, [f"m.yaml:5:9: limits.acceptance_radius_m: 2 m (the default) {TOO_SMALL}"]),
        ("limits: {acceptance_radius_m: 80}\nvtol:\n  hover_enu: {east_m: 30, north_m: 40, up_m: 20}\n" + WP, []),  # 50 m: at the limit
        (
            "limits: {acceptance_radius_m: 80}\nvtol:\n  hover_enu: {east_m: -40, north_m: 31, up_m: 20}\n" + WP,
            [f"m.yaml:7:14: vtol.hover_enu: 51 m from home, over 50 m: {FAR}"],
        ),
        (
            "limits: {acceptance_radius_m: 80}\nvtol: {hover_enu: {east_m: 3, north_m: 4, up_m: 2}}\n" + WP,
            ["m.yaml:6:49: vtol.hover_enu.up_m: 2: Input should be greater than or equal to 5"],
        ),
        (
            "limits: {acceptance_radius_m: 80}\nvtol: {hover_enu: {east_m: 3, up_m: 20}}\n" + WP,
            ["m.yaml:6:19: vtol.hover_enu.north_m: required field is missing"],
        ),
        ("limits: {acceptance_radius_m: 80}\nsimulator: {q_guided_mode: 1}\n" + WP, []),
        (
            "limits: {acceptance_radius_m: 80}\nsimulator: {q_guided_mode: 2}\n" + WP,
            ["m.yaml:6:28: simulator.q_guided_mode: 2: Input should be less than or equal to 1"],
        ),
    ],
)
def test_vtol_rules(body: str, expected: list[str]) -> None:
    assert errors_of(HEAD + body) == expected


def test_only_the_simulated_vtol_has_q_guided_mode() -> None:
    text = "version: 1\nname: m\nvehicle: rover\nsimulator: {ekf_ready_after_s: 5, q_guided_mode: 1}\n" + WP
    assert errors_of(text) == ["m.yaml:4:50: simulator.q_guided_mode: only the simulated vtol (ArduPlane) has Q_GUIDED_MODE"]


def test_a_rover_keeps_its_small_acceptance_radius() -> None:
    assert errors_of("version: 1\nname: m\nvehicle: rover\nlimits: {acceptance_radius_m: 1.5}\n" + WP) == []
