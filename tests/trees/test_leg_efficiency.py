"""The executive drives legs nearly as fast as the autopilot's own AUTO, and leaves the route no farther than AUTO does:
the example missions on the lock-step simulation (manual clock), with the firmware's default parameters and with SITL's."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from benchmarks.efficiency import MISSIONS, TARGET_RATIO, Timing, corner_cuts, route_of, time_auto, time_guided, with_sitl_parameters
from executive.behaviours import GoTo
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from tests_support import SharedEfficiencyRuns

# the module's runs are shared (Timings), so its tests run on one xdist worker
pytestmark = pytest.mark.xdist_group("leg_efficiency")


def example(name: str, sitl: bool) -> Mission:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    return with_sitl_parameters(mission) if sitl else mission


class Runs:
    """Each example timed once, GUIDED and AUTO: the lock-step run of the same mission is the same run, track and all (shared with
    the other users of conftest's ``efficiency_runs``)."""

    def __init__(self, shared: SharedEfficiencyRuns) -> None:
        self._shared = shared

    def _timed(self, how: Callable[[Mission], Timing], name: str, sitl: bool) -> Timing:
        return self._shared.timed(how, example(name, sitl))

    def guided(self, name: str, sitl: bool = False) -> Timing:
        return self._timed(time_guided, name, sitl)

    def auto(self, name: str, sitl: bool = False) -> Timing:
        return self._timed(time_auto, name, sitl)


@pytest.fixture(scope="module")
def runs(efficiency_runs: SharedEfficiencyRuns) -> Runs:
    return Runs(efficiency_runs)


@pytest.mark.parametrize("name", ["rover_square", "boat_survey"])
def test_guided_legs_take_no_longer_than_auto_on_the_same_waypoints(runs: Runs, name: str) -> None:
    # the firmware's defaults (WP_SPEED 2): within 10 %. With SITL's WP_SPEED 5 the benchmark reports 1.15x: GUIDED brakes
    # for every target on the half-acceleration approach, AUTO's S-curves at the full one (README, Benchmarks)
    guided, auto = runs.guided(name), runs.auto(name)
    assert guided.seconds / auto.seconds <= TARGET_RATIO, (guided, auto)


@pytest.mark.parametrize("sitl", [False, True], ids=["firmware-defaults", "sitl-parameters"])
@pytest.mark.parametrize("name", ["rover_square", "boat_survey"])
def test_guided_leaves_the_route_no_farther_than_auto(runs: Runs, name: str, sitl: bool) -> None:
    guided, auto = runs.guided(name, sitl), runs.auto(name, sitl)
    route = route_of(example(name, sitl))
    guided_cuts, auto_cuts = corner_cuts(guided.track, route), corner_cuts(auto.track, route)
    assert max(guided_cuts) <= max(auto_cuts), (guided_cuts, auto_cuts)
    assert min(guided_cuts) > 0.1  # corners driven through, not stopped at


def test_without_look_ahead_every_corner_is_a_stop(runs: Runs, monkeypatch: pytest.MonkeyPatch) -> None:
    # the same mission driven stop to stop (a leg ends only inside the acceptance radius) is slower: the look-ahead is what helps
    ahead = runs.guided("rover_square", sitl=True).seconds
    monkeypatch.setattr(GoTo, "drive_through", lambda self, position, distance_m: None)
    assert time_guided(example("rover_square", sitl=True)).seconds > ahead + 1.5
