"""ArduSub as the simulated AUV's autopilot: its modes drive an :class:`~executive.sim.physics.underwater.UnderwaterVehicle`.

What follows ArduSub's source (4.x): every mode may be armed; GUIDED, POSHOLD, AUTO and CIRCLE
need a position estimate even disarmed ("Mode change failed: X requires position"); SURFACE climbs
at the waypoint climb speed and switches itself to ALT_HOLD at the surface; GUIDED takes
SET_POSITION_TARGET_GLOBAL_INT with a position in the relative-altitude frames (altitude above
home, negative below the surface); the terrain and absolute frames are ignored; in ALT_HOLD the same message
sets only the depth (``alt`` taken as metres above the EKF origin, whatever the frame).
DO_REPOSITION goes to a point in GUIDED (or switches to it when asked); NAV_LAND means SURFACE and
NAV_LOITER_UNLIM means POSHOLD. The height above the seabed comes from a downward rangefinder,
reported in DISTANCE_SENSOR (orientation PITCH_270) with the EXTRA3 stream; ArduPilot 4.7 no
longer streams the older RANGEFINDER message, which is sent only on request.

The rangefinder (RNGFND1_MIN/RNGFND1_MAX, 0.5-30 m by default) reports the raw distance whatever
its status, in DISTANCE_SENSOR with its range and in RANGEFINDER without (GCS_Common.cpp
send_distance_sensor / send_rangefinder); beyond its maximum the reading is OutOfRangeHigh
(AP_RangeFinder_Backend.cpp update_status), not a height. A terrain-frame GUIDED target is dropped
silently: ArduSub converts it with Location::get_vector_from_origin_NEU_cm, which fails without
terrain data, and the handler breaks (ArduSub/GCS_MAVLink_Sub.cpp, 4.7). SURFTRAK is entered
without a good reading ("waiting for a rangefinder reading") and holds the depth until one comes,
then the height it reads (ArduSub/mode_surftrak.cpp).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import ClassVar

from executive.sim.ardupilot.base import (
    ACC_BITS,
    DEFAULT_INTERVALS,
    GLOBAL_FRAMES,
    POS_BITS,
    RATE_ATTITUDE,
    TARGET_REPORT_MASK,
    ArduPilotSim,
)
from executive.sim.ardupilot.mission_store import ArduPilotMissionStore
from executive.sim.firmware import DEFAULT_HOME, Command, Home, e7, valid_latlon
from executive.sim.mission_store import AutopilotMissionState, StoredCommand
from executive.sim.physics.underwater import SUB_HORIZONTAL_LIMITS, SUB_LIMITS, Seabed, SubLimits, UnderwaterVehicle
from executive.sim.physics.vehicle import VehicleModel
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.vehicles import SUB_MODES, VehicleProfile

_M = mavlink
RELATIVE_FRAMES = frozenset({_M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})
TERRAIN_FRAMES = frozenset({_M.MAV_FRAME_GLOBAL_TERRAIN_ALT, _M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})
SURFACE_DEPTH_M = 0.10  # SURFACE_DEPTH (-10 cm): shallower than this (with 5 cm of margin) the vehicle is at the surface
RANGEFINDER_MIN_M, RANGEFINDER_MAX_M = 0.5, 30.0  # RNGFND1_MIN/RNGFND1_MAX of ArduSub's simulated sonar
RANGEFINDER_REACH_M = 655.35  # DISTANCE_SENSOR's current_distance is 16 bits of cm


#: WPNAV_SPEED and WPNAV_RADIUS as ArduSub sets them (ArduSub/Parameters.h: WPNAV_SPEED 100 cm/s; AC_WPNav.cpp: WPNAV_RADIUS 200 cm).
WPNAV_SPEED_M_S, WPNAV_RADIUS_M = 1.0, 2.0


class ArduSubMissionStore(ArduPilotMissionStore):
    """ArduSub's mission: ArduPilot's store, silent at the mission's end (Sub::exit_mission says nothing, unlike ArduRover), and
    counting MISSION_SET_CURRENTs, which start the item again in AUTO (AP_Mission::set_current_cmd)."""

    starts = 0  # set-currents so far: AUTO starts its item again at each

    def set_current(self, seq: int) -> bool:
        done = super().set_current(seq)
        self.starts += int(done)
        return done

    def _completed(self) -> None:
        """ArduSub announces no mission end."""


class ArduSubSim(ArduPilotSim):
    """ArduSub on a vectored ROV/AUV frame, over a seabed; the seabed and the limits are options.

    MANUAL, STABILIZE and ACRO have no pilot here: the vehicle stops and its buoyancy takes it up.
    ALT_HOLD holds the depth it had when entered (or when armed), POSHOLD the position too. GUIDED
    holds where it can stop until given a target; a target reached is held. SURFTRAK holds the
    height above the seabed it had when entered. AUTO flies the mission (:meth:`_update_auto`); CIRCLE and
    MOTOR_DETECT are not simulated.
    """

    FIRMWARE = "ArduSub"
    BATTERY_OF = "sub"
    READY_TEXT = "Frame: VECTORED_6DOF"
    BOOT_MODE = "MANUAL"  # ArduSub has no INITIALISING mode: it reports its initial mode while booting
    INITIAL_MODE = "MANUAL"
    MANUAL_INPUT_MODES = frozenset(SUB_MODES)  # ArduSub sets MANUAL_INPUT and STABILIZE in every mode
    STABILIZE_MODES = MANUAL_INPUT_MODES
    AUTOPILOT_MODES = frozenset({"AUTO", "GUIDED", "CIRCLE", "POSHOLD"})
    POSITION_MODES = frozenset({"GUIDED", "AUTO", "POSHOLD", "CIRCLE"})  # Mode::requires_GPS()
    DEPTH_HOLD_MODES = frozenset({"ALT_HOLD", "POSHOLD", "GUIDED", "SURFTRAK"})
    NOT_SIMULATED = frozenset({"CIRCLE", "MOTOR_DETECT"})
    MISSION_STORE = ArduSubMissionStore
    STREAMS: ClassVar[Mapping[int, float]] = MappingProxyType({**DEFAULT_INTERVALS, _M.MAVLINK_MSG_ID_DISTANCE_SENSOR: 0.25})

    vehicle: UnderwaterVehicle

    def __init__(
        self,
        profile: VehicleProfile,
        clock: Clock,
        home: Home = DEFAULT_HOME,
        *,
        seabed: Seabed | None = None,
        limits: SubLimits = SUB_LIMITS,
        seabed_depth_m: float | None = None,
        rangefinder_max_m: float = RANGEFINDER_MAX_M,
        **options: float,
    ) -> None:
        """``seabed_depth_m``: a plane seabed that deep under the start (else ``seabed``, else 30 m); ``rangefinder_max_m``: RNGFND1_MAX."""
        if seabed is None and seabed_depth_m is not None:
            seabed = Seabed(depth_m=seabed_depth_m)
        self._seabed = seabed if seabed is not None else Seabed()
        self.rangefinder_max_m = rangefinder_max_m
        self._limits = limits
        self._destination: tuple[float, float] | None = None  # GUIDED's horizontal target
        self._guided_speed: float | None = None
        self._auto_item: tuple[int | None, int, StoredCommand] | None = None  # AUTO's command: (seq, the set-current it began at, item)
        self._auto_reached_at: float | None = None  # when AUTO's waypoint was reached (its hold time counts from there)
        super().__init__(profile, clock, home, **options)
        self.params.update(RNGFND1_MIN=RANGEFINDER_MIN_M, RNGFND1_MAX=rangefinder_max_m)  # answered to PARAM_REQUEST_READ

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return UnderwaterVehicle(home[0], home[1], home[2], self._limits, self._seabed)

    # -- what the firmware reports -----------------------------------------------------------

    @property
    def rangefinder_m(self) -> float | None:
        """The downward rangefinder's good reading (height above the seabed), None out of its range (RangeFinder::Status not Good)."""
        altitude = self.vehicle.altitude_m
        return altitude if RANGEFINDER_MIN_M <= altitude <= self.rangefinder_max_m else None

    @property
    def rangefinder_raw_m(self) -> float:
        """What the sonar measures, in range or not (what ArduPilot reports)."""
        return min(self.vehicle.altitude_m, RANGEFINDER_REACH_M)

    @property
    def at_surface(self) -> bool:
        return self.vehicle.depth_m < SURFACE_DEPTH_M + 0.05

    def _system_status(self) -> int:
        if not self.booted:
            return _M.MAV_STATE_BOOT
        return _M.MAV_STATE_ACTIVE if self.armed else _M.MAV_STATE_STANDBY

    def _control_sensors(self) -> tuple[int, int]:
        """ArduSub/GCS_Sub.cpp: rate, attitude and yaw control always; depth and position control in the modes that hold them."""
        depth_position = _M.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL | _M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
        always = RATE_ATTITUDE | _M.MAV_SYS_STATUS_SENSOR_YAW_POSITION
        holding = self.mode in ("ALT_HOLD", "AUTO", "GUIDED", "CIRCLE", "SURFACE", "POSHOLD", "SURFTRAK")
        return always | depth_position, always | (depth_position if holding else 0)

    def _throttle(self) -> float:
        if not self.armed:
            return 0.0
        vn, ve, vd = self.vehicle.velocity_ned
        return min(1.0, math.hypot(vn, ve) / self._limits.horizontal.max_m_s + abs(vd) / self._limits.descend_m_s)

    def _servo_outputs(self) -> Sequence[int]:
        """Eight bidirectional thrusters: 1-4 horizontal (vectored), 5-8 vertical; 1500 = stopped."""
        outputs = [0] * 16
        vn, ve, vd = self.vehicle.velocity_ned if self.armed else (0.0, 0.0, 0.0)
        forward = math.hypot(vn, ve) / self._limits.horizontal.max_m_s
        down = vd / max(self._limits.descend_m_s, self._limits.climb_m_s)
        outputs[0:4] = [round(1500 + 400 * max(-1.0, min(1.0, forward)))] * 4
        outputs[4:8] = [round(1500 + 400 * max(-1.0, min(1.0, down)))] * 4
        return outputs

    # -- modes -------------------------------------------------------------------------------

    def set_mode(self, number: int) -> bool:
        name = self._mode_names.get(number)
        if name in self.POSITION_MODES and name != self.mode and not self.position_ok:  # checked armed or not, unlike Rover
            self._text(_M.MAV_SEVERITY_WARNING, f"Mode change failed: {name} requires position")
            return False
        return super().set_mode(number)

    def _enter_mode(self, mode: str) -> bool:
        v = self.vehicle
        if mode in self.NOT_SIMULATED:
            return False
        if mode == "AUTO" and not self.mission.present:  # ModeAuto::init: a position and a mission
            return False
        self._destination = None
        v.hold()
        if mode == "SURFTRAK" and self.rangefinder_m is None:
            self._text(_M.MAV_SEVERITY_INFO, "waiting for a rangefinder reading")  # ModeSurftrak::init: entered all the same
            v.hold_depth()
        elif mode == "SURFTRAK":
            v.hold_altitude_at(v.altitude_m)
        elif mode == "SURFACE":
            v.hold_depth_at(0.0)
        elif mode in self.DEPTH_HOLD_MODES:
            v.hold_depth()
        else:
            v.release_depth()
        if mode in ("GUIDED", "AUTO"):
            self._guided_speed = None  # AUTO: wp_and_spline_init_cm, back to WPNAV_SPEED
        if mode == "AUTO":
            self._auto_item = None
            self.mission.start_or_resume()  # MIS_RESTART 0
        return True

    def _update_mode(self) -> None:
        v = self.vehicle
        if self.mode == "AUTO" and self.armed:
            self._update_auto()
        if not self.armed and self.mode in self.DEPTH_HOLD_MODES | {"SURFACE"}:
            # disarmed, the controllers relax: once armed the vehicle holds where it then is
            if v.holding_altitude:
                v.hold_altitude_at(v.altitude_m)
            elif self.mode != "SURFACE":
                v.hold_depth_at(v.depth_m)
        if self.mode == "SURFTRAK" and self.armed and not v.holding_altitude and self.rangefinder_m is not None:
            v.hold_altitude_at(self.rangefinder_m)  # the first good reading sets the target (update_surface_offset)
        if self.mode == "SURFACE" and self.armed and self.at_surface:
            self.set_mode(self.profile.modes["ALT_HOLD"])  # ModeReason::SURFACE_COMPLETE
        elif self.mode == "ALT_HOLD" and self.at_surface and (v.depth_target_m or 0.0) < SURFACE_DEPTH_M + 0.05:
            v.hold_depth_at(SURFACE_DEPTH_M + 0.05)  # ArduSub keeps its depth target 5 cm under SURFACE_DEPTH

    def _update_auto(self) -> None:
        """AUTO flies the mission as ArduSub does (ArduSub/mode_auto.cpp, commands_logic.cpp, AP_Mission).

        A NAV_WAYPOINT: straight to the point at its altitude above home (a depth: an altitude of 0 keeps the
        current depth, do_nav_wp), at WPNAV_SPEED (or DO_CHANGE_SPEED's), every waypoint a stop; reached within
        WPNAV_RADIUS in 3-D (AC_WPNav), then its hold time, "Reached command #N" and MISSION_ITEM_REACHED. Other items
        are passed over. An item rewritten while flown is flown as it began (AP_Mission runs its cached command: no
        mission change detection in ArduSub); MISSION_SET_CURRENT starts it again. After the last: ModeAuto::auto_loiter_start,
        holding the stopping point and its depth in AUTO (Sub::exit_mission), said by no message; without a position,
        ALT_HOLD instead.
        """
        v, mission = self.vehicle, self.mission
        assert isinstance(mission, ArduSubMissionStore)
        item = mission.current
        if item is None:  # complete (or cleared): hold where it stops
            if self._auto_item is not None:
                self._auto_item = self._destination = None
                v.hold()
                v.hold_depth()
                if mission.state is AutopilotMissionState.COMPLETE and not self.position_ok:
                    # Sub::exit_mission (commands_logic.cpp): ModeAuto::auto_loiter_start fails without a position, then
                    # ALT_HOLD (ModeReason::MISSION_END), said by no message
                    self._force_mode("ALT_HOLD")
            return
        seq = mission.current_seq
        if self._auto_item is not None and self._auto_item[:2] == (seq, mission.starts):
            item = self._auto_item[2]  # the command as it began
            if item.command == _M.MAV_CMD_NAV_WAYPOINT and not self._waypoint_reached(item):
                return
            if item.command == _M.MAV_CMD_NAV_WAYPOINT and self.elapsed_s < (self._auto_reached_at or 0.0) + item.params[0]:
                return
            if item.command == _M.MAV_CMD_NAV_WAYPOINT:
                self._text(_M.MAV_SEVERITY_INFO, f"Reached command #{seq}")
            item = mission.advance()
            if item is None:
                self._update_auto()
                return
        self._auto_item, self._auto_reached_at = (mission.current_seq, mission.starts, item), None
        if item.command != _M.MAV_CMD_NAV_WAYPOINT:
            return
        depth = v.depth_m if item.alt_cm == 0 else -item.alt_cm / 100
        self._destination = (item.lat, item.lon)
        v.drive_to(item.lat, item.lon, self._guided_speed or float(self.params.get("WPNAV_SPEED", WPNAV_SPEED_M_S * 100)) / 100)
        v.hold_depth_at(depth)

    def _waypoint_reached(self, item: StoredCommand) -> bool:
        """AC_WPNav: the leg finished and the vehicle within WPNAV_RADIUS of the point, in 3-D; when, remembered.

        Its leg is one 3-D track, finished when its target is at the point in depth too: here, arrived horizontally and
        within the horizontal arrival distance of the depth."""
        if self._auto_reached_at is not None:
            return True
        v = self.vehicle
        depth = v.depth_target_m if v.depth_target_m is not None else v.depth_m
        off = math.hypot(v.distance_to(item.lat, item.lon), v.depth_m - depth)
        finished = v.arrived and abs(v.depth_m - depth) <= SUB_HORIZONTAL_LIMITS.arrive_m
        if finished and off <= float(self.params.get("WPNAV_RADIUS", WPNAV_RADIUS_M * 100)) / 100:
            self._auto_reached_at = self.elapsed_s
            return True
        return False

    def _desired_location(self) -> tuple[float, float] | None:
        if self.mode in ("GUIDED", "POSHOLD") and self.vehicle.target is not None:
            return self.vehicle.target
        return None

    # -- messages ----------------------------------------------------------------------------

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {**super()._message_handlers(), "SET_POSITION_TARGET_GLOBAL_INT": self._on_position_target}

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        return {
            **super()._message_builders(),
            _M.MAVLINK_MSG_ID_DISTANCE_SENSOR: self._msg_distance_sensor,
            _M.MAVLINK_MSG_ID_RANGEFINDER: self._msg_rangefinder,
        }

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
        modes = self.profile.modes
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_REPOSITION: self._cmd_reposition,
            _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed,
            _M.MAV_CMD_NAV_LAND: lambda cmd: self._mode_result(modes["SURFACE"]),
            _M.MAV_CMD_NAV_LOITER_UNLIM: lambda cmd: self._mode_result(modes["POSHOLD"]),
            _M.MAV_CMD_MISSION_START: self._cmd_mission_start,
        }

    def _mode_result(self, number: int) -> int:
        return _M.MAV_RESULT_ACCEPTED if self.set_mode(number) else _M.MAV_RESULT_FAILED

    def _on_position_target(self, msg: MAVLinkMessage) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT: GUIDED goes there, ALT_HOLD takes the depth; never acknowledged."""
        v = self.vehicle
        z_ignored = msg.type_mask & _M.POSITION_TARGET_TYPEMASK_Z_IGNORE
        if self.mode == "ALT_HOLD":
            if not z_ignored:
                v.hold_depth_at(-msg.alt)
            return
        if self.mode != "GUIDED" or not msg.type_mask & ACC_BITS or msg.type_mask & POS_BITS:
            return  # velocity-only targets (pos ignored) are not simulated
        lat, lon = msg.lat_int * 1e-7, msg.lon_int * 1e-7
        if not valid_latlon(lat, lon) or msg.coordinate_frame not in GLOBAL_FRAMES:
            return
        if msg.coordinate_frame in RELATIVE_FRAMES:
            self._go(lat, lon)
            v.hold_depth_at(-msg.alt)
        # the terrain frames: no terrain data under water, get_vector_from_origin_NEU_cm fails: dropped, silently;
        # the absolute frames (GLOBAL, GLOBAL_INT) are not supported by ArduSub's GUIDED

    def _go(self, lat: float, lon: float) -> None:
        self._destination = (lat, lon)
        self.vehicle.drive_to(lat, lon, self._guided_speed)

    def _cmd_reposition(self, cmd: Command) -> int:
        change_mode = int(cmd.params[1]) & _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
        if self.mode != "GUIDED" and not change_mode:
            return _M.MAV_RESULT_DENIED
        lat, lon = cmd.lat_lon
        alt = cmd.params[6]
        # Location::sanitize() fills in a zero lat/lon or a zero relative altitude: ArduSub refuses such a target
        relative_zero = alt == 0.0 and cmd.frame not in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT)
        if not valid_latlon(lat, lon) or (lat == 0.0 and lon == 0.0) or relative_zero:
            return _M.MAV_RESULT_DENIED
        if cmd.frame in TERRAIN_FRAMES or cmd.frame not in GLOBAL_FRAMES:
            return _M.MAV_RESULT_FAILED  # no terrain database under water
        if self.mode != "GUIDED" and not self.set_mode(self.profile.modes["GUIDED"]):
            return _M.MAV_RESULT_FAILED
        self._go(lat, lon)
        self.vehicle.hold_depth_at(-alt)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_change_speed(self, cmd: Command) -> int:
        if cmd.params[1] <= 0:
            return _M.MAV_RESULT_DENIED
        if int(cmd.params[0]) not in (_M.SPEED_TYPE_AIRSPEED, _M.SPEED_TYPE_GROUNDSPEED):
            return _M.MAV_RESULT_DENIED
        self._guided_speed = cmd.params[1]
        if self._destination is not None:
            self.vehicle.drive_to(*self._destination, self._guided_speed)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_mission_start(self, cmd: Command) -> int:
        if any(cmd.params[:2]):
            return _M.MAV_RESULT_DENIED
        return _M.MAV_RESULT_ACCEPTED if self.armed and self.set_mode(self.profile.modes["AUTO"]) else _M.MAV_RESULT_FAILED

    def _msg_distance_sensor(self) -> MAVLinkMessage | None:
        """The raw distance with the sensor's range: the reader judges it (beyond max_distance: not a height)."""
        return self._mav.distance_sensor_encode(
            self._ms(),
            round(RANGEFINDER_MIN_M * 100),
            round(self.rangefinder_max_m * 100),
            round(self.rangefinder_raw_m * 100),
            _M.MAV_DISTANCE_SENSOR_ULTRASOUND,
            0,
            _M.MAV_SENSOR_ROTATION_PITCH_270,
            0,
            signal_quality=0,  # unknown: the sonar backends report no quality
        )

    def _msg_rangefinder(self) -> MAVLinkMessage | None:
        """The raw distance, whatever the sensor's status (GCS_Common.cpp send_rangefinder)."""
        return self._mav.rangefinder_encode(self.rangefinder_raw_m, 0.0)

    def _msg_nav_controller_output(self) -> MAVLinkMessage | None:
        """ArduSub sends it in every mode: the waypoint controller's target, and the depth error."""
        v = self.vehicle
        target = self._desired_location()
        distance, bearing = (v.distance_to(*target), round(v.bearing_to(*target))) if target else (0.0, 0)
        depth_target = v.depth_target_m
        alt_error = 0.0 if depth_target is None else v.depth_m - depth_target
        return self._mav.nav_controller_output_encode(0.0, 0.0, bearing, bearing, min(round(distance), 65535), alt_error, 0.0, 0.0)

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        target = self._desired_location()
        depth_target = self.vehicle.depth_target_m
        if target is None or depth_target is None:
            return None
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL, TARGET_REPORT_MASK, e7(target[0]), e7(target[1]), -depth_target, 0, 0, 0, 0, 0, 0, 0, 0
        )
