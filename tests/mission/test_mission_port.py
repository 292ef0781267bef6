"""The mission port: all a behaviour gets of the mission; it reads, reports outcomes, and the lifecycle applies or refuses them."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest

from executive.behaviours.base import ExecutiveBehaviour
from executive.mission.lifecycle import MissionState, Refused
from executive.mission.port import MissionPort

BEHAVIOURS = Path(__file__).resolve().parents[2] / "executive" / "behaviours"
REQUESTS = ("upload", "replace", "start", "pause", "resume", "delete", "complete", "abort", "set_route", "advance_leg", "record_sample")


class Holds(ExecutiveBehaviour):
    needs = ("mission_state",)

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS


def test_a_tree_is_given_the_port_which_has_no_lifecycle_request(harness) -> None:
    behaviour = Holds("holds")
    harness(behaviour)
    assert isinstance(behaviour.mission_state, MissionPort)
    assert [name for name in REQUESTS if hasattr(MissionPort, name)] == []


def test_no_behaviour_names_the_mission_state() -> None:
    naming = [path.name for path in sorted(BEHAVIOURS.glob("*.py")) if "MissionState" in path.read_text()]
    assert naming == []


def test_a_leg_reported_done_is_applied_by_the_lifecycle_or_refused(square_mission) -> None:
    state = MissionState()
    port = MissionPort(state)
    state.upload(square_mission)
    with pytest.raises(Refused, match="cannot advance a leg while READY"):
        port.leg_done()
    state.start()
    port.leg_done()
    assert (port.leg_index, state.legs.leg_index, port.target) == (1, 1, square_mission.waypoints[1])
