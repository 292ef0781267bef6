"""The executive drives legs as fast as the autopilot's own AUTO: the example missions on the lock-step simulation (manual clock)."""

from __future__ import annotations

import pytest

from benchmarks.efficiency import MISSIONS, TARGET_RATIO, time_auto, time_guided
from executive.behaviours import GoTo
from executive.mission.loader import load_mission


@pytest.mark.parametrize("name", ["rover_square", "boat_survey"])
def test_guided_legs_take_no_longer_than_auto_on_the_same_waypoints(name: str) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    guided, auto = time_guided(mission), time_auto(mission)
    assert guided.seconds / auto.seconds <= TARGET_RATIO, (guided, auto)


def test_without_look_ahead_every_corner_is_a_stop(monkeypatch: pytest.MonkeyPatch) -> None:
    # the same mission driven stop to stop (a leg ends only inside the acceptance radius) is slower: the look-ahead is what helps
    mission = load_mission(MISSIONS / "rover_square.yaml")
    ahead = time_guided(mission).seconds
    monkeypatch.setattr(GoTo, "pass_distance_m", lambda self, position: None)
    assert time_guided(mission).seconds > ahead + 1.5
