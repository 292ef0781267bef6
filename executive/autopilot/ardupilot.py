"""The ArduPilot back end of the autopilot port (ArduRover, ArduSub, ArduPlane QuadPlane)."""

from __future__ import annotations

from collections.abc import Sequence

from executive.autopilot.mavlink_port import MavlinkPort, ahead_of
from executive.autopilot.port import Capabilities, FenceSettings, Request, VtolState
from executive.autopilot.rover_motion import MOTION_PARAMS
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, HomePosition
from executive.world.vehicles import AUTOPILOT_VEHICLES, VehicleProfile

#: The RC channel that sets the mode by itself, per firmware (0 disables it): ArduRover MODE_CH (Rover/Parameters.cpp,
#: default MODE_CHANNEL 8 in Rover/config.h), ArduPlane FLTMODE_CH (ArduPlane/Parameters.cpp, default 8). ArduSub has
#: none: its modes come from joystick buttons. RC_Channels::flight_mode_channel() takes no channel for 0 or less. By the
#: HEARTBEAT type the firmware reports (a plugin's kind declares its own), so a kind is known by what it is, not its name.
_ROVER_TYPES = frozenset({mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_TYPE_SURFACE_BOAT})
_PLANE_TYPES = frozenset({mavlink.MAV_TYPE_FIXED_WING, mavlink.MAV_TYPE_VTOL_QUADROTOR, mavlink.MAV_TYPE_VTOL_TILTROTOR})
MODE_SWITCH_PARAMS = {**dict.fromkeys(_ROVER_TYPES, "MODE_CH"), **dict.fromkeys(_PLANE_TYPES, "FLTMODE_CH")}

#: libraries/AC_Fence/AC_Fence.cpp: FENCE_TYPE bit 1 the circle centred on home (FENCE_RADIUS), bit 2 the uploaded inclusion and
#: exclusion polygons and circles; FENCE_OPTIONS bit 1 (2) makes several inclusion shapes a union (AC_PolyFence_loader.cpp
#: breached: an intersection without it); FENCE_ACTION {Rover} 2 Hold (Rover/fence.cpp fence_check: set_mode(mode_hold)).
FENCE_TYPE_CIRCLE, FENCE_TYPE_POLYGON, FENCE_OPTION_INCLUSION_UNION, ROVER_FENCE_ACTION_HOLD = 2, 4, 2, 2
_INT = mavlink.MAV_PARAM_TYPE_INT32
_REAL = mavlink.MAV_PARAM_TYPE_REAL32


class ArduPilotPort(MavlinkPort):
    """ArduPilot: modes named per vehicle firmware, NAV_TAKEOFF above home, VTOL transitions by mode outside AUTO."""

    name = "ardupilot"

    def __init__(self, commander: Commander, transfer: MissionTransfer | None, profile: VehicleProfile) -> None:
        super().__init__(commander, transfer, profile)
        self.capabilities = Capabilities(
            autopilot="ardupilot",
            safe_mode=profile.safe_mode,
            guided_mode=profile.guided_mode,
            route_mode="AUTO",
            vehicles=AUTOPILOT_VEHICLES["ardupilot"],
            transition_anywhere=False,
            takeoff_alt_amsl=False,
            first_item_seq=1,
            mode_switch_param=MODE_SWITCH_PARAMS.get(profile.mav_type),
            motion_params=MOTION_PARAMS if profile.mav_type in _ROVER_TYPES else (),
            # libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp: MONITOR (0 none, 3 voltage only, 4 voltage and current...),
            # CAPACITY (mAh, 3300 by default), ARM_MAH and ARM_VOLT (what arming requires; 0: nothing)
            battery_params=("BATT_MONITOR", "BATT_CAPACITY", "BATT_ARM_MAH", "BATT_ARM_VOLT"),
            fence_params=("FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION", "FENCE_RADIUS", "FENCE_OPTIONS"),
        )

    def fence_settings(self, *, radius_m: float | None, inclusion_shapes: Sequence[str], held: dict[str, float]) -> FenceSettings:
        """ArduRover: FENCE_ENABLE 1, FENCE_TYPE's circle and polygon bits as the mission has them (other bits kept), FENCE_RADIUS
        the mission's max_distance_from_home_m, FENCE_ACTION 2 (Hold), FENCE_OPTIONS' union bit with several inclusion shapes."""
        if self.profile.mav_type not in _ROVER_TYPES:
            why = "ArduPlane's and ArduSub's fence actions (RTL, Land) are not a hold: set FENCE_* on the vehicle yourself"
            return FenceSettings({}, f"geofence.autopilot: enforce is built for ArduRover (FENCE_ACTION 2, Hold); {why}")
        fence_type = (int(held.get("FENCE_TYPE", 0)) & ~(FENCE_TYPE_CIRCLE | FENCE_TYPE_POLYGON)) | FENCE_TYPE_POLYGON
        params = {"FENCE_ENABLE": (1.0, _INT), "FENCE_ACTION": (float(ROVER_FENCE_ACTION_HOLD), _INT)}
        if radius_m is not None:
            fence_type |= FENCE_TYPE_CIRCLE
            params["FENCE_RADIUS"] = (radius_m, _REAL)
        params["FENCE_TYPE"] = (float(fence_type), _INT)
        if len(inclusion_shapes) > 1:
            params["FENCE_OPTIONS"] = (float(int(held.get("FENCE_OPTIONS", 0)) | FENCE_OPTION_INCLUSION_UNION), _INT)
        return FenceSettings(params)

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        if airborne and position is not None:
            # ArduPlane refuses NAV_TAKEOFF in the air: the climb goes on with DO_REPOSITION above the vehicle
            # (a QuadPlane with Q_GUIDED_MODE=1 flies it on its lift motors)
            return self.reposition(position.lat, position.lon, alt_m)
        return super().take_off(alt_m, home=home, position=position, airborne=airborne)

    def land(self, mode: str | None = None) -> Request:
        # ArduPlane takes no landing command outside a mission (GCS_MAVLink_Plane.cpp handles neither NAV_LAND nor
        # NAV_VTOL_LAND): a QuadPlane lands where it is in QLAND
        if mode is None and self.profile.kind == "vtol":
            return self.set_mode("QLAND")
        return super().land(mode)

    def transition(
        self, to: VtolState, *, mode: str | None, position: GlobalPosition | None, heading_deg: float, mc_mode: str, ahead_m: float
    ) -> Request | None:
        # ArduPlane takes MAV_CMD_DO_VTOL_TRANSITION in AUTO only (GCS_MAVLink_Plane.cpp handle_command_DO_VTOL_TRANSITION):
        # elsewhere the mode decides
        if mode == "AUTO":
            return super().transition(to, mode=mode, position=position, heading_deg=heading_deg, mc_mode=mc_mode, ahead_m=ahead_m)
        if to == "MC":
            return self.set_mode(mc_mode)
        if position is None:
            return None  # there is no "ahead" without a position
        lat, lon = ahead_of(position, heading_deg, ahead_m)
        request = self.reposition(lat, lon, position.alt_rel_m)
        return Request(request.ticket, request.outcome, f"reposition {ahead_m:g} m ahead")
