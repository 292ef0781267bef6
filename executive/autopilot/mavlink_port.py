"""What both MAVLink back ends share: intents sent through the :class:`Commander` and the route through the :class:`MissionTransfer`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import ClassVar

from executive.autopilot.port import Capabilities, FenceSettings, Request, Target, VtolState
from executive.io.mavlink.commander import Commander, command_outcome
from executive.io.mavlink.mission_protocol import (
    MissionItem,
    MissionTransfer,
    first_mismatch,
    horizon_not_on_autopilot,
    route_items,
    route_not_on_autopilot,
)
from executive.mission.model import Waypoint
from executive.world import geo
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, HomePosition, TargetAsk
from executive.world.vehicles import VehicleProfile


class MavlinkPort:
    """The intents every MAVLink autopilot takes the same way; a back end overrides what its firmware does differently."""

    capabilities: Capabilities
    name: ClassVar[str] = ""

    def __init__(self, commander: Commander, transfer: MissionTransfer | None, profile: VehicleProfile) -> None:
        self.commander = commander
        self.transfer = transfer
        self.profile = profile
        self._route_differs = SameAnswer(route_not_on_autopilot)
        self._horizon_differs = SameAnswer(horizon_not_on_autopilot)

    def _request(self, ticket: int, command: int, how: str = "") -> Request:
        return Request(ticket, command_outcome(command), how)

    def mode_name(self, mode: str) -> str:
        return self.commander.modes.canonical(mode)

    def service(self) -> None:
        """What the back end keeps sending between requests (PX4's offboard setpoint stream); every tick, before the commands go out."""

    # -- acked intents -----------------------------------------------------------------------
    def set_mode(self, mode: str) -> Request:
        return self._request(self.commander.set_mode(mode), mavlink.MAV_CMD_DO_SET_MODE, self.mode_name(mode))

    def hold(self) -> Request:
        return self.set_mode(self.capabilities.safe_mode)

    def arm(self, *, force: bool = False) -> Request:
        return self._request(self.commander.arm(force=force), mavlink.MAV_CMD_COMPONENT_ARM_DISARM)

    def disarm(self, *, force: bool = False) -> Request:
        return self._request(self.commander.disarm(force=force), mavlink.MAV_CMD_COMPONENT_ARM_DISARM)

    def reposition(self, lat: float, lon: float, alt_m: float) -> Request:
        return self._request(self.commander.reposition(lat, lon, alt_m), mavlink.MAV_CMD_DO_REPOSITION)

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        return self._request(self.commander.takeoff(alt_m), mavlink.MAV_CMD_NAV_TAKEOFF)

    def land(self, mode: str | None = None) -> Request:
        if mode is not None:
            return self.set_mode(mode)
        return self._request(self.commander.land(), mavlink.MAV_CMD_NAV_LAND)

    def return_home(self) -> Request:
        return self.set_mode("RTL")

    def transition(
        self, to: VtolState, *, mode: str | None, position: GlobalPosition | None, heading_deg: float, mc_mode: str, ahead_m: float
    ) -> Request | None:
        return self._request(self.commander.vtol_transition(to), mavlink.MAV_CMD_DO_VTOL_TRANSITION, "DO_VTOL_TRANSITION")

    def change_speed(self, speed_m_s: float, *, airspeed: bool = False) -> Request:
        return self._request(self.commander.change_speed(speed_m_s, airspeed=airspeed), mavlink.MAV_CMD_DO_CHANGE_SPEED)

    def start_route(self) -> Request:
        return self.set_mode(self.capabilities.route_mode)

    def set_home(self, lat: float | None = None, lon: float | None = None, alt_m: float = 0.0) -> Request:
        return self._request(self.commander.set_home(lat, lon, alt_m), mavlink.MAV_CMD_DO_SET_HOME)

    def cancel(self, request: Request | None) -> bool:
        return request is not None and self.commander.cancel(request.ticket)

    def read_parameter(self, name: str) -> None:
        self.commander.request_parameter(name)

    def mode_asked_at(self, mode: str) -> float | None:
        return self.commander.modes_asked.get(mode)

    @property
    def target_asked(self) -> TargetAsk | None:
        return self.commander.target_asked

    @property
    def takeoff_alt_msl_m(self) -> float | None:
        return self.commander.takeoff_alt_msl_m

    # -- setpoints -----------------------------------------------------------------------------
    def go_to(self, target: Target) -> None:
        if target.altitude_m is not None:
            self.commander.depth_target(target.lat, target.lon, altitude_m=target.altitude_m)
        elif target.depth_m is not None:
            self.commander.depth_target(target.lat, target.lon, depth_m=target.depth_m)
        else:
            self.commander.goto(target.lat, target.lon, target.alt_m)

    def go_to_local(self, north_m: float, east_m: float, down_m: float) -> None:
        self.commander.local_setpoint(north_m, east_m, down_m)

    def hold_depth(self, lat: float, lon: float, *, depth_m: float | None = None, altitude_m: float | None = None) -> None:
        self.commander.depth_target(lat, lon, depth_m=depth_m, altitude_m=altitude_m)

    # -- the autopilot's own route -------------------------------------------------------------
    def route_differs(self, waypoints: Sequence[Waypoint], held: object | None) -> str | None:
        return self._route_differs(waypoints, held)

    @property
    def route_transfer_idle(self) -> bool:
        return self.transfer is None or self.transfer.idle

    def upload_route(self, waypoints: Sequence[Waypoint], home: HomePosition | None) -> int:
        if self.transfer is None:
            raise RuntimeError("no mission transfer on this link")
        return self.transfer.upload(route_items(waypoints), (home.lat, home.lon, home.alt_m) if home else None)

    def horizon_differs(self, waypoints: Sequence[Waypoint], leg: int, horizon: int, held: object | None) -> str | None:
        return self._horizon_differs(waypoints, leg, horizon, held)

    def extend_route(self, waypoints: Sequence[Waypoint]) -> int:
        if self.transfer is None:
            raise RuntimeError("no mission transfer on this link")
        return self.transfer.append(route_items(waypoints))

    def set_route_leg(self, leg: int) -> int:
        if self.transfer is None:
            raise RuntimeError("no mission transfer on this link")
        return self.transfer.set_current(self.capabilities.first_item_seq + leg)

    # -- the autopilot's fence and rally points ---------------------------------------------------
    def upload_zones(self, items: Sequence[object], mission_type: int) -> int:
        if self.transfer is None:
            raise RuntimeError("no mission transfer on this link")
        zone_items: Sequence[MissionItem] = items  # type: ignore[assignment]  # executive.autopilot.fence
        return self.transfer.upload(zone_items, verify=True, mission_type=mission_type)

    def zones_differ(self, items: Sequence[object], held: object) -> str | None:
        sent: Sequence[MissionItem] = items  # type: ignore[assignment]  # executive.autopilot.fence
        return first_mismatch(sent, held)  # type: ignore[arg-type]  # /vehicle/fence_items, /vehicle/rally_items

    #: PARAM_SET carries an integer parameter's bytes in its float (PX4), else its value (ArduPilot).
    bytewise_params: ClassVar[bool] = False

    def set_parameter(self, name: str, value: float, param_type: int) -> None:
        self.commander.set_parameter(name, value, param_type, bytewise=self.bytewise_params)

    def fence_settings(self, *, radius_m: float | None, inclusion_shapes: Sequence[str], held: dict[str, float]) -> FenceSettings:
        return FenceSettings({}, f"the {self.name or 'autopilot'} back end enforces no fence")


class SameAnswer:
    """A comparison of a route with the items the autopilot holds (``/vehicle/mission_items``), answered again without
    comparing while it is asked of the same objects as last time: the tree asks every tick, and they seldom change.

    The answer is a function of the values alone, and these cannot change under the same objects: the waypoints are frozen
    models (compared by identity, and kept, so that no new object takes one's id), the other arguments plain values, and
    the items held a tuple of frozen dataclasses (the mission transfer's). Held items of another type are compared each time.
    """

    def __init__(self, compare: Callable[..., str | None]) -> None:
        self._compare = compare
        #: The last call's waypoints' ids, other arguments and items held, the waypoints (kept) and the answer.
        self._last: tuple[tuple[int, ...], tuple[object, ...], object, tuple[Waypoint, ...], str | None] | None = None

    def __call__(self, waypoints: Sequence[Waypoint], *args: object) -> str | None:
        """``compare(waypoints, *args)``; its last argument is the items held."""
        values, held = args[:-1], args[-1]
        ids = tuple(map(id, waypoints))
        last = self._last
        if last is not None and last[2] is held and last[0] == ids and last[1] == values:
            return last[4]
        answer = self._compare(waypoints, *args)
        if held is None or type(held) is tuple:
            self._last = (ids, values, held, tuple(waypoints), answer)
        return answer


def ahead_of(position: GlobalPosition, heading_deg: float, distance_m: float) -> tuple[float, float]:
    """The point ``distance_m`` ahead of ``position`` on ``heading_deg``."""
    return geo.destination(position.lat, position.lon, heading_deg, distance_m)
