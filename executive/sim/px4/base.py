"""What every simulated PX4 does alike: the commander (modes, arming, failsafes, data links), the navigator, the land detector.

:mod:`executive.sim.px4` lists what is modelled and what is not; a subclass per airframe moves its vehicle
model (:mod:`~executive.sim.px4.vtol`, :mod:`~executive.sim.px4.rover`).
"""

from __future__ import annotations

import dataclasses
import math
from abc import abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import ClassVar

from executive.sim.firmware import DEFAULT_HOME, Command, CommandHandler, Home, valid_latlon
from executive.sim.mission_store import AutopilotMissionState
from executive.sim.px4.mission_store import Px4MissionStore
from executive.sim.px4.modes import NAV_STATE_NAMES, NOT_SIMULATED, PILOT_MODES, PREVENT_ARMING_MODES, PX4_MODE_NUMBERS
from executive.sim.px4.parameters import (
    AT_REST_AFTER_S,
    COM_DISARM_LAND,
    COM_DISARM_PRFLT,
    COM_DL_LOSS_T,
    COM_FAIL_ACT_T,
    COM_OBC_LOSS_T,
    COM_OF_LOSS_T,
    COM_SPOOLUP_TIME,
    ESTIMATOR_READY_S,
    FORCE_ARM_DISARM,
    HOME_AMSL_M,
    MIS_TAKEOFF_ALT,
    MISSION_CHECK_S,
    MPC_XY_CRUISE,
    NAV_LOITER_RAD,
    RTL_RETURN_ALT,
    WANT_TAKEOFF_M_S,
)
from executive.sim.px4.streams import Px4Streams
from executive.sim.zone_stores import Px4FenceStore, Px4RallyStore
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.vehicles import VehicleProfile

_M = mavlink

#: Commands the MAVLink receiver answers itself, at once (mavlink_receiver.cpp).
RECEIVER_COMMANDS = frozenset({
    _M.MAV_CMD_SET_MESSAGE_INTERVAL, _M.MAV_CMD_GET_MESSAGE_INTERVAL, _M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
    _M.MAV_CMD_REQUEST_MESSAGE,
})  # fmt: skip

#: HEARTBEAT type -> what the commander says when its heartbeats stop, and when they come back (Commander.cpp).
LINK_LOSS_TEXTS: Mapping[int, tuple[str, str]] = MappingProxyType({
    _M.MAV_TYPE_GCS: ("Connection to ground station lost", "GCS connection regained"),
    _M.MAV_TYPE_ONBOARD_CONTROLLER: ("Connection to mission computer lost", "Onboard controller regained"),
})  # fmt: skip


