"""The simulated autopilots by name: the built-in ones, one a program registers, one an installed package declares."""

from __future__ import annotations

from collections.abc import Iterator
from importlib.metadata import EntryPoint

import pytest

from executive.sim import registry
from executive.sim.ardupilot.base import ArduPilotSim
from executive.sim.ardupilot.bunker import BunkerSim
from executive.sim.ardupilot.plane import QuadPlaneSim
from executive.sim.ardupilot.rover import ArduRoverSim
from executive.sim.ardupilot.sub import ArduSubSim
from executive.sim.firmware import FirmwareSim
from executive.sim.px4.base import Px4Sim
from executive.sim.px4.rover import Px4RoverSim
from executive.sim.px4.vtol import Px4VtolSim
from executive.sim.registry import ENTRY_POINT_GROUP, firmwares_for, make_autopilot, register_autopilot
from executive.world.clock import ManualClock


class BoatOnPx4(Px4RoverSim):
    """A user's simulator: PX4 on a boat (here PX4's rover under another name)."""


@pytest.fixture
def registry_alone(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """No simulator added by another test, and no installed package's."""
    monkeypatch.setattr(registry, "_added", {})
    monkeypatch.setattr(registry, "entry_points", lambda group: [])
    registry._installed.cache_clear()
    yield
    registry._installed.cache_clear()


@pytest.mark.parametrize(
    ("autopilot", "kind", "expected"),
    [
        ("ardupilot", "rover", ArduRoverSim),
        ("ardupilot", "boat", ArduRoverSim),
        ("ardupilot", "bunker", BunkerSim),
        ("ardupilot", "sub", ArduSubSim),
        ("ardupilot", "vtol", QuadPlaneSim),
        ("px4", "vtol", Px4VtolSim),
        ("px4", "rover", Px4RoverSim),
    ],
)
def test_each_built_in_simulator_is_made_by_its_firmware_and_kind(registry_alone: None, autopilot: str, kind: str, expected: type) -> None:
    ap = make_autopilot(kind, ManualClock(), autopilot=autopilot)
    assert type(ap) is expected and ap.profile.kind == ("rover" if kind == "bunker" else kind)
    assert isinstance(ap, FirmwareSim) and isinstance(ap, ArduPilotSim) is (autopilot == "ardupilot")


def test_px4_shares_the_firmware_base_not_ardupilot() -> None:
    assert issubclass(Px4Sim, FirmwareSim) and not issubclass(Px4Sim, ArduPilotSim)


def test_unknown_names_are_refused_with_what_is_known(registry_alone: None) -> None:
    with pytest.raises(ValueError, match=r"no simulated autopilot 'inav' \(known: ardupilot, px4\)"):
        make_autopilot("rover", ManualClock(), autopilot="inav")
    with pytest.raises(ValueError, match=r"no simulated vehicle of kind 'sub' on px4 \(known: vtol, rover\)"):
        make_autopilot("sub", ManualClock(), autopilot="px4")


def test_a_simulator_a_program_registers_is_made_by_name(registry_alone: None) -> None:
    register_autopilot("px4", "boat", BoatOnPx4)
    assert list(firmwares_for("px4")) == ["vtol", "rover", "boat"]
    assert type(make_autopilot("boat", ManualClock(), autopilot="px4")) is BoatOnPx4
    register_autopilot("myfirmware", "rover", "executive.sim.ardupilot.rover:ArduRoverSim")  # imported on first use
    assert type(make_autopilot("rover", ManualClock(), autopilot="myfirmware")) is ArduRoverSim


def test_a_simulator_an_installed_package_declares_is_found_by_its_entry_point(registry_alone: None, monkeypatch: pytest.MonkeyPatch) -> None:
    declared = [EntryPoint(name="px4.boat", value=f"{__name__}:BoatOnPx4", group=ENTRY_POINT_GROUP)]
    monkeypatch.setattr(registry, "entry_points", lambda group: declared if group == ENTRY_POINT_GROUP else [])
    assert list(firmwares_for("px4")) == ["vtol", "rover", "boat"]
    assert list(firmwares_for("ardupilot")) == ["rover", "boat", "bunker", "sub", "vtol"]  # another firmware's kinds unchanged
    assert type(make_autopilot("boat", ManualClock(), autopilot="px4")) is BoatOnPx4
