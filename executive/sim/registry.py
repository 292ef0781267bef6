"""The simulated autopilots by name: a firmware and a vehicle kind make a simulator, built in or added by a user.

As python-can finds its interfaces: a table of the built-in simulators (imported on first use), those
a program adds with :func:`register_autopilot`, and those installed packages declare as entry points
in the ``executive.simulators`` group, named ``<firmware>.<kind>`` (``px4.boat = "mypkg.sim:Px4BoatSim"``).
A simulator is a :class:`~executive.sim.firmware.FirmwareSim` subclass, made as
``cls(profile, clock, home, **options)``.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from functools import cache
from importlib.metadata import entry_points
from types import MappingProxyType
from typing import TYPE_CHECKING

from executive.mission.declaration import kind_spec, vehicle_profile
from executive.sim.firmware import DEFAULT_HOME, Home

if TYPE_CHECKING:
    from executive.sim.firmware import FirmwareSim
    from executive.world.clock import Clock

#: The entry-point group installed packages add simulators in (names ``<firmware>.<kind>``, values ``module:Class``).
ENTRY_POINT_GROUP = "executive.simulators"

#: The built-in simulators: firmware -> vehicle kind -> ``module:Class``.
BUILT_IN: Mapping[str, Mapping[str, str]] = MappingProxyType({
    "ardupilot": MappingProxyType({
        "rover": "executive.sim.ardupilot.rover:ArduRoverSim", "boat": "executive.sim.ardupilot.rover:ArduRoverSim",
        "bunker": "executive.sim.ardupilot.bunker:BunkerSim", "sub": "executive.sim.ardupilot.sub:ArduSubSim",
        "vtol": "executive.sim.ardupilot.plane:QuadPlaneSim",
    }),
    "px4": MappingProxyType({"vtol": "executive.sim.px4.vtol:Px4VtolSim", "rover": "executive.sim.px4.rover:Px4RoverSim"}),
})  # fmt: skip

#: The simulated autopilot firmwares built in (``executive sim --autopilot``).
FIRMWARES = tuple(BUILT_IN)
#: Kinds that are another kind's profile on a different vehicle model (a Bunker is an ArduRover rover).
PROFILE_OF: Mapping[str, str] = MappingProxyType({"bunker": "rover"})

_added: dict[str, dict[str, type[FirmwareSim] | str]] = {}


def register_autopilot(firmware: str, kind: str, simulator: type[FirmwareSim] | str) -> None:
    """Add (or replace) the simulator of a firmware's vehicle kind: a class, or ``module:Class`` imported on first use."""
    _added.setdefault(firmware, {})[kind] = simulator


@cache
def _installed() -> Mapping[str, Mapping[str, str]]:
    """The simulators installed packages declare (read once)."""
    found: dict[str, dict[str, str]] = {}
    for point in entry_points(group=ENTRY_POINT_GROUP):
        firmware, _, kind = point.name.partition(".")
        if kind:
            found.setdefault(firmware, {})[kind] = point.value
    return found


def _load(where: type[FirmwareSim] | str) -> type[FirmwareSim]:
    if not isinstance(where, str):
        return where
    module, _, name = where.partition(":")
    cls: type[FirmwareSim] = getattr(importlib.import_module(module), name)
    return cls


class Simulators(Mapping[str, "type[FirmwareSim]"]):
    """Vehicle kind -> simulator class, for one firmware; classes are imported on first use.

    Added simulators come first, then the built-in ones; installed packages' are looked up only for
    a kind neither has (and when listing).
    """

    def __init__(self, firmware: str) -> None:
        self.firmware = firmware

    def _where(self, kind: str, *, installed: bool) -> type[FirmwareSim] | str | None:
        where = _added.get(self.firmware, {}).get(kind) or BUILT_IN.get(self.firmware, {}).get(kind)
        return where or (_installed().get(self.firmware, {}).get(kind) if installed else None)

    def __getitem__(self, kind: str) -> type[FirmwareSim]:
        where = self._where(kind, installed=True)
        if where is None:
            raise KeyError(kind)
        return _load(where)

    def __contains__(self, kind: object) -> bool:
        return isinstance(kind, str) and self._where(kind, installed=True) is not None

    def __iter__(self) -> Iterator[str]:
        kinds = {**BUILT_IN.get(self.firmware, {}), **_added.get(self.firmware, {}), **_installed().get(self.firmware, {})}
        return iter(kinds)

    def __len__(self) -> int:
        return sum(1 for _ in self)


#: The simulated ArduPilot for each vehicle kind (``executive sim --vehicle``).
AUTOPILOTS: Mapping[str, type[FirmwareSim]] = Simulators("ardupilot")


def firmwares_for(autopilot: str) -> Mapping[str, type[FirmwareSim]]:
    """Vehicle kind -> simulator class, for one firmware (``ardupilot``, ``px4``, or one a user added)."""
    if autopilot not in BUILT_IN and autopilot not in _added and autopilot not in _installed():
        known = [*BUILT_IN, *(name for name in (*_added, *_installed()) if name not in BUILT_IN)]
        raise ValueError(f"no simulated autopilot {autopilot!r} (known: {', '.join(dict.fromkeys(known))})")
    return AUTOPILOTS if autopilot == "ardupilot" else Simulators(autopilot)


def simulated_model(kind: str) -> str:
    """The simulated vehicle a vehicle kind rides: itself, or the one a plugin's kind names (:attr:`VehicleKindSpec.simulator`)."""
    spec = kind_spec(kind)
    return spec.simulator if spec is not None and spec.simulator is not None else kind


def make_autopilot(kind: str, clock: Clock, home: Home = DEFAULT_HOME, *, autopilot: str = "ardupilot", **options: float) -> FirmwareSim:
    """The simulated autopilot for a vehicle kind; ``options`` go to its class (:class:`~.firmware.FirmwareSim` and the firmware's own).

    A plugin's kind rides the simulated vehicle it names, which speaks with the kind's own profile (its MAV_TYPE, modes).
    """
    firmwares, model = firmwares_for(autopilot), simulated_model(kind)
    if model not in firmwares:
        raise ValueError(f"no simulated vehicle of kind {kind!r} on {autopilot} (known: {', '.join(firmwares)})")
    spec = kind_spec(kind)
    profile = spec.profile if spec is not None else vehicle_profile(PROFILE_OF.get(kind, kind))
    return firmwares[model](profile, clock, home, **options)