class Px4Sim(Px4Streams):
    """What every simulated PX4 does alike (see the module's docstring); a subclass per airframe moves its vehicle model.

    ``home_amsl_m`` is the start point's altitude above sea level (NAV_TAKEOFF's param7 counts from
    sea level). Like every simulated autopilot, :meth:`handle` and :meth:`update` return what to send.
    """

    FIRMWARE = "PX4"
    VERSION = "V1.16.0-dev"
    BOOT_MODE = INITIAL_MODE = "AUTO.LOITER"
    MISSION_STORE = Px4MissionStore
    ZONE_STORES = (Px4FenceStore, Px4RallyStore)
    PARAM_SET_BYTEWISE = True
    #: navigator/geofence_params.c: GF_ACTION 2 (Hold mode), GF_MAX_HOR_DIST 0 (off); navigator_params.c: NAV_MC_ALT_RAD 0.8 m.
    PARAMS: ClassVar[Mapping[str, float]] = {"GF_ACTION": 2.0, "GF_MAX_HOR_DIST": 0.0, "NAV_MC_ALT_RAD": 0.8}
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset({"GF_ACTION"})
    AUTOPILOT_MODES = frozenset({"AUTO.LOITER", "AUTO.MISSION", "AUTO.RTL", "AUTO.LAND", "AUTO.TAKEOFF", "OFFBOARD"})
    MAV_TYPE: ClassVar[int]
    FLIES: ClassVar[bool]  # takes off and lands (mission take-off and landing items are passed over otherwise)
    UNAVAILABLE_MODES: ClassVar[frozenset[str]] = frozenset()  # modes this airframe has not
    # src/modules/mavlink/streams/BATTERY_STATUS.hpp: energy_consumed -1; battery_remaining from src/lib/battery/battery.cpp's
    # estimate, which starts from the voltage at rest (a pack not fully charged reads so)
    BATTERY_COUNTED_FROM_FULL = False
    BATTERY_REPORTS_ENERGY = False
    BATTERY_CAPACITY_PARAM = "BAT1_CAPACITY"

    def battery_params(self, capacity_mah: float) -> dict[str, float]:
        """The pack as src/lib/battery/module.yaml names it: BAT1_CAPACITY mAh, BAT1_N_CELLS, per-cell V_EMPTY and V_CHARGED
        (defaults); and RTL_RETURN_ALT, read with them (the way home's climb)."""
        cells = float(self.battery.spec.cells)
        return {"BAT1_CAPACITY": capacity_mah, "BAT1_N_CELLS": cells, "BAT1_V_EMPTY": 3.6, "BAT1_V_CHARGED": 4.05, "RTL_RETURN_ALT": RTL_RETURN_ALT}

    def __init__(
        self,
        profile: VehicleProfile,
        clock: Clock,
        home: Home = DEFAULT_HOME,
        *,
        home_amsl_m: float = HOME_AMSL_M,
        ekf_ready_after_s: float = ESTIMATOR_READY_S,
        **options: float,
    ) -> None:
        self.home_amsl_m = home_amsl_m
        self._pending: list[tuple[Command, tuple[int, int]]] = []  # commands for the commander's next loop
        self._goal: tuple[float, float, float] | None = None  # lat, lon, height above home the mode flies to
        self._goal_radius, self._landing = NAV_LOITER_RAD, False
        self._takeoff_alt: float | None = None  # AUTO.TAKEOFF's height above home
        self._takeoff_point: tuple[float, float] | None = None  # NAV_TAKEOFF's finite param5/param6; None: here
        self._offboard_at = -math.inf  # when the last setpoint came (elapsed s)
        self._offboard_goal: tuple[float, float, float] | None = None
        self._failsafe_at: float | None = None  # when the offboard failsafe began
        self.mode_after_disarm = "AUTO.LOITER"  # UserModeIntention::_nav_state_after_disarming
        self._armed_at, self._taken_off, self._landed = 0.0, False, True
        self._landed_at: float | None = None
        self._moved_at = -math.inf  # the last time the land detector saw the vehicle move (or in the air)
        self._mission_item: tuple[int | None, object] | None = None
        # Commander::dataLinkCheck: HEARTBEAT type -> (last seen, lost), for a ground station and a mission computer
        self._links: dict[int, tuple[float, bool]] = {}
        profile = dataclasses.replace(profile, mav_type=self.MAV_TYPE, modes=MappingProxyType(dict(PX4_MODE_NUMBERS)))
        super().__init__(profile, clock, home, ekf_ready_after_s=ekf_ready_after_s, **options)

    # -- the state PX4 reports ---------------------------------------------------------------------

    @property
    def landed(self) -> bool:
        """The land detector: on the ground and not climbing away from it."""
        return self._landed

    @property
    def at_rest(self) -> bool:
        """LandDetector.cpp: landed, no movement (no vibration: disarmed) for :data:`AT_REST_AFTER_S` (the estimator's ``vehicle_at_rest``)."""
        return self._landed and self.elapsed_s - self._moved_at > AT_REST_AFTER_S

    @property
    def landed_state(self) -> int:
        if self._landed:
            return _M.MAV_LANDED_STATE_ON_GROUND
        if self.mode == "AUTO.TAKEOFF":
            return _M.MAV_LANDED_STATE_TAKEOFF
        if self._landing:
            return _M.MAV_LANDED_STATE_LANDING
        return _M.MAV_LANDED_STATE_IN_AIR

    @property
    def in_failsafe(self) -> bool:
        return self._failsafe_at is not None

    def can_arm(self) -> bool:
        """What the health and arming checks say now (SYS_STATUS MAV_SYS_STATUS_PREARM_CHECK)."""
        return self.booted and self.position_ok and self._can_run(self.mode)

    def _system_status(self) -> int:
        if not self.booted:
            return _M.MAV_STATE_BOOT
        if self.in_failsafe:
            return _M.MAV_STATE_CRITICAL
        return _M.MAV_STATE_ACTIVE if self.armed else _M.MAV_STATE_STANDBY

    def _desired_location(self) -> tuple[float, float] | None:
        return None if self._goal is None else self._goal[:2]

    # -- modes -----------------------------------------------------------------------------------

    def _can_run(self, mode: str) -> bool:
        """The mode's requirements (ModeChecks): what makes "Switching to X is currently not available"."""
        if mode in PILOT_MODES or mode in NOT_SIMULATED or mode in self.UNAVAILABLE_MODES or mode not in PX4_MODE_NUMBERS:
            return False
        if not self.position_ok:
            return False
        if mode == "OFFBOARD":
            return self.offboard_signal
        if mode == "AUTO.MISSION":
            checked = self.mission.uploaded_at is None or self.clock.now() - self.mission.uploaded_at >= MISSION_CHECK_S
            return self.mission.present and checked and self.mission.feasible(int(self.params.get("MIS_TKO_LAND_REQ", 0)), self._landed)
        return mode != "AUTO.RTL" or self.home is not None

    @property
    def offboard_signal(self) -> bool:
        """A setpoint came less than COM_OF_LOSS_T ago."""
        return self.elapsed_s - self._offboard_at < COM_OF_LOSS_T

    def request_mode(self, mode: str) -> bool:
        """A user's mode change (the commander's user intention): STATUSTEXT and False when the mode cannot run."""
        if mode == self.mode and self._failsafe_at is None:
            return True
        if not self._can_run(mode):
            # Commander::printRejectMode
            self._text(_M.MAV_SEVERITY_CRITICAL, f"Switching to {NAV_STATE_NAMES.get(mode, mode)} is currently not available")
            return False
        self._failsafe_at = None  # a user's mode change ends the failsafe
        self._user_intends(mode)
        self._switch(mode)
        return True

    def _user_intends(self, mode: str) -> None:
        """UserModeIntention::change: the user's mode, kept for after disarming unless it prevents arming."""
        if mode not in PREVENT_ARMING_MODES:
            self.mode_after_disarm = mode

    def set_mode(self, number: int) -> bool:
        name = self._mode_names.get(number)
        return name is not None and self.request_mode(name)

    def _switch(self, mode: str) -> None:
        if self.mode == "AUTO.MISSION" and mode != "AUTO.MISSION":
            self.mission.stop()
        self.mode = mode
        self._enter_mode(mode)

    def _enter_mode(self, mode: str) -> bool:
        v = self.vehicle
        self._landing = False
        if mode == "AUTO.LOITER" or mode == "POSCTL":
            self._hold_here()
        elif mode == "AUTO.LAND":
            self._start_landing()
        elif mode == "AUTO.RTL":
            assert self.home is not None
            self._fly_to(*self.home, max(RTL_RETURN_ALT, v.alt_m))
        elif mode == "AUTO.TAKEOFF":
            if self._takeoff_alt is None:
                self._takeoff_alt = MIS_TAKEOFF_ALT
            self._goal = (v.lat, v.lon, max(self._takeoff_alt, v.alt_m))
            if self.armed and self._wants_takeoff():
                self._steer()
        elif mode == "OFFBOARD":
            if self._offboard_goal is not None:
                self._fly_to(*self._offboard_goal)
            else:
                self._hold_here()
        elif mode == "AUTO.MISSION":
            self._mission_item = None
            self.mission.start_or_resume()
        return True

    def _wants_takeoff(self) -> bool:
        """FlightTaskAuto: on the ground, the straight path to the take-off point must climb faster than 0.3 m/s to lift off.

        Along the path at MPC_XY_CRUISE the upward speed is its share of the climb in the 3-D distance: a point
        thousands of kilometres off (0, 0 sent as "no position") gives none, and the vehicle stays on the ground.
        The simulated climb goes straight up all the same (the path towards a near point is not modelled).
        """
        if self._takeoff_point is None or not self._landed:
            return True
        v, goal = self.vehicle, self._goal
        assert goal is not None
        climb, across = goal[2] - v.alt_m, v.distance_to(*self._takeoff_point)
        return climb > 0 and MPC_XY_CRUISE * climb / math.hypot(climb, across) > WANT_TAKEOFF_M_S

    # -- where the vehicle goes ------------------------------------------------------------------

    def _fly_to(self, lat: float, lon: float, alt: float, radius: float = NAV_LOITER_RAD) -> None:
        """Go to a point and hold there: hover over it (multicopter) or circle it (fixed wing)."""
        self._goal, self._goal_radius = (lat, lon, max(0.0, alt)), radius
        if self._landed and self.mode not in ("AUTO.TAKEOFF", "OFFBOARD"):
            return  # the navigator does not take off to go somewhere; OFFBOARD to a point above does (MulticopterPositionControl want_takeoff)
        self._steer()

    # -- transitions (vtol_att_control) ----------------------------------------------------------

    # -- the airframe (each PX4 vehicle's own) --------------------------------------------------

    @property
    def vtol_state(self) -> int:
        """EXTENDED_SYS_STATE vtol_state (MAV_VTOL_STATE): UNDEFINED but on a VTOL."""
        return _M.MAV_VTOL_STATE_UNDEFINED

    @abstractmethod
    def _hold_here(self) -> None:
        """Stop where the vehicle can, and hold there (sets the goal)."""

    @abstractmethod
    def _steer(self) -> None:
        """Give the vehicle model the order that takes it to the goal."""

    @abstractmethod
    def _start_landing(self) -> None:
        """Land (or stop) where the vehicle is."""

    @abstractmethod
    def _detect_landed(self) -> bool:
        """The land detector's verdict now."""

    @abstractmethod
    def _reached(self, lat: float, lon: float, alt: float) -> bool:
        """A mission waypoint is reached."""

    def _climbing_first(self, alt: float) -> bool:
        """A mission's item started on the ground: True (the item not started yet) while the airframe climbs to ``alt`` first."""
        return False

    def _update_airframe(self) -> None:
        """What the airframe does on its own each step (transitions)."""

    def _update_return(self, lat: float, lon: float) -> None:
        """On the way home (RTL) or to a mission landing point: land once over it."""

    def _transition_to(self, state: int) -> None:
        """A VTOL transition (MAV_VTOL_STATE_FW or _MC); nothing on other airframes."""

    # -- the commander's loop --------------------------------------------------------------------

    def update(self) -> list[MAVLinkMessage]:
        pending, self._pending = self._pending, []
        for cmd, sender in pending:
            handler = self._commands.get(cmd.command)
            result = handler(cmd) if handler is not None else _M.MAV_RESULT_UNSUPPORTED
            if result is not None:  # some refusals are not answered at all
                self._emit(self._mav.command_ack_encode(cmd.command, result, 0, 0, *sender))
        return super().update()

    def _update_mode(self) -> None:
        self._update_links()
        self._update_land_detector()
        if not self.armed:
            return
        self._update_airframe()
        self._update_offboard_failsafe()
        if self.mode == "AUTO.TAKEOFF" and self._goal is not None and self._takeoff_reached(self._goal[2]) and not self._landed:
            self._takeoff_alt, self._takeoff_point, there = None, None, self._goal
            self._user_intends("AUTO.LOITER")
            self._switch("AUTO.LOITER")  # the takeoff is done: loiter there (Commander::checkForMissionUpdate)
            self._fly_to(*there)
        elif self.mode == "AUTO.RTL" and not self._landing and self.home is not None:
            self._update_return(*self.home)
        elif self.mode == "AUTO.MISSION":
            self._update_mission()
        self._auto_disarm()

    def _takeoff_reached(self, takeoff_alt_m: float) -> bool:
        """navigator/mission_block.cpp, NAV_CMD_TAKEOFF on a rotary wing (a VTOL's): above it less NAV_MC_ALT_RAD (or half of it if less)."""
        radius = self.params["NAV_MC_ALT_RAD"]
        return self.vehicle.alt_m > takeoff_alt_m - (takeoff_alt_m / 2.0 if 0.0 < takeoff_alt_m < radius else radius)

    def _update_land_detector(self) -> None:
        v = self.vehicle
        landed = self._detect_landed()
        if self.armed and landed and not self._landed and self._taken_off:
            self._text(_M.MAV_SEVERITY_INFO, "Landing detected")
            self._landed_at = self.elapsed_s
        elif self.armed and self._landed and not landed:
            self._text(_M.MAV_SEVERITY_INFO, "Takeoff detected")
            self._taken_off = True
            self.home = self.home or (v.lat, v.lon)
        self._landed = landed
        if not landed or self.armed or abs(v.speed_m_s) > 0.05 or abs(v.velocity_ned[2]) > 0.05:
            self._moved_at = self.elapsed_s  # LandDetector::UpdateVehicleAtRest: the motors' vibration is movement too

    def _auto_disarm(self) -> None:
        if not self._taken_off and self.elapsed_s - self._armed_at >= COM_SPOOLUP_TIME + COM_DISARM_PRFLT:
            self.disarm("auto preflight disarming")
        elif self._taken_off and self._landed and self._landed_at is not None and self.elapsed_s - self._landed_at >= COM_DISARM_LAND:
            self.disarm("landing")

    def _update_offboard_failsafe(self) -> None:
        if self.mode == "OFFBOARD" and not self.offboard_signal:
            # no RC: the offboard fallback is position mode (COM_OBL_RC_ACT 0), then the RC-loss action, landing
            self._text(_M.MAV_SEVERITY_CRITICAL, "Failsafe activated: no offboard signal")  # wording ours: PX4 reports it as an event
            self._failsafe_at = self.elapsed_s
            self.mode = "POSCTL"
            self._hold_here()
        elif self.mode == "POSCTL" and self._failsafe_at is not None and self.elapsed_s - self._failsafe_at >= COM_FAIL_ACT_T:
            self.mode = "AUTO.LAND"
            self._start_landing()

    def _update_mission(self) -> None:
        v = self.vehicle
        item = self.mission.current
        if item is None:
            if self.mission.state is AutopilotMissionState.COMPLETE and not self._landed and self._goal is not None:
                self._user_intends("AUTO.LOITER")
                self._switch("AUTO.LOITER")  # Commander::checkForMissionUpdate: a finished mission loiters
            return
        key = (self.mission.current_seq, item)
        alt = item.alt_cm / 100.0 - (self.home_amsl_m if item.frame in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT) else 0.0)
        here = (item.lat_e7 == 0 and item.lon_e7 == 0) or not valid_latlon(item.lat_e7 * 1e-7, item.lon_e7 * 1e-7)
        lat, lon = (v.lat, v.lon) if here else (item.lat_e7 * 1e-7, item.lon_e7 * 1e-7)
        started = self._mission_item == key
        self._mission_item = key
        cmd = item.command
        if cmd in (_M.MAV_CMD_NAV_TAKEOFF, _M.MAV_CMD_NAV_VTOL_TAKEOFF) and self.FLIES:
            if not started:
                self._goal = (v.lat, v.lon, alt)
                self._steer()
            elif v.alt_m >= alt - 0.5:
                self.mission.advance()
        elif cmd == _M.MAV_CMD_NAV_WAYPOINT or cmd == _M.MAV_CMD_NAV_LOITER_UNLIM:
            if not started and not self._climbing_first(alt):
                self._fly_to(lat, lon, alt)
            elif cmd == _M.MAV_CMD_NAV_WAYPOINT and self._reached(lat, lon, alt):
                self.mission.advance()
        elif cmd in (_M.MAV_CMD_NAV_LAND, _M.MAV_CMD_NAV_VTOL_LAND) and self.FLIES:
            if not started:
                self._fly_to(lat, lon, v.alt_m)
            elif self._landing and self._landed:
                self.mission.advance()
            elif not self._landing:
                self._update_return(lat, lon)  # over the point: land there
        elif cmd == _M.MAV_CMD_DO_VTOL_TRANSITION and self.vtol_state != _M.MAV_VTOL_STATE_UNDEFINED:
            if not started:
                self._transition_to(int(item.params[0] + 0.5))
            elif self.vtol_state in (_M.MAV_VTOL_STATE_MC, _M.MAV_VTOL_STATE_FW):
                self.mission.advance()
        else:  # not simulated: passed over
            self.mission.advance()

    # -- time-driven behaviour -------------------------------------------------------------------

    def _events(self) -> None:
        if not self._booted and self.elapsed_s >= self.boot_s - 1e-6:
            self._booted = True
            self.mode = self.INITIAL_MODE
        if not self._origin_set and self.position_ok:
            self._origin_set = True
            self.home = (self.vehicle.lat, self.vehicle.lon)  # PX4 sets home once the position is valid, landed
            self._emit(self._msg_home_position())

    # -- incoming messages -----------------------------------------------------------------------

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {
            **super()._message_handlers(),
            "SET_MODE": self._on_set_mode,
            "SET_POSITION_TARGET_LOCAL_NED": self._on_setpoint,
            "SET_POSITION_TARGET_GLOBAL_INT": self._on_setpoint,
            "HEARTBEAT": self._on_heartbeat,
        }

    def _on_heartbeat(self, msg: MAVLinkMessage) -> None:
        """Commander::dataLinkCheck: a ground station's or a mission computer's HEARTBEAT keeps its link up."""
        if msg.type not in LINK_LOSS_TEXTS:
            return
        _, lost = self._links.get(msg.type, (0.0, False))
        if lost:
            self._text(_M.MAV_SEVERITY_INFO, LINK_LOSS_TEXTS[msg.type][1])
        self._links[msg.type] = (self.elapsed_s, False)

    def _update_links(self) -> None:
        for kind, (seen_at, lost) in self._links.items():
            timeout = COM_DL_LOSS_T if kind == _M.MAV_TYPE_GCS else COM_OBC_LOSS_T
            if not lost and self.elapsed_s - seen_at > timeout:
                self._links[kind] = (seen_at, True)
                severity = _M.MAV_SEVERITY_INFO if kind == _M.MAV_TYPE_GCS else _M.MAV_SEVERITY_CRITICAL
                self._text(severity, LINK_LOSS_TEXTS[kind][0])

    def _on_command(self, msg: MAVLinkMessage) -> None:
        if msg.command in RECEIVER_COMMANDS:
            super()._on_command(msg)  # answered by the MAVLink receiver itself, at once
            return
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if msg.command == _M.MAV_CMD_DO_SET_MODE:
            # mavlink_receiver.cpp handle_message_command_both publishes DO_SET_MODE to the commander *and* keeps
            # send_ack (ACCEPTED): the receiver's ACCEPTED now, the commander's real result on its next loop
            self._emit(self._mav.command_ack_encode(msg.command, _M.MAV_RESULT_ACCEPTED, 0, 0, *sender))
        self._pending.append((self._command_of(msg), sender))

    def _on_set_mode(self, msg: MAVLinkMessage) -> None:
        # mavlink_receiver.cpp handle_message_set_mode: a VEHICLE_CMD_DO_SET_MODE for the commander
        main, sub = (msg.custom_mode >> 16) & 0xFF, (msg.custom_mode >> 24) & 0xFF
        cmd = Command(_M.MAV_CMD_DO_SET_MODE, (float(msg.base_mode), float(main), float(sub), 0.0, 0.0, 0.0, 0.0), False)
        self._pending.append((cmd, (msg.get_srcSystem(), msg.get_srcComponent())))

    def _on_setpoint(self, msg: MAVLinkMessage) -> None:
        """SET_POSITION_TARGET_*: any setpoint keeps the offboard signal alive; in OFFBOARD a position is flown to."""
        local = msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
        values = (msg.vx, msg.vy, msg.vz, msg.afx, msg.afy, msg.afz, msg.yaw, *((msg.x, msg.y, msg.z) if local else (msg.alt,)))
        if not all(math.isfinite(value) for value in values):
            return  # mavlink_receiver.cpp: a setpoint with any non-finite value is dropped whole, ignored fields too
        goal = None
        if not msg.type_mask & 0x7:  # any position bit set: the position is ignored
            if local:
                if msg.coordinate_frame != _M.MAV_FRAME_LOCAL_NED:
                    return
                lat, lon = self.vehicle._latlon(msg.x, msg.y)
                goal = (lat, lon, -msg.z)
            else:
                frames = {_M.MAV_FRAME_GLOBAL_INT: self.home_amsl_m, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: 0.0}
                if msg.coordinate_frame not in frames or not valid_latlon(msg.lat_int * 1e-7, msg.lon_int * 1e-7):
                    return
                goal = (msg.lat_int * 1e-7, msg.lon_int * 1e-7, msg.alt - frames[msg.coordinate_frame])
        self._offboard_at = self.elapsed_s
        if goal is not None:
            self._offboard_goal = goal
            if self.mode == "OFFBOARD" and goal != self._goal:
                self._fly_to(*goal)

    # -- commands (the commander, the navigator, vtol_att_control) --------------------------------

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_SET_MODE: self._cmd_set_mode,
            _M.MAV_CMD_COMPONENT_ARM_DISARM: self._cmd_arm_disarm,
            _M.MAV_CMD_NAV_TAKEOFF: self._cmd_takeoff,
            _M.MAV_CMD_NAV_LAND: lambda cmd: self._mode_command("AUTO.LAND", "Landing at current position"),
            _M.MAV_CMD_NAV_RETURN_TO_LAUNCH: lambda cmd: self._mode_command("AUTO.RTL", "Returning to launch"),
            _M.MAV_CMD_DO_REPOSITION: self._cmd_reposition,
            _M.MAV_CMD_MISSION_START: self._cmd_mission_start,
        }

    def _mode_command(self, mode: str, announce: str = "") -> int:
        if not self.request_mode(mode):
            return _M.MAV_RESULT_TEMPORARILY_REJECTED
        if announce:
            self._text(_M.MAV_SEVERITY_INFO, announce)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_set_mode(self, cmd: Command) -> int:
        """Commander::handle_command, VEHICLE_CMD_DO_SET_MODE: param2 the main mode, param3 the sub mode."""
        base_mode, main, sub = int(cmd.params[0]), int(cmd.params[1]), int(cmd.params[2])
        if not base_mode & _M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return _M.MAV_RESULT_ACCEPTED  # no custom mode and no base-mode mapping here: nothing changes, yet ACCEPTED
        if main == 4 and sub == 0:
            sub = 4  # AUTO without a sub mode is the mission
        name = self._mode_names.get((main << 16) | (sub << 24) if main == 4 else main << 16)
        if name is None:
            if main == 4:
                self._text(_M.MAV_SEVERITY_CRITICAL, "Unsupported auto mode")
                return _M.MAV_RESULT_TEMPORARILY_REJECTED
            return _M.MAV_RESULT_ACCEPTED  # an unknown main mode changes nothing
        return _M.MAV_RESULT_ACCEPTED if self.request_mode(name) else _M.MAV_RESULT_TEMPORARILY_REJECTED

    def _cmd_arm_disarm(self, cmd: Command) -> int | None:
        action, forced = round(cmd.params[0]), round(cmd.params[1]) == FORCE_ARM_DISARM
        if action == 1:
            if self.armed:
                return _M.MAV_RESULT_ACCEPTED
            if not self.can_arm():  # from outside, the checks run even when forced
                self._text(_M.MAV_SEVERITY_CRITICAL, "Arming denied: Resolve system health failures first")
                return _M.MAV_RESULT_TEMPORARILY_REJECTED
            self.armed = self.vehicle.powered = True
            self._armed_at, self._taken_off, self._landed_at = self.elapsed_s, False, None
            self.home = (self.vehicle.lat, self.vehicle.lon)  # COM_HOME_EN: home where it arms
            self._text(_M.MAV_SEVERITY_INFO, "Armed by external command")
            self._emit(self._msg_home_position())
            if self.mode == "AUTO.TAKEOFF":
                self._enter_mode("AUTO.TAKEOFF")
            return _M.MAV_RESULT_ACCEPTED
        if action == 0:
            if not self.armed:
                return _M.MAV_RESULT_ACCEPTED
            if not forced and not self._landed:
                self._text(_M.MAV_SEVERITY_CRITICAL, "Disarming denied: not landed")
                return _M.MAV_RESULT_TEMPORARILY_REJECTED
            self.disarm()
            return _M.MAV_RESULT_ACCEPTED
        self._text(_M.MAV_SEVERITY_CRITICAL, f"Unsupported ARM_DISARM param: {cmd.params[0]:.3f}")
        return None  # Commander.cpp leaves the result UNSUPPORTED and sends no ack

    def disarm(self, reason: str = "external command") -> None:
        if self.armed:
            self.armed = self.vehicle.powered = False
            self._landing, self._goal, self._failsafe_at = False, None, None
            self._text(_M.MAV_SEVERITY_INFO, f"Disarmed by {reason}")
            if self.mode != self.mode_after_disarm:  # UserModeIntention::onDisarm: disarmed, no failsafe holds another mode
                if self.mode == "AUTO.MISSION":
                    self.mission.stop()
                self.mode = self.mode_after_disarm  # nothing to fly on the ground, disarmed
            self._emit(self._msg_heartbeat())

    def _cmd_takeoff(self, cmd: Command) -> int:
        """NAV_TAKEOFF: param7 the altitude above sea level (NaN: MIS_TAKEOFF_ALT above home); param5/param6, both finite,
        the take-off point (navigator_main.cpp), else here. Acked by the commander whether or not the vehicle will lift off."""
        amsl = cmd.params[6]
        self._takeoff_alt = MIS_TAKEOFF_ALT if math.isnan(amsl) else amsl - self.home_amsl_m
        lat, lon = cmd.lat_lon
        self._takeoff_point = (lat, lon) if math.isfinite(lat) and math.isfinite(lon) else None
        if self.mode == "AUTO.TAKEOFF":
            self._enter_mode("AUTO.TAKEOFF")
            return _M.MAV_RESULT_ACCEPTED
        return _M.MAV_RESULT_ACCEPTED if self.request_mode("AUTO.TAKEOFF") else _M.MAV_RESULT_TEMPORARILY_REJECTED

    def _cmd_reposition(self, cmd: Command) -> int:
        """Commander.cpp: only with the change-mode flag (and no other bit); the navigator flies there in AUTO.LOITER.

        Latitude and longitude NaN keep the position (navigator_main.cpp)."""
        flags = int(cmd.params[1])
        if not flags & _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE or flags & ~_M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE:
            return _M.MAV_RESULT_UNSUPPORTED
        if not self.request_mode("AUTO.LOITER"):
            return _M.MAV_RESULT_TEMPORARILY_REJECTED
        v = self.vehicle
        lat, lon = cmd.lat_lon
        if not (math.isfinite(lat) and math.isfinite(lon)) or not valid_latlon(lat, lon):
            lat, lon = v.lat, v.lon
        # navigator_main.cpp: param7 is the altitude above sea level whatever the COMMAND_INT's frame (NaN: keep it)
        alt = cmd.params[6] - self.home_amsl_m if math.isfinite(cmd.params[6]) else v.alt_m
        radius = cmd.params[2] if math.isfinite(cmd.params[2]) and cmd.params[2] > 0 else NAV_LOITER_RAD
        self._fly_to(lat, lon, alt, radius)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_mission_start(self, cmd: Command) -> int:
        if not self.mission.present:
            self._text(_M.MAV_SEVERITY_CRITICAL, "Mission start denied! No valid mission")
            return _M.MAV_RESULT_DENIED
        if not self.request_mode("AUTO.MISSION"):
            return _M.MAV_RESULT_TEMPORARILY_REJECTED
        self._cmd_arm_disarm(Command(_M.MAV_CMD_COMPONENT_ARM_DISARM, (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), False))
        return _M.MAV_RESULT_ACCEPTED if self.armed else _M.MAV_RESULT_TEMPORARILY_REJECTED

    # -- outgoing messages -----------------------------------------------------------------------
