"""The autopilot the behaviours talk to: a back end chosen from the HEARTBEAT's ``autopilot`` field, or forced."""

from __future__ import annotations

import logging
from collections.abc import Sequence

from executive.autopilot.ardupilot import ArduPilotPort
from executive.autopilot.mavlink_port import MavlinkPort
from executive.autopilot.port import AutopilotName, Capabilities, FenceSettings, Request, Target, VtolState
from executive.autopilot.px4 import Px4Port
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.modes import mode_table
from executive.mission.model import Waypoint
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, HomePosition, TargetAsk
from executive.world.vehicles import VehicleProfile

log = logging.getLogger(__name__)

BACK_ENDS: dict[str, type[MavlinkPort]] = {"ardupilot": ArduPilotPort, "px4": Px4Port}
#: Commands each firmware acks twice (the first ACCEPTED only says "received"): PX4's MAVLink receiver and then its
#: commander both answer DO_SET_MODE (issue 12; src/modules/commander/Commander.cpp handle_command answers on its own loop).
DOUBLE_ACKED: dict[str, frozenset[int]] = {"ardupilot": frozenset(), "px4": frozenset({mavlink.MAV_CMD_DO_SET_MODE})}


def autopilot_name(heartbeat_autopilot: int) -> AutopilotName:
    """``MAV_AUTOPILOT_PX4`` -> ``px4``; anything else is taken as ArduPilot."""
    return "px4" if heartbeat_autopilot == mavlink.MAV_AUTOPILOT_PX4 else "ardupilot"


class Autopilot:
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
        self.backend: MavlinkPort = BACK_ENDS[forced or "ardupilot"](commander, transfer, profile)
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

    # -- the port, forwarded -------------------------------------------------------------------
    @property
    def capabilities(self) -> Capabilities:
        return self.backend.capabilities

    def mode_name(self, mode: str) -> str:
        return self.backend.mode_name(mode)

    def set_mode(self, mode: str) -> Request:
        return self.backend.set_mode(mode)

    def hold(self) -> Request:
        return self.backend.hold()

    def arm(self, *, force: bool = False) -> Request:
        return self.backend.arm(force=force)

    def disarm(self, *, force: bool = False) -> Request:
        return self.backend.disarm(force=force)

    def reposition(self, lat: float, lon: float, alt_m: float) -> Request:
        return self.backend.reposition(lat, lon, alt_m)

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        return self.backend.take_off(alt_m, home=home, position=position, airborne=airborne)

    def land(self, mode: str | None = None) -> Request:
        return self.backend.land(mode)

    def return_home(self) -> Request:
        return self.backend.return_home()

    def transition(
        self, to: VtolState, *, mode: str | None, position: GlobalPosition | None, heading_deg: float, mc_mode: str, ahead_m: float
    ) -> Request | None:
        return self.backend.transition(to, mode=mode, position=position, heading_deg=heading_deg, mc_mode=mc_mode, ahead_m=ahead_m)

    def change_speed(self, speed_m_s: float, *, airspeed: bool = False) -> Request:
        return self.backend.change_speed(speed_m_s, airspeed=airspeed)

    def start_route(self) -> Request:
        return self.backend.start_route()

    def set_home(self, lat: float | None = None, lon: float | None = None, alt_m: float = 0.0) -> Request:
        return self.backend.set_home(lat, lon, alt_m)

    def cancel(self, request: Request | None) -> bool:
        return self.backend.cancel(request)

    def read_parameter(self, name: str) -> None:
        self.backend.read_parameter(name)

    def mode_asked_at(self, mode: str) -> float | None:
        return self.backend.mode_asked_at(mode)

    @property
    def target_asked(self) -> TargetAsk | None:
        return self.backend.target_asked

    @property
    def takeoff_height_m(self) -> float | None:
        return self.backend.takeoff_height_m

    def go_to(self, target: Target) -> None:
        self.backend.go_to(target)

    def go_to_local(self, north_m: float, east_m: float, down_m: float) -> None:
        self.backend.go_to_local(north_m, east_m, down_m)

    def hold_depth(self, lat: float, lon: float, *, depth_m: float | None = None, altitude_m: float | None = None) -> None:
        self.backend.hold_depth(lat, lon, depth_m=depth_m, altitude_m=altitude_m)

    def route_differs(self, waypoints: Sequence[Waypoint], held: object | None) -> str | None:
        return self.backend.route_differs(waypoints, held)

    @property
    def route_transfer_idle(self) -> bool:
        return self.backend.route_transfer_idle

    def upload_route(self, waypoints: Sequence[Waypoint], home: HomePosition | None) -> int:
        return self.backend.upload_route(waypoints, home)

    def horizon_differs(self, waypoints: Sequence[Waypoint], leg: int, horizon: int, held: object | None) -> str | None:
        return self.backend.horizon_differs(waypoints, leg, horizon, held)

    def extend_route(self, waypoints: Sequence[Waypoint]) -> int:
        return self.backend.extend_route(waypoints)

    def set_route_leg(self, leg: int) -> int:
        return self.backend.set_route_leg(leg)

    def upload_zones(self, items: Sequence[object], mission_type: int) -> int:
        return self.backend.upload_zones(items, mission_type)

    def zones_differ(self, items: Sequence[object], held: object) -> str | None:
        return self.backend.zones_differ(items, held)

    def set_parameter(self, name: str, value: float, param_type: int) -> None:
        self.backend.set_parameter(name, value, param_type)

    def fence_settings(self, *, radius_m: float | None, inclusion_shapes: Sequence[str], held: dict[str, float]) -> FenceSettings:
        return self.backend.fence_settings(radius_m=radius_m, inclusion_shapes=inclusion_shapes, held=held)
