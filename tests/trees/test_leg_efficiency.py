"""The executive drives legs nearly as fast as the autopilot's own AUTO, and leaves the route no farther than AUTO does:
the example missions on the lock-step simulation (manual clock), with the firmware's default parameters and with SITL's."""

from __future__ import annotations

import pytest

from benchmarks.efficiency import MISSIONS, TARGET_RATIO, corner_cuts, route_of, time_auto, time_guided, with_sitl_parameters
from executive.behaviours import GoTo
from executive.mission.loader import load_mission


@pytest.mark.parametrize("name", ["rover_square", "boat_survey"])
def test_guided_legs_take_no_longer_than_auto_on_the_same_waypoints(name: str) -> None:
    # the firmware's defaults (WP_SPEED 2): within 10 %. With SITL's WP_SPEED 5 the benchmark reports 1.15x: GUIDED brakes
    # for every target on the half-acceleration approach, AUTO's S-curves at the full one (README, Benchmarks)
    mission = load_mission(MISSIONS / f"{name}.yaml")
    guided, auto = time_guided(mission), time_auto(mission)
    assert guided.seconds / auto.seconds <= TARGET_RATIO, (guided, auto)


@pytest.mark.parametrize("sitl", [False, True], ids=["firmware-defaults", "sitl-parameters"])
@pytest.mark.parametrize("name", ["rover_square", "boat_survey"])
def test_guided_leaves_the_route_no_farther_than_auto(name: str, sitl: bool) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    mission = with_sitl_parameters(mission) if sitl else mission
    guided, auto = time_guided(mission), time_auto(mission)
    route = route_of(mission)
    guided_cuts, auto_cuts = corner_cuts(guided.track, route), corner_cuts(auto.track, route)
    assert max(guided_cuts) <= max(auto_cuts), (guided_cuts, auto_cuts)
    assert min(guided_cuts) > 0.1  # corners driven through, not stopped at


def test_without_look_ahead_every_corner_is_a_stop(monkeypatch: pytest.MonkeyPatch) -> None:
    # the same mission driven stop to stop (a leg ends only inside the acceptance radius) is slower: the look-ahead is what helps
    mission = with_sitl_parameters(load_mission(MISSIONS / "rover_square.yaml"))
    ahead = time_guided(mission).seconds
    monkeypatch.setattr(GoTo, "drive_through", lambda self, position, distance_m: None)
    assert time_guided(mission).seconds > ahead + 1.5
