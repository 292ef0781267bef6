"""ArduRover as a simulated autopilot: a rover, or a boat (FRAME_CLASS=2), driving a surface vehicle as the firmware's navigation does."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import ClassVar

from executive.autopilot.rover_motion import FIRMWARE_DEFAULTS, RoverMotion
from executive.sim.ardupilot.base import ACC_BITS, GLOBAL_FRAMES, NAVIGATION, POS_BITS, RATE_ATTITUDE, ArduPilotSim
from executive.sim.ardupilot.mission_change import MissionChangeDetector
from executive.sim.ardupilot.rover_fence import FENCE_ACTIONS, FENCE_DEFAULTS, breaches
from executive.sim.ardupilot.rover_nav import RoverNavigator
from executive.sim.firmware import EPSILON_S, Command, CommandHandler, Home, valid_latlon
from executive.sim.mission_store import StoredCommand
from executive.sim.physics.vehicle import BOAT_LIMITS, ROVER_LIMITS, MotionLimits, SurfaceVehicle, VehicleModel
from executive.world.bounds import clamp
from executive.world.dialect import MAVLinkMessage, mavlink

_M = mavlink

#: How the simulated ArduRover vehicles respond to the autopilot (their motors, hull and the throttle and steering
#: controllers; not the firmware's parameters): the speed's lag and the least turning radius (SITL's rover and motorboat
#: steer with a 1.8 m turning circle: libraries/SITL/SIM_Rover.h, SIM_Sailboat.cpp).
ROVER_RESPONSE = {"speed_lag_s": 0.3, "min_turn_radius_m": 0.9}
BOAT_RESPONSE = {"speed_lag_s": 0.5, "min_turn_radius_m": 0.9}

#: The parameters ArduPilot's SITL starts each frame with (Tools/autotest/default_params/rover.parm, and for the
#: motorboat frame motorboat.parm on top; Tools/autotest/pysim/vehicleinfo.py): how the real firmware drove in the
#: recordings of tests/data/ardurover/. Give them as ``params`` to drive as SITL does.
SITL_PARAMS: Mapping[str, Mapping[str, float]] = MappingProxyType({
    "rover": MappingProxyType({"WP_SPEED": 5.0, "CRUISE_SPEED": 5.0, "WP_RADIUS": 3.0}),
    "boat": MappingProxyType({"WP_SPEED": 5.0, "CRUISE_SPEED": 5.0, "WP_RADIUS": 3.0, "FRAME_CLASS": 2.0}),
})  # fmt: skip


class ArduRoverSim(ArduPilotSim):
    """ArduRover: a rover, or a boat (FRAME_CLASS=2), whose modes drive a :class:`SurfaceVehicle`.

    HOLD and the manual modes stop (no pilot in the sim). LOITER holds a point within
    ``LOITER_RADIUS_M``. GUIDED drives to position targets, then stops (rover) or loiters (boat).
    RTL drives home, then stops or loiters, staying in RTL as the firmware does. AUTO drives to each
    NAV_WAYPOINT of the mission in turn (a NAV_LOITER_UNLIM: to stay there), then stops and stays in AUTO (MIS_DONE_BEHAVE=0); it is
    refused without a mission ("No Mission. Can't set AUTO.").

    GUIDED, AUTO and RTL drive as the firmware's navigation does (:class:`~executive.sim.ardupilot.rover_nav.RoverNavigator`:
    GUIDED's shaped stop points, AUTO's S-curves and fast waypoints, pivots), by the parameters the
    vehicle has (:attr:`params`: the firmware's defaults unless set; :data:`SITL_PARAMS` as SITL starts).
    """

    FIRMWARE = "ArduRover"
    READY_TEXT = "Ready to drive"
    #: Answered to PARAM_REQUEST_READ: MODE_CH (Rover/Parameters.cpp, MODE_CHANNEL 8 in Rover/config.h), CRUISE_SPEED
    #: (Rover/config.h CRUISE_SPEED 2), and the navigation's parameters with the firmware's defaults.
    #: SERVO1_FUNCTION 26 (GroundSteering) and SERVO3_FUNCTION 70 (Throttle): ArduRover's default outputs (Rover/Parameters.cpp).
    #: MIS_DONE_BEHAVE 0: stop in AUTO at the mission's end (Rover/Parameters.cpp).
    PARAMS: ClassVar[Mapping[str, float]] = {
        "MODE_CH": 8, "CRUISE_SPEED": 2.0, "MIS_DONE_BEHAVE": 0.0, "FRAME_CLASS": 1.0, "SERVO1_FUNCTION": 26.0, "SERVO3_FUNCTION": 70.0,
        **FIRMWARE_DEFAULTS, **FENCE_DEFAULTS,
    }  # fmt: skip
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset({
        "MODE_CH", "FRAME_CLASS", "MIS_DONE_BEHAVE", "WP_PIVOT_ANGLE", "WP_PIVOT_RATE", "SERVO1_FUNCTION", "SERVO3_FUNCTION",
        "FENCE_ENABLE", "FENCE_TYPE", "FENCE_ACTION", "FENCE_OPTIONS",
    })  # fmt: skip
    SKID_STEERING: ClassVar[bool] = False  # SERVO1/3_FUNCTION ThrottleLeft/Right: pivot turns (Rover.cpp set_turn_params)
    MANUAL_INPUT_MODES = frozenset({"MANUAL", "ACRO", "STEERING", "INITIALISING"})
    PILOT_DRIVEN_MODES: ClassVar[frozenset[str]] = frozenset({"MANUAL", "ACRO", "STEERING"})
    STICK_DEADZONE_US: ClassVar[int] = 30  # RC_DZ
    AUTOPILOT_MODES = frozenset({"AUTO", "GUIDED", "LOITER", "RTL", "SMART_RTL", "FOLLOW", "CIRCLE", "DOCK"})
    POSITION_MODES = frozenset({"LOITER", "FOLLOW", "SIMPLE", "CIRCLE", "DOCK", "AUTO", "RTL", "SMART_RTL", "GUIDED"})
    EKF_FAILSAFE_MODE = "HOLD"
    UNARMABLE_MODES = frozenset({"RTL", "SMART_RTL"})
    NOT_SIMULATED = frozenset({"FOLLOW", "CIRCLE", "DOCK", "INITIALISING"})  # no target, beacon or pilot to use
    LOITER_RADIUS_M = 2.0  # LOIT_RADIUS

    # the mode's navigation state (class defaults, replaced per instance)
    _destination: tuple[float, float] | None = None  # what the mode reports as its target
    _driving = False  # on the way to _destination
    _loitering = False  # holding _destination within the loiter radius
    _nav: RoverNavigator | None = None  # AR_WPNav, from the last mode entry that initialised it
    limits: MotionLimits
    motion: RoverMotion
    _auto_waiting = False  # in AUTO, waiting for an EKF origin to start the mission
    _auto_item: tuple[int | None, StoredCommand] | None = None  # the (seq, item) AUTO is executing
    _mission_change: MissionChangeDetector  # ModeAuto's mis_change_detector
    _auto_hold_until = 0.0  # elapsed_s at which a waypoint's hold time ends

    @property
    def is_boat(self) -> bool:
        return self.profile.mav_type == _M.MAV_TYPE_SURFACE_BOAT

    @property
    def base_limits(self) -> MotionLimits:
        """The vehicle's own limits, before the firmware's parameters."""
        return BOAT_LIMITS if self.is_boat else ROVER_LIMITS

    @property
    def response(self) -> Mapping[str, float]:
        """How the vehicle responds to the autopilot's speed and turn demands (:data:`ROVER_RESPONSE`)."""
        return BOAT_RESPONSE if self.is_boat else ROVER_RESPONSE

    def _make_vehicle(self, home: Home) -> VehicleModel:
        self.motion = RoverMotion.from_params(self.params, skid_steering=self.SKID_STEERING)
        base = self.base_limits
        # the firmware's parameters set the cruise speed, the acceleration and the braking of the modes that do not
        # navigate (LOITER, a stop); a top speed below WP_SPEED would not be the vehicle the parameters were set for
        self.limits = dataclasses.replace(
            base, cruise_m_s=self.motion.speed_m_s, max_m_s=max(base.max_m_s, self.motion.speed_m_s),
            accel_m_s2=self.motion.accel_max_m_s2, decel_m_s2=self.motion.decel_m_s2, **self.response,
        )  # fmt: skip
        return self._vehicle_model(home, self.limits)

    def _vehicle_model(self, home: Home, limits: MotionLimits) -> SurfaceVehicle:
        return SurfaceVehicle(home[0], home[1], home[2], limits)

    def _navigator(self, speed_m_s: float | None = None) -> RoverNavigator:
        """A fresh AR_WPNav (a mode's entry calls wp_nav.init(): the default speed again), driving the vehicle."""
        self._nav = RoverNavigator(self.motion, speed_m_s)
        assert isinstance(self.vehicle, SurfaceVehicle)
        self.vehicle.follow(self._nav)
        return self._nav

    _fence_breaches = 0  # the fence types breached at the last check (AC_Fence's _breached_fences)
    _fence_breach_count = 0
    _fence_breach_ms = 0

    def _check_health(self) -> None:
        super()._check_health()
        self._check_fence()

    def _check_fence(self) -> None:
        """Rover/fence.cpp fence_check, at 10 Hz: a new breach sends FENCE_STATUS (no STATUSTEXT: AC_Fence::record_breach) and, armed,
        takes FENCE_ACTION once (see rover_fence)."""
        if not self.ekf_ready or (not self._fence_breaches and not self.params.get("FENCE_ENABLE")):
            return  # nothing breached, nothing to check (breaches: none while FENCE_ENABLE is 0)
        fence = self.zone_stores[_M.MAV_MISSION_TYPE_FENCE].commands
        found = breaches(self.params, fence, self.home, self.vehicle.lat, self.vehicle.lon)
        new = found & ~self._fence_breaches
        if found != self._fence_breaches:
            if new:
                self._fence_breach_count += 1
                self._fence_breach_ms = self._ms()
            self._fence_breaches = found
            self._emit(self._msg_fence_status())
        if not new or not self.armed:
            return
        for action in FENCE_ACTIONS.get(int(self.params.get("FENCE_ACTION", 1)), ("HOLD",)):
            if action == "DISARM":
                self.disarm()
                break
            self._force_mode(action)
            if self.mode == action:
                break

    def _msg_fence_status(self) -> MAVLinkMessage:
        """FENCE_STATUS (GCS_MAVLink/GCS_Fence.cpp send_fence_status): breach_type 3 (boundary) for the circle and polygon."""
        breach_type = _M.FENCE_BREACH_BOUNDARY if self._fence_breaches else _M.FENCE_BREACH_NONE
        return self._mav.fence_status_encode(int(bool(self._fence_breaches)), self._fence_breach_count, breach_type, self._fence_breach_ms, 0)

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {**super()._message_handlers(), "SET_POSITION_TARGET_GLOBAL_INT": self._on_position_target}

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_REPOSITION: self._cmd_reposition,
            _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed,
            _M.MAV_CMD_NAV_RETURN_TO_LAUNCH: lambda cmd: self._set_mode_result("RTL"),
            _M.MAV_CMD_MISSION_START: lambda cmd: _M.MAV_RESULT_DENIED if any(cmd.params[:2]) else self._set_mode_result("AUTO"),
        }

    def _set_mode_result(self, mode: str) -> int:
        return _M.MAV_RESULT_ACCEPTED if self.set_mode(self.profile.modes[mode]) else _M.MAV_RESULT_FAILED

    # -- what the vehicle is doing ---------------------------------------------------------------

    def _stop(self) -> None:
        """Mode::stop_vehicle: brake within ATC_DECEL_MAX, without turning."""
        self._destination, self._driving, self._loitering = None, False, False
        nav = self._nav if self._nav is not None else self._navigator()
        nav.stop()
        assert isinstance(self.vehicle, SurfaceVehicle)
        self.vehicle.follow(nav)

    def _loiter(self) -> bool:
        """Hold where the vehicle can stop; needs a position estimate."""
        if not self.position_ok:
            return False
        self._destination, self._driving, self._loitering = self.vehicle.stopping_point(), False, True
        self.vehicle.hold()
        return True

    def _drive(self, lat: float, lon: float, then: tuple[float, float] | None = None, *, guided: bool = False) -> None:
        """Drive to a point and stop there: GUIDED's shaped stop point (``guided``), or else (AUTO, RTL) an S-curve leg,
        through the point toward ``then`` when given (AUTO's next waypoint: a "fast waypoint")."""
        self._destination, self._driving, self._loitering = (lat, lon), True, False
        vehicle = self.vehicle
        assert isinstance(vehicle, SurfaceVehicle)
        nav = self._nav if self._nav is not None else self._navigator()
        if guided:
            nav.guided_to(vehicle.ne_of(lat, lon), vehicle)
        else:
            nav.auto_to(vehicle.ne_of(lat, lon), None if then is None else vehicle.ne_of(*then), vehicle)
        vehicle.follow(nav)

    def _enter_mode(self, mode: str) -> bool:
        if mode == "AUTO":
            if not self.mission.present:
                self._text(_M.MAV_SEVERITY_NOTICE, "No Mission. Can't set AUTO.")
                return False
            self._auto_waiting, self._auto_item, self._mission_change = True, None, MissionChangeDetector()
            self._navigator()  # ModeAuto::_enter: wp_nav.init()
            if not (self.is_boat and self._loiter()):
                self._stop()
            return True
        if mode in self.NOT_SIMULATED:
            return False
        if mode == "LOITER":
            return self._loiter()
        if mode in ("RTL", "SMART_RTL"):
            # SMART_RTL needs the path recorded since arming; here it drives straight home like RTL
            if self.home is None or (mode == "SMART_RTL" and not self.armed):
                return False
            self._navigator(self.params.get("RTL_SPEED", 0.0))  # ModeRTL::_enter: wp_nav.init(RTL_SPEED), 0: WP_SPEED
            self._drive(*self.home)
            return True
        if mode == "GUIDED":
            self._navigator()  # ModeGuided::_enter: wp_nav.init()
            if not (self.is_boat and self._loiter()):
                self._stop()
            return True
        self._stop()
        return True

    def _update_mode(self) -> None:
        if self.mode == "AUTO":
            self._update_auto()
            return
        if self.mode in self.PILOT_DRIVEN_MODES:
            self._drive_by_sticks()
            return
        if self._driving and self.vehicle.arrived:
            self._driving = False
            if self.mode == "GUIDED":
                self._emit(self._mav.mission_item_reached_encode(0))
            else:
                self._text(_M.MAV_SEVERITY_INFO, "Reached destination")
            if self.is_boat:
                self._loiter()
            elif self._nav is not None:
                self._nav.stop()  # rovers stop where they are (Mode::stop_vehicle) and keep reporting the destination
        if self._loitering and self._destination is not None:
            if self.vehicle.target is None and self.vehicle.distance_to(*self._destination) > self.LOITER_RADIUS_M:
                self.vehicle.drive_to(*self._destination)
            elif self.vehicle.arrived:
                self.vehicle.hold()

    def disarm(self) -> None:
        super().disarm()
        if self._nav is not None:
            self._nav.settle()

    def _drive_by_sticks(self) -> None:
        """MANUAL and friends: the pilot's sticks drive (RCMAP defaults: steering channel 1, throttle channel 3)."""

        def stick(pwm: int) -> float:
            offset = pwm - 1500
            return 0.0 if pwm == 0 or abs(offset) <= self.STICK_DEADZONE_US else offset / 500.0

        self._destination, self._driving, self._loitering = None, False, False
        self.vehicle.drive_manual(stick(self.rc_channels[2]), stick(self.rc_channels[0]))

    def _update_auto(self) -> None:
        """Start the mission once the EKF has an origin, drive to each NAV_WAYPOINT, pass over other items, stop at the end.

        As ModeAuto::do_nav_wp (Rover/mode_auto.cpp): a waypoint followed by another navigation command and
        without a hold time is driven through toward that one (AR_WPNav's "fast waypoint": no stop, the corner
        cut within WP_RADIUS); the last one, or one with a hold time, is a stop. The next item starts at once.
        A NAV_LOITER_UNLIM is a stop at its location (do_nav_wp with always_stop_at_destination; a boat loiters
        there) that never completes (verify_loiter_unlimited: no MISSION_ITEM_REACHED), until MISSION_SET_CURRENT.
        """
        if self._auto_waiting:
            if not self.position_ok:
                return
            self._auto_waiting = False
            self.mission.start_or_resume()
            self._mission_change.start(self.mission.changes, self.mission.current_seq)
        item = self.mission.current
        if self._mission_change.check(self.mission.changes, self.mission.current_seq):
            self._restart_on_change(item)
        if item is None:  # complete (ArduRover stays in AUTO, stopped), or the mission was cleared
            if self._driving or self._loitering:
                self._stop()
            return
        stop_here = item.command == _M.MAV_CMD_NAV_LOITER_UNLIM
        if (self.mission.current_seq, item) == self._auto_item:
            if self._driving and self.vehicle.arrived:
                self._driving = False
                hold_s = 0.0 if stop_here else item.params[0]  # ModeAuto::verify_nav_wp: a hold time waits there, counted from arrival
                self._auto_hold_until = self.elapsed_s + hold_s
                seq = self.mission.current_seq
                self._text(_M.MAV_SEVERITY_INFO, f"Reached waypoint #{seq}" + (f". Loiter for {hold_s:.0f} seconds" if hold_s else ""))
                if stop_here and self.is_boat:  # ModeAuto::update: boats loiter once a waypoint that is not a fast one is reached
                    self._loiter()
            if stop_here or self._driving or self.elapsed_s < self._auto_hold_until - EPSILON_S:
                return  # verify_loiter_unlimited never completes: the vehicle stays until the mission is moved on
            item = self.mission.advance()
            if item is None:
                self._mission_done()
                return
        # the next item, a set-current, or an upload replaced it
        self._auto_item = (self.mission.current_seq, item)
        if item.command == _M.MAV_CMD_NAV_WAYPOINT:
            self._drive(item.lat, item.lon, then=self._next_corner(item))
        elif item.command == _M.MAV_CMD_NAV_LOITER_UNLIM:  # do_nav_wp(cmd, always_stop_at_destination=true)
            self._drive(item.lat, item.lon)
        else:
            self.mission.advance()

    def _restart_on_change(self, item: StoredCommand | None) -> None:
        """The mission changed while AUTO drives a waypoint (:class:`MissionChangeDetector`): ModeAuto::update restarts that
        waypoint's command (Rover/mode_auto.cpp, AP_Mission::restart_current_nav_cmd): AR_WPNav::set_desired_location, the
        leg not reached, starts again from the stopping point."""
        if item is None or not self._driving or item.command not in (_M.MAV_CMD_NAV_WAYPOINT, _M.MAV_CMD_NAV_LOITER_UNLIM):
            return
        self._text(_M.MAV_SEVERITY_CRITICAL, "Auto mission changed, restarted command")
        self._auto_item = None

    def _mission_done(self) -> None:
        """ModeAuto::exit_mission (Rover/mode_auto.cpp): MIS_DONE_BEHAVE 0 stops in AUTO, 1 loiters in AUTO, 2 ACRO, 3 MANUAL."""
        behave = int(self.params.get("MIS_DONE_BEHAVE", 0))
        if behave == 1 and self._loiter():
            return
        if behave in (2, 3):
            self._force_mode("ACRO" if behave == 2 else "MANUAL")
            return
        self._stop()

    def _next_corner(self, item: StoredCommand) -> tuple[float, float] | None:
        """The navigation command after the waypoint ``item``, given to AR_WPNav with it unless the waypoint has a hold time
        (ModeAuto::do_nav_wp); AR_WPNav itself stops there when it would pivot."""
        if item.params[0] > 0 or self.mission.current_seq is None:  # a hold time: always a stop
            return None
        after = self.mission.next_nav_after(self.mission.current_seq)
        return None if after is None else (after.lat, after.lon)

    def _desired_location(self) -> tuple[float, float] | None:
        return self._destination

    def _system_status(self) -> int:
        if self.mode == self.BOOT_MODE:
            return _M.MAV_STATE_CALIBRATING
        return _M.MAV_STATE_STANDBY if self.mode == "HOLD" else _M.MAV_STATE_ACTIVE

    def _control_sensors(self) -> tuple[int, int]:
        """GCS_Rover::update_vehicle_sensor_status_flags (Rover/GCS_Rover.cpp): rate and attitude control in the
        modes that stabilise the heading (all but MANUAL, HOLD and INITIALISING: Rover/mode.h), yaw and position
        control in the autopilot modes."""
        enabled = RATE_ATTITUDE if self.mode not in ("MANUAL", "HOLD", "INITIALISING") else 0
        if self.mode in self.AUTOPILOT_MODES:
            enabled |= NAVIGATION
        return RATE_ATTITUDE | NAVIGATION, enabled

    def _throttle(self) -> float:
        if not self.armed:
            return 0.0
        share = abs(self.vehicle.speed_m_s) / self.limits.max_m_s
        return share if share < 1.0 else 1.0

    def _servo_outputs(self) -> Sequence[int]:
        """ArduRover's default outputs: SERVO1 ground steering, SERVO3 throttle."""
        steer = clamp(self.vehicle.yaw_rate_rad_s / math.radians(self.limits.turn_rate_deg_s), 1.0)
        outputs = [0] * 16
        outputs[0] = round(1500 + 500 * steer)
        outputs[2] = round(1500 + 500 * self._throttle())
        return outputs

    # -- GUIDED targets --------------------------------------------------------------------------

    def _on_position_target(self, msg: MAVLinkMessage) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT: only in GUIDED, never acknowledged (as ArduRover)."""
        if self.mode != "GUIDED" or msg.coordinate_frame not in GLOBAL_FRAMES:
            return
        lat, lon = msg.lat_int * 1e-7, msg.lon_int * 1e-7
        if not msg.type_mask & POS_BITS and not valid_latlon(lat, lon):
            return
        if not msg.type_mask & ACC_BITS:
            self._text(_M.MAV_SEVERITY_INFO, "Ignoring SET_POSITION_TARGET_GLOBAL_INT; set ACC_IGNORE in mask")
            return
        if not msg.type_mask & POS_BITS:  # velocity, heading and turn-rate targets are not simulated
            self._drive(lat, lon, guided=True)

    def _cmd_change_speed(self, cmd: Command) -> int:
        """ArduRover: only the autonomous modes take a desired speed (Mode::set_desired_speed), else FAILED."""
        speed = cmd.params[1]
        if self.mode not in ("GUIDED", "AUTO", "RTL", "SMART_RTL") or not 0.0 < speed <= self.vehicle.limits.max_m_s:
            return _M.MAV_RESULT_FAILED
        (self._nav if self._nav is not None else self._navigator()).set_speed(speed)  # AR_WPNav::set_speed_max
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_reposition(self, cmd: Command) -> int:
        change_mode = int(cmd.params[1]) & _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
        if self.mode != "GUIDED" and not change_mode:
            return _M.MAV_RESULT_DENIED
        lat, lon = cmd.lat_lon
        if not valid_latlon(lat, lon) or (lat == 0.0 and lon == 0.0):
            return _M.MAV_RESULT_DENIED
        if self.mode != "GUIDED" and not self.set_mode(self.profile.modes["GUIDED"]):
            return _M.MAV_RESULT_FAILED
        if cmd.params[0] > 0:
            (self._nav if self._nav is not None else self._navigator()).set_speed(cmd.params[0])
        self._drive(lat, lon, guided=True)
        return _M.MAV_RESULT_ACCEPTED
