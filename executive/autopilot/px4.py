"""The PX4 back end of the autopilot port."""

from __future__ import annotations

import math

from executive.autopilot.mavlink_port import MavlinkPort
from executive.autopilot.port import Capabilities, Request
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.dialect import mavlink
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.state import GlobalPosition, HomePosition
from executive.vehicles import VehicleProfile

#: Vehicle kinds PX4 drives (of ours): VTOL and rover; it has no ArduSub equivalent.
PX4_VEHICLES = frozenset({"vtol", "rover"})


class Px4Port(MavlinkPort):
    """PX4: main/sub modes in ``custom_mode``, NAV_TAKEOFF above sea level, VTOL transitions by command in flight."""

    name = "px4"

    def __init__(self, commander: Commander, transfer: MissionTransfer | None, profile: VehicleProfile) -> None:
        super().__init__(commander, transfer, profile)
        self.capabilities = Capabilities(
            autopilot="px4",
            safe_mode="AUTO.LOITER",
            guided_mode="OFFBOARD",
            route_mode="AUTO.MISSION",
            vehicles=PX4_VEHICLES,
            transition_anywhere=True,
            takeoff_alt_amsl=True,
        )

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        # param7 is an altitude above sea level: home's plus the height (NaN: PX4's default take-off altitude)
        amsl = home.alt_m + alt_m if home is not None else math.nan
        return self._request(self.commander.takeoff(amsl), mavlink.MAV_CMD_NAV_TAKEOFF)
