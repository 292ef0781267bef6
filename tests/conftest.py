"""Fixtures shared by every test: a clean blackboard, a manual clock, a fake MAVLink link."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import py_trees
import pytest

from executive import blackboard
from executive.autopilot.selection import Autopilot
from executive.clock import ManualClock
from executive.io.heading import wait_for_filterpy
from executive.io.mavlink.commander import Commander
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.vehicles import PROFILES
from tests_support import FakeLink, Harness, Vehicle, port_for


@pytest.fixture(scope="session", autouse=True)
def filterpy_loaded() -> None:
    """The heading filter loads filterpy in the background; tests want it judging from the first reading."""
    assert wait_for_filterpy()


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    blackboard.reset()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock(start=100.0)


@pytest.fixture
def link() -> FakeLink:
    return FakeLink()


@pytest.fixture
def commander(link: FakeLink, clock: ManualClock) -> Commander:
    return Commander(link, clock, PROFILES["rover"])


@pytest.fixture
def autopilot(commander: Commander) -> Autopilot:
    """The autopilot port over the shared commander (ArduPilot; ``autopilot.adopt`` for PX4)."""
    return port_for(commander)


@pytest.fixture
def vehicle() -> Vehicle:
    return Vehicle()


@pytest.fixture
def square_mission() -> Mission:
    """Four waypoints on a 20 m square (the rover square), radius 1.5 m, leg timeout 60 s."""
    corners = [(47.397742, 8.545594), (47.397922, 8.545594), (47.397922, 8.545860), (47.397742, 8.545860)]
    return Mission.model_validate(
        {
            "version": 1,
            "name": "square",
            "vehicle": "rover",
            "auto_arm": True,
            "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60.0, "recovery_timeout_s": 30.0, "ekf_wait_s": 60.0},
            "waypoints": [{"lat": lat, "lon": lon} for lat, lon in corners],
        }
    )


@pytest.fixture
def mission_state(square_mission: Mission) -> MissionState:
    state = MissionState()
    state.upload(square_mission)
    return state


@pytest.fixture
def harness(clock: ManualClock, link: FakeLink, commander: Commander, autopilot: Autopilot, mission_state: MissionState):
    """``harness(root)`` -> a :class:`Harness` ticking ``root`` with the shared fakes."""

    def make(root: py_trees.behaviour.Behaviour) -> Harness:
        return Harness(root, clock, link, commander, mission_state, autopilot)

    return make


DATA = Path(__file__).parent / "data"


@pytest.fixture
def minimal_mission() -> Path:
    """A valid mission file: one waypoint, rover, tree waypoints."""
    return DATA / "minimal_mission.yaml"


@pytest.fixture
def minimal_yaml(minimal_mission: Path) -> str:
    """The text of the smallest valid mission."""
    return minimal_mission.read_text(encoding="utf-8")
