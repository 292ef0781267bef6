"""The autopilot the behaviours talk to: a back end chosen from the HEARTBEAT's ``autopilot`` field, or forced."""

from __future__ import annotations

import inspect
import logging
from types import FunctionType
from typing import TYPE_CHECKING, Any

from executive.autopilot.ardupilot import ArduPilotPort
from executive.autopilot.mavlink_port import MavlinkPort
from executive.autopilot.port import AutopilotName
from executive.autopilot.px4 import Px4Port
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.modes import mode_table
from executive.world.dialect import mavlink
from executive.world.vehicles import VehicleProfile

log = logging.getLogger(__name__)

BACK_ENDS: dict[str, type[MavlinkPort]] = {"ardupilot": ArduPilotPort, "px4": Px4Port}
#: Commands each firmware acks twice (the first ACCEPTED only says "received"): PX4's MAVLink receiver and then its
#: commander both answer DO_SET_MODE (issue 12; src/modules/commander/Commander.cpp handle_command answers on its own loop).
DOUBLE_ACKED: dict[str, frozenset[int]] = {"ardupilot": frozenset(), "px4": frozenset({mavlink.MAV_CMD_DO_SET_MODE})}


def autopilot_name(heartbeat_autopilot: int) -> AutopilotName:
    """``MAV_AUTOPILOT_PX4`` -> ``px4``; anything else is taken as ArduPilot."""
    return "px4" if heartbeat_autopilot == mavlink.MAV_AUTOPILOT_PX4 else "ardupilot"


# For a type checker the selection IS a back end (MavlinkPort implements the whole AutopilotPort; the Protocol itself
# would be abstract); at run time it has none of their members, so each public one reaches __getattr__ and the back end.
if TYPE_CHECKING:
    _Port = MavlinkPort
else:
    _Port = object


class Autopilot(_Port):
    """The autopilot port handed to the tree: forwards every intent to the back end of the firmware found (or forced).

    The tree is set up before the autopilot's first HEARTBEAT, so the back end is swapped under it
    when the reader finds the autopilot (:meth:`adopt`); ``forced`` keeps the one given.
    """

    def __init__(
        self, commander: Commander, transfer: MissionTransfer | None, profile: VehicleProfile, *, forced: AutopilotName | None = None
    ) -> None:
        self._commander = commander
        self._transfer = transfer
        self._profile = profile
        self.forced = forced
        self._bound: list[str] = []
        self.backend = BACK_ENDS[forced or "ardupilot"](commander, transfer, profile)
        if forced == "px4":
            self._commander.modes = mode_table(mavlink.MAV_AUTOPILOT_PX4, profile.mav_type)
            self._commander.double_acked = DOUBLE_ACKED["px4"]

    def adopt(self, heartbeat_autopilot: int, mav_type: int) -> None:
        """The reader found the autopilot: use its back end (unless one was forced) and its mode table."""
        name = self.forced or autopilot_name(heartbeat_autopilot)
        if self.forced is not None and name != autopilot_name(heartbeat_autopilot):
            log.warning("the autopilot's heartbeat says %s; %s was forced", autopilot_name(heartbeat_autopilot), name)
        self._commander.modes = mode_table(mavlink.MAV_AUTOPILOT_PX4 if name == "px4" else heartbeat_autopilot, mav_type)
        self._commander.double_acked = DOUBLE_ACKED[name]
        if self._transfer is not None:
            self._transfer.home_slot = name != "px4"
        if name != self.backend.name:
            self.backend = BACK_ENDS[name](self._commander, self._transfer, self._profile)
            log.info("autopilot back end: %s", name)

    def service(self) -> None:
        """Every tick, before the commands are sent: the back end's own traffic (PX4's offboard setpoint stream)."""
        self.backend.service()

    @property
    def backend(self) -> MavlinkPort:
        """The back end of the firmware found (or forced)."""
        return self._backend

    @backend.setter
    def backend(self, backend: MavlinkPort) -> None:
        # Its methods are bound here, as __getattr__ would give them: the tree calls several a tick, and each call would go
        # through __getattr__ (a failed look-up first). Its other members (capabilities, properties) are read at each use.
        for name in self._bound:
            del self.__dict__[name]
        self._backend = backend
        self._bound = [name for name in _methods(type(backend)) if not hasattr(Autopilot, name)]
        for name in self._bound:
            self.__dict__[name] = getattr(backend, name)

    if not TYPE_CHECKING:  # a type checker sees the back end's own signatures (MavlinkPort's) instead

        def __getattr__(self, name: str) -> Any:
            """Every intent and capability of the port, the back end's: one forwarding, whatever the port grows."""
            if name.startswith("_"):  # the back end's own state, and Python's protocols (copy, pickle), are not forwarded
                raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
            return getattr(self.backend, name)


def _methods(backend: type) -> list[str]:
    """The public methods of a back end's class (plain functions, as its class and bases define them last)."""
    names = {name for klass in backend.__mro__ for name in vars(klass) if not name.startswith("_")}
    return sorted(name for name in names if isinstance(inspect.getattr_static(backend, name), FunctionType))
