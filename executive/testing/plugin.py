"""The pytest plugin of :mod:`executive.testing` (entry point ``pytest11``): its pieces as fixtures.

A project's own fixture of the same name wins (``mission_state`` with its mission uploaded, say).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    import py_trees

    from executive.autopilot.selection import Autopilot
    from executive.io.mavlink.commander import Commander
    from executive.mission.lifecycle import MissionState
    from executive.mission.model import Mission
    from executive.testing.canbus import VirtualCan
    from executive.testing.harness import Harness, Vehicle
    from executive.testing.links import FakeLink
    from executive.testing.lockstep import Lockstep
    from executive.testing.on_link import RuntimeOnLink
    from executive.world.clock import ManualClock

# Each fixture imports what it makes: pytest loads this plugin in every process it starts, xdist's controller too, which
# runs no test (importing the kit here cost that controller 0.6 s of CPU before it started its workers).


@pytest.fixture
def clean_blackboard() -> Iterator[None]:
    """The blackboard reset before the test (a board no runtime has), every documented key at its default, and cleared after."""
    import py_trees

    from executive.world import blackboard

    blackboard.reset()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def clock() -> ManualClock:
    """A manual clock at :data:`~executive.testing.START_S`."""
    from executive.testing.harness import START_S
    from executive.world.clock import ManualClock

    return ManualClock(start=START_S)


@pytest.fixture
def link() -> FakeLink:
    """A link that records what is sent and returns what the test queues."""
    from executive.testing.links import FakeLink

    return FakeLink()


@pytest.fixture
def commander(link: FakeLink, clock: ManualClock) -> Commander:
    """A rover's commander on :func:`link`."""
    from executive.io.mavlink.commander import Commander
    from executive.world.vehicles import PROFILES

    return Commander(link, clock, PROFILES["rover"])


@pytest.fixture
def autopilot(commander: Commander) -> Autopilot:
    """The autopilot port over :func:`commander` (ArduPilot; ``autopilot.adopt(MAV_AUTOPILOT_PX4, ...)`` for PX4)."""
    from executive.testing.harness import port_for

    return port_for(commander)


@pytest.fixture
def vehicle(clean_blackboard: None) -> Vehicle:
    """Writes vehicle facts to the blackboard: ``vehicle.set(vehicle__mode="GUIDED", link__up=True)``."""
    from executive.testing.harness import Vehicle

    return Vehicle()


@pytest.fixture
def mission_state() -> MissionState:
    """A mission lifecycle with no mission (override it with one that has yours uploaded)."""
    from executive.mission.lifecycle import MissionState

    return MissionState()


@pytest.fixture
def harness(
    clean_blackboard: None, clock: ManualClock, link: FakeLink, commander: Commander, autopilot: Autopilot, mission_state: MissionState
) -> Callable[..., Harness]:
    """``harness(root)`` -> a :class:`Harness` ticking ``root`` with the fixtures' clock, link, commander, autopilot port and mission state."""
    from executive.testing.harness import Harness

    def make(root: py_trees.behaviour.Behaviour, **setup: Any) -> Harness:
        return Harness(root, clock, link, commander, mission_state, autopilot, **setup)

    return make


@pytest.fixture
def lockstep() -> Iterator[Callable[..., Lockstep]]:
    """``lockstep(mission, **options)`` -> a :class:`Lockstep` simulation, closed after the test."""
    from executive.testing.lockstep import Lockstep

    made: list[Lockstep] = []

    def make(mission: Mission, **options: Any) -> Lockstep:
        made.append(Lockstep(mission, **options))
        return made[-1]

    yield make
    for sim in made:
        sim.close()


@pytest.fixture
def runtime_on_link(clean_blackboard: None, clock: ManualClock, link: FakeLink) -> Iterator[Callable[..., RuntimeOnLink]]:
    """``runtime_on_link(mission, **options)`` -> a :class:`RuntimeOnLink` on the fixtures' clock and link, closed after the test."""
    from executive.testing.on_link import RuntimeOnLink

    made: list[RuntimeOnLink] = []

    def make(mission: Mission, **options: Any) -> RuntimeOnLink:
        made.append(RuntimeOnLink(mission, clock=clock, link=link, **options))
        return made[-1]

    yield make
    for runtime in made:
        runtime.close()


@pytest.fixture
def can_buses() -> Iterator[VirtualCan]:
    """Two ends of a fresh CAN bus in memory, ``base, ours = can_buses``; shut after the test."""
    from executive.testing.canbus import VirtualCan

    with VirtualCan() as buses:
        yield buses
