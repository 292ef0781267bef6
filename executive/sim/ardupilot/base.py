"""ArduPilot as the simulated vehicles' autopilot: MAVLink messages in, MAVLink messages out, no sockets.

:class:`ArduPilotSim` does what every ArduPilot firmware does alike: HEARTBEAT, telemetry streams
and their rates, COMMAND_LONG / COMMAND_INT answered with COMMAND_ACK, arming and its pre-arm
checks, the EKF's slow start, the battery, STATUSTEXT. A subclass per firmware adds its modes and
the vehicle model they drive: :class:`ArduRoverSim` for rovers and boats. A sub, a VTOL or a
tracked frame is another subclass registered in :data:`AUTOPILOTS`.

Everything runs in the injected clock's time (a ScaledClock shared with the executive gives the
speed-up; a ManualClock steps it in tests). The behaviour follows ArduPilot's source and what a
real ArduRover did, quirks included: the firmware is the reference, not the MAVLink spec.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import ClassVar

from executive.autopilot.rover_motion import FIRMWARE_DEFAULTS, RoverMotion
from executive.clock import Clock
from executive.io.mavlink.dialect import AUTOPILOT_COMPONENT, MAVLinkMessage, encoder, mavlink
from executive.sim.ardupilot.rover_nav import RoverNavigator
from executive.sim.mission_store import MissionStore, StoredCommand
from executive.sim.physics.vehicle import BOAT_LIMITS, ROVER_LIMITS, Limits, SurfaceVehicle, VehicleModel
from executive.sim.proximity import Proximity
from executive.vehicles import PROFILES, VehicleProfile

Home = tuple[float, float, float]  # latitude, longitude (degrees), heading (degrees)

#: Where ArduPilot's own simulator starts: Canberra Model Aircraft Club.
DEFAULT_HOME: Home = (-35.363261, 149.165230, 353.0)

#: ArduPilot's magic param2 values for MAV_CMD_COMPONENT_ARM_DISARM (GCS_MAVLink/GCS.h).
#: 2989 skips the pre-arm checks; 21196 only forces a *disarm* (an arm with it is checked as usual).
FORCE_ARM = 2989.0
FORCE_DISARM = 21196.0

EKF_FLAGS_READY = 0x33F  # 831, as read on the real firmware once the EKF uses GPS
EKF_FLAGS_WAITING = 0xA7  # attitude, velocities, vertical position, constant-position mode: no GPS yet
WAITING_REL_ALT_M = 9.7  # the wrong altitude GLOBAL_POSITION_INT carries before the EKF has an origin
PREARM_AHRS = "AHRS: not using configured AHRS type"
PREARM_REPORT_S = 30.0  # a disarmed ArduPilot repeats its failing pre-arm checks this often
BATTERY_MAH = 10000.0
RELAYS = 16  # ArduPilot 4.5: RELAY1..RELAY16 (AP_Relay)
BATTERY_FULL_V, BATTERY_EMPTY_V, BATTERY_SAG_V_PER_A = 12.6, 10.5, 0.03

_M = mavlink
_EPSILON_S = 1e-6  # clock times closer than this are the same instant
GLOBAL_FRAMES = frozenset({
    _M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    _M.MAV_FRAME_GLOBAL_TERRAIN_ALT, _M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
})  # fmt: skip
# ArduPilot treats a group as ignored when any of its bits is set
POS_BITS = _M.POSITION_TARGET_TYPEMASK_X_IGNORE | _M.POSITION_TARGET_TYPEMASK_Y_IGNORE | _M.POSITION_TARGET_TYPEMASK_Z_IGNORE
ACC_BITS = _M.POSITION_TARGET_TYPEMASK_AX_IGNORE | _M.POSITION_TARGET_TYPEMASK_AY_IGNORE | _M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
TARGET_REPORT_MASK = 0xFDF8  # what ArduRover puts in POSITION_TARGET_GLOBAL_INT: position only

# SYS_STATUS bits (GCS::update_sensor_status_flags, libraries/GCS_MAVLink/GCS.cpp): the sensors every simulated
# ArduPilot has and keeps healthy (a GPS with a 3D fix from the start, no safety switch, RC seen)...
SENSORS = (
    _M.MAV_SYS_STATUS_SENSOR_3D_MAG | _M.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE | _M.MAV_SYS_STATUS_SENSOR_GPS
    | _M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | _M.MAV_SYS_STATUS_SENSOR_RC_RECEIVER | _M.MAV_SYS_STATUS_SENSOR_BATTERY
)  # fmt: skip
# ... the inertial sensors (not enabled while they calibrate at boot) and the AHRS (enabled once initialised,
# healthy with the EKF: NavEKF3_core::healthy, libraries/AP_NavEKF3/AP_NavEKF3_Control.cpp)...
STARTED_AFTER_BOOT = _M.MAV_SYS_STATUS_SENSOR_3D_GYRO | _M.MAV_SYS_STATUS_SENSOR_3D_ACCEL | _M.MAV_SYS_STATUS_AHRS
# ... and the controllers the mode uses (each firmware's update_vehicle_sensor_status_flags).
RATE_ATTITUDE = _M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL | _M.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
NAVIGATION = _M.MAV_SYS_STATUS_SENSOR_YAW_POSITION | _M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL

_STREAM_S = 0.25  # ArduRover's telemetry arrives at ~4 Hz without being asked
#: Messages sent unasked, with their default interval (s). Others are sent only on request.
DEFAULT_INTERVALS: Mapping[int, float] = MappingProxyType({
    _M.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    **dict.fromkeys((
        _M.MAVLINK_MSG_ID_SYS_STATUS, _M.MAVLINK_MSG_ID_GPS_RAW_INT, _M.MAVLINK_MSG_ID_ATTITUDE,
        _M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, _M.MAVLINK_MSG_ID_VFR_HUD, _M.MAVLINK_MSG_ID_RC_CHANNELS,
        _M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, _M.MAVLINK_MSG_ID_EKF_STATUS_REPORT,
        _M.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT, _M.MAVLINK_MSG_ID_POSITION_TARGET_GLOBAL_INT,
        _M.MAVLINK_MSG_ID_MISSION_CURRENT,
    ), _STREAM_S),
})  # fmt: skip


def _valid_latlon(lat: float, lon: float) -> bool:
    return abs(lat) <= 90.0 and abs(lon) <= 180.0


def _e7(degrees: float) -> int:
    return round(degrees * 1e7)


@dataclass(frozen=True, slots=True)
class Command:
    """A COMMAND_LONG or COMMAND_INT, as ArduPilot handles both (params 5-7 are x, y, z)."""

    command: int
    params: tuple[float, float, float, float, float, float, float]
    is_int: bool
    # ArduPilot handles a COMMAND_LONG as a COMMAND_INT in the relative-altitude frame
    frame: int = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT

    @property
    def lat_lon(self) -> tuple[float, float]:
        scale = 1e-7 if self.is_int else 1.0
        return self.params[4] * scale, self.params[5] * scale


class ArduPilotSim(ABC):
    """The firmware-independent part of a simulated ArduPilot.

    Call :meth:`handle` with every received message and :meth:`update` often; both return the
    messages to send. Not thread-safe: the server serialises calls.
    """

    FIRMWARE: ClassVar[str]
    VERSION: ClassVar[str] = "V4.7.0-dev"
    READY_TEXT: ClassVar[str]
    BOOT_MODE: ClassVar[str] = "INITIALISING"
    INITIAL_MODE: ClassVar[str] = "MANUAL"
    MANUAL_INPUT_MODES: ClassVar[frozenset[str]] = frozenset()  # HEARTBEAT MANUAL_INPUT_ENABLED
    AUTOPILOT_MODES: ClassVar[frozenset[str]] = frozenset()  # HEARTBEAT GUIDED_ENABLED, NAV_CONTROLLER_OUTPUT
    STABILIZE_MODES: ClassVar[frozenset[str]] = frozenset()  # HEARTBEAT STABILIZE_ENABLED
    STREAMS: ClassVar[Mapping[int, float]] = DEFAULT_INTERVALS  # messages sent unasked, with their default interval (s)
    POSITION_MODES: ClassVar[frozenset[str]] = frozenset()  # refused while armed without a position estimate
    UNARMABLE_MODES: ClassVar[frozenset[str]] = frozenset()
    NAV_PERIOD_S: ClassVar[float] = 0.1  # how often mode logic runs, in clock time
    #: The firmware's own EKF failsafe (Rover/ekf_check.cpp): the mode it puts a vehicle in a position mode in; None: not modelled.
    EKF_FAILSAFE_MODE: ClassVar[str | None] = None
    #: ekf_check runs at 10 Hz and latches after EKF_CHECK_ITERATIONS_MAX (10) bad checks in a row; it clears 10 good ones later.
    EKF_CHECK_ITERATIONS_MAX: ClassVar[int] = 10
    MISSION_STORE: ClassVar[type[MissionStore]] = MissionStore  # the firmware's side of the mission protocol
    PARAMS: ClassVar[Mapping[str, float]] = {}  # parameters answered to PARAM_REQUEST_READ, with the firmware's defaults
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset({"MODE_CH", "FLTMODE_CH"})  # answered as integers (MAV_PARAM_TYPE_INT8), the rest REAL32

    def __init__(
        self,
        profile: VehicleProfile,
        clock: Clock,
        home: Home = DEFAULT_HOME,
        *,
        system_id: int = 1,
        component_id: int = AUTOPILOT_COMPONENT,
        ekf_ready_after_s: float = 40.0,
        boot_s: float = 1.0,
        params: Mapping[str, float] | None = None,
    ) -> None:
        """``params``: parameters set differently from the firmware's defaults (as SITL's --defaults file)."""
        self.profile = profile
        self.params = {**self.PARAMS, **(params or {})}
        self.clock = clock
        self.system_id = system_id
        self.component_id = component_id
        self.ekf_ready_after_s = ekf_ready_after_s
        self.boot_s = boot_s
        self.start = (home[0], home[1])
        self.vehicle: VehicleModel = self._make_vehicle(home)
        self.mode = self.BOOT_MODE
        self.armed = False
        self.home: tuple[float, float] | None = None  # set when the EKF gets its origin
        self.rc_channels = [1500] * 16
        self.rc_channels[4] = self.rc_channels[5] = 1000  # ch5/ch6 switches low
        self.ekf_position_lost = False  # set by fault injection: the EKF has no horizontal position
        #: The firmware's EKF failsafe is latched (Rover ``failsafe.ekf``): position modes are refused meanwhile.
        self.failsafe_ekf = False
        self._ekf_fail_count = 0
        self.consumed_mah = 0.0
        self._mav = encoder(system_id, component_id)
        self._t0 = self._t = clock.now()
        self._mode_names = {number: name for name, number in profile.modes.items()}
        self._intervals = dict(self.STREAMS)
        self._due: dict[int, float] = {}
        self._out: list[MAVLinkMessage] = []
        self._booted = self._origin_set = False
        self._prearm_reported_at = -math.inf
        self._text_id = 0
        self.mission = self.MISSION_STORE(self, self._emit, self._text)
        self.proximity = Proximity()  # a MAVLink proximity sensor (PRX1_TYPE 2): what OBSTACLE_DISTANCE tells
        self.relays: dict[int, bool] = {}  # relay instance -> on, as MAV_CMD_DO_SET_RELAY left it
        self._builders = self._message_builders()
        self._handlers = self._message_handlers()
        self._commands = self._command_handlers()
        self._text(_M.MAV_SEVERITY_INFO, f"{self.FIRMWARE} {self.VERSION} (sim)")

    # -- the public face -----------------------------------------------------------------------

    @property
    def elapsed_s(self) -> float:
        """Clock time since boot, as of the last :meth:`update`."""
        return self._t - self._t0

    @property
    def booted(self) -> bool:
        """Past INITIALISING: in its initial mode and handling messages."""
        return self._booted

    @property
    def ekf_ready(self) -> bool:
        """The EKF uses GPS: a position estimate, a home, arming possible."""
        return self.elapsed_s >= self.ekf_ready_after_s - _EPSILON_S

    @property
    def mode_number(self) -> int:
        return self.profile.modes[self.mode]

    def handle(self, msg: MAVLinkMessage) -> list[MAVLinkMessage]:
        """React to one received message; returns what to send (replies first)."""
        handler = self._handlers.get(msg.get_type())
        # while initialising, the firmware is not processing GCS messages yet
        if handler is not None and self.booted and self._addressed_to_me(msg):
            handler(msg)
        return self._flush()

    def update(self) -> list[MAVLinkMessage]:
        """Move the world to the clock's now; returns the telemetry and notices now due."""
        now = self.clock.now()
        while now - self._t > _EPSILON_S:
            h = min(self.NAV_PERIOD_S, now - self._t)
            self._ekf_check()
            self._update_mode()
            self.vehicle.step(h)
            self._drain_battery(h)
            self._t = now if now - self._t - h < _EPSILON_S else self._t + h
        self.mission.update()
        self._events()
        self._telemetry()
        return self._flush()

    def _ekf_check(self) -> None:
        """The firmware's EKF failsafe, as Rover/ekf_check.cpp runs it at 10 Hz (once per NAV_PERIOD_S here).

        Armed, with an EKF origin: each check without a position estimate counts up (to 10: latched,
        "EKF failsafe", a position mode left for ``EKF_FAILSAFE_MODE``); each good one counts down,
        and the latch clears at 0 ("EKF failsafe cleared"): about 1 s after the EKF recovered, during
        which position modes are still refused. Disarmed: cleared at once. Variances are not modelled:
        a lost position is what trips it (ekf_over_threshold returns !ekf_position_ok()).
        """
        if self.EKF_FAILSAFE_MODE is None or not self._origin_set:
            return
        if not self.armed:
            self._ekf_fail_count = 0
            self._ekf_failsafe_off()
            return
        if not self.position_ok:
            if not self.failsafe_ekf:
                self._ekf_fail_count += 1
                if self._ekf_fail_count >= self.EKF_CHECK_ITERATIONS_MAX:
                    self._ekf_fail_count = self.EKF_CHECK_ITERATIONS_MAX
                    self.failsafe_ekf = True
                    # failsafe_ekf_event: in a mode that needs no position it returns before acting or announcing
                    if self.mode in self.POSITION_MODES:  # FS_EKF_ACTION 1, hold
                        self._force_mode(self.EKF_FAILSAFE_MODE)
                        self._text(_M.MAV_SEVERITY_CRITICAL, "EKF failsafe")
        elif self._ekf_fail_count > 0:
            self._ekf_fail_count -= 1
            if self._ekf_fail_count == 0:
                self._ekf_failsafe_off()

    def _ekf_failsafe_off(self) -> None:
        if self.failsafe_ekf:
            self.failsafe_ekf = False
            self._text(_M.MAV_SEVERITY_CRITICAL, "EKF failsafe cleared")

    def _force_mode(self, name: str) -> None:
        """A mode change of the firmware's own (a failsafe): no position check, the mode's entry only."""
        if name == self.mode or not self._enter_mode(name):
            return
        if self.mode == "AUTO":
            self.mission.stop()
        self.mode = name
        self._emit(self._msg_heartbeat())

    # -- hooks for each firmware ---------------------------------------------------------------

    @abstractmethod
    def _make_vehicle(self, home: Home) -> VehicleModel:
        """The vehicle model (called once, before anything else is set up)."""

    @abstractmethod
    def _enter_mode(self, mode: str) -> bool:
        """Mode-specific entry: set the vehicle going, or return False to refuse the mode."""

    @abstractmethod
    def _update_mode(self) -> None:
        """Run the current mode's logic (every ``NAV_PERIOD_S``)."""

    @abstractmethod
    def _desired_location(self) -> tuple[float, float] | None:
        """Where the current mode is taking the vehicle, if anywhere."""

    @abstractmethod
    def _system_status(self) -> int:
        """HEARTBEAT system_status (MAV_STATE)."""

    @abstractmethod
    def _throttle(self) -> float:
        """Throttle in [0, 1]: VFR_HUD and the battery's load."""

    @abstractmethod
    def _servo_outputs(self) -> Sequence[int]:
        """SERVO_OUTPUT_RAW, 16 PWM values (0 = output not used)."""

    def _prearm_failures(self) -> list[str]:
        """Why arming would be refused now (without the "PreArm: " prefix)."""
        failures = [] if self.ekf_ready else [PREARM_AHRS]
        if self.mode in self.UNARMABLE_MODES:
            failures.append("Mode not armable")
        return failures

    @property
    def servo_outputs(self) -> tuple[int, ...]:
        """The 16 PWM outputs now (SERVO_OUTPUT_RAW; 0 = unused): what a drive bridge forwards to motors."""
        return tuple(self._servo_outputs())

    @property
    def position_ok(self) -> bool:
        """The firmware's own "EKF position ok" (false while an injected fault takes the position away)."""
        return self.ekf_ready and not self.ekf_position_lost

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {
            "COMMAND_LONG": self._on_command,
            "COMMAND_INT": self._on_command,
            "SET_MODE": self._on_set_mode,
            **dict.fromkeys(MissionStore.MESSAGES, self.mission.handle),
            "OBSTACLE_DISTANCE": lambda msg: self.proximity.handle(msg, self.elapsed_s),
            "PARAM_REQUEST_READ": self._on_param_request_read,
        }

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
        return {
            _M.MAV_CMD_DO_SET_MODE: lambda cmd: self._set_mode_common(int(cmd.params[0]), int(cmd.params[1])),
            _M.MAV_CMD_COMPONENT_ARM_DISARM: self._cmd_arm_disarm,
            _M.MAV_CMD_SET_MESSAGE_INTERVAL: self._cmd_set_message_interval,
            _M.MAV_CMD_GET_MESSAGE_INTERVAL: self._cmd_get_message_interval,
            _M.MAV_CMD_REQUEST_MESSAGE: self._cmd_request_message,
            _M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: self._cmd_request_capabilities,
            _M.MAV_CMD_DO_SET_HOME: self._cmd_set_home,
            _M.MAV_CMD_DO_SET_RELAY: self._cmd_set_relay,
            _M.MAV_CMD_DO_SET_MISSION_CURRENT: lambda cmd: self.mission.command_set_current(cmd.params[0], cmd.params[1]),
        }

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        return {
            _M.MAVLINK_MSG_ID_HEARTBEAT: self._msg_heartbeat,
            _M.MAVLINK_MSG_ID_SYS_STATUS: self._msg_sys_status,
            _M.MAVLINK_MSG_ID_GPS_RAW_INT: self._msg_gps_raw_int,
            _M.MAVLINK_MSG_ID_ATTITUDE: self._msg_attitude,
            _M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: self._msg_global_position_int,
            _M.MAVLINK_MSG_ID_VFR_HUD: self._msg_vfr_hud,
            _M.MAVLINK_MSG_ID_RC_CHANNELS: self._msg_rc_channels,
            _M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: self._msg_servo_output_raw,
            _M.MAVLINK_MSG_ID_EKF_STATUS_REPORT: self._msg_ekf_status_report,
            _M.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: self._msg_nav_controller_output,
            _M.MAVLINK_MSG_ID_POSITION_TARGET_GLOBAL_INT: self._msg_position_target_global_int,
            _M.MAVLINK_MSG_ID_HOME_POSITION: self._msg_home_position,
            _M.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: self._msg_gps_global_origin,
            _M.MAVLINK_MSG_ID_AUTOPILOT_VERSION: self._msg_autopilot_version,
            _M.MAVLINK_MSG_ID_MISSION_CURRENT: self.mission.current_message,
        }

    # -- output ----------------------------------------------------------------------------------

    def _emit(self, msg: MAVLinkMessage | None) -> None:
        if msg is not None:
            self._out.append(msg)

    def _text(self, severity: int, text: str) -> None:
        """STATUSTEXT; over 50 bytes, MAVLink 2 chunks sharing a non-zero id, as ArduPilot sends them."""
        data = text.encode()
        if len(data) <= 50:
            self._emit(self._mav.statustext_encode(severity, data))
            return
        self._text_id = self._text_id % 0xFFFF + 1
        for seq, start in enumerate(range(0, len(data), 50)):
            self._emit(self._mav.statustext_encode(severity, data[start : start + 50], self._text_id, seq))

    def _flush(self) -> list[MAVLinkMessage]:
        out, self._out = self._out, []
        return out

    def _ms(self) -> int:
        return int(self.elapsed_s * 1000) & 0xFFFFFFFF

    def _us(self) -> int:
        return int(self.elapsed_s * 1e6)

    # -- time-driven behaviour -------------------------------------------------------------------

    def _events(self) -> None:
        if not self._booted and self.elapsed_s >= self.boot_s - _EPSILON_S:
            self._booted = True
            self.mode = self.INITIAL_MODE
            self._enter_mode(self.mode)
            self._emit(self._msg_heartbeat())
            self._text(_M.MAV_SEVERITY_INFO, self.READY_TEXT)
        if not self._origin_set and self.ekf_ready:
            self._origin_set = True
            self._text(_M.MAV_SEVERITY_INFO, "EKF3 IMU0 origin set")
            self._text(_M.MAV_SEVERITY_INFO, "EKF3 IMU0 is using GPS")
            self.home = (self.vehicle.lat, self.vehicle.lon)
            self._emit(self._msg_home_position())
            self._emit(self._msg_gps_global_origin())
        if self._booted and not self.armed and self.elapsed_s - self._prearm_reported_at >= PREARM_REPORT_S:
            failures = self._prearm_failures()
            if failures:
                self._prearm_reported_at = self.elapsed_s
                self._report_prearm(failures)

    def _telemetry(self) -> None:
        for msg_id, interval in self._intervals.items():
            if interval <= 0 or not (self._booted or msg_id == _M.MAVLINK_MSG_ID_HEARTBEAT):
                continue
            due = self._due.get(msg_id, self._t)
            if self._t + _EPSILON_S >= due:
                self._emit(self._builders[msg_id]())
                # at a high speed-up several intervals may pass between updates: send once, no burst
                self._due[msg_id] = due + interval if due + interval > self._t else self._t + interval

    def _drain_battery(self, dt: float) -> None:
        self.consumed_mah += self._current_a() * dt / 3.6

    def _current_a(self) -> float:
        return 0.5 + (2.0 + 10.0 * self._throttle() if self.armed else 0.0)

    # -- incoming messages -----------------------------------------------------------------------

    def _addressed_to_me(self, msg: MAVLinkMessage) -> bool:
        target_system = getattr(msg, "target_system", 0)
        target_component = getattr(msg, "target_component", 0)
        return target_system in (0, self.system_id) and target_component in (0, self.component_id)

    @staticmethod
    def _command_of(msg: MAVLinkMessage) -> Command:
        """A received COMMAND_LONG or COMMAND_INT as a :class:`Command`."""
        if msg.get_type() == "COMMAND_INT":
            params = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
        else:
            params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        is_int = msg.get_type() == "COMMAND_INT"
        return Command(msg.command, params, is_int, msg.frame if is_int else _M.MAV_FRAME_GLOBAL_RELATIVE_ALT)

    def _on_command(self, msg: MAVLinkMessage) -> None:
        cmd = self._command_of(msg)
        handler = self._commands.get(cmd.command)
        self._ack_first(msg, cmd.command, lambda: handler(cmd) if handler else _M.MAV_RESULT_UNSUPPORTED)

    def _on_param_request_read(self, msg: MAVLinkMessage) -> None:
        """PARAM_VALUE for a parameter by name (or by index, param_index >= 0); nothing for one the firmware does not have (GCS_Param.cpp)."""
        names = sorted(self.params)
        name = msg.param_id.rstrip("\x00") if isinstance(msg.param_id, str) else msg.param_id.decode("ascii", "replace").rstrip("\x00")
        if msg.param_index >= 0:
            name = names[msg.param_index] if msg.param_index < len(names) else ""
        if name in self.params:
            kind = _M.MAV_PARAM_TYPE_INT8 if name in self.INT_PARAMS else _M.MAV_PARAM_TYPE_REAL32
            self._emit(self._mav.param_value_encode(name.encode(), self.params[name], kind, len(names), names.index(name)))

    def _on_set_mode(self, msg: MAVLinkMessage) -> None:
        # ArduPilot acks the SET_MODE message with a COMMAND_ACK whose command is the message id (11)
        self._ack_first(msg, _M.MAVLINK_MSG_ID_SET_MODE, lambda: self._set_mode_common(msg.base_mode, msg.custom_mode))

    def _ack_first(self, msg: MAVLinkMessage, command: int, run: Callable[[], int]) -> None:
        """Run a command; its COMMAND_ACK goes out before whatever the command itself sent."""
        mark = len(self._out)
        result = run()
        self._out.insert(mark, self._mav.command_ack_encode(command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()))

    # -- modes -----------------------------------------------------------------------------------

    def _set_mode_common(self, base_mode: int, custom_mode: int) -> int:
        if not base_mode & _M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return _M.MAV_RESULT_DENIED  # ArduPilot has no mapping from MAVLink base modes
        return _M.MAV_RESULT_ACCEPTED if self.set_mode(custom_mode) else _M.MAV_RESULT_FAILED

    def set_mode(self, number: int) -> bool:
        """Change mode as a GCS command would (STATUSTEXT on refusal); True on success."""
        name = self._mode_names.get(number)
        if name is None:
            self._text(_M.MAV_SEVERITY_WARNING, f"No such mode {number}")
            return False
        if name == self.mode:
            return True
        # ArduPilot only checks the position estimate when armed: a disarmed vehicle may enter any mode. ArduRover's
        # Mode::enter (Rover/mode.cpp) also refuses them while its EKF failsafe is latched: ekf_position_ok() && !failsafe.ekf
        position_ok = self.position_ok and not self.failsafe_ekf
        if (self.armed and name in self.POSITION_MODES and not position_ok) or not self._enter_mode(name):
            self._text(_M.MAV_SEVERITY_WARNING, "Flight mode change failed")
            return False
        if self.mode == "AUTO":
            self.mission.stop()  # leaving AUTO stops the mission where it is, to resume there
        self.mode = name
        self._emit(self._msg_heartbeat())  # ArduPilot announces a new mode at once
        return True

    # -- commands --------------------------------------------------------------------------------

    def disarm(self) -> None:
        """Disarm, whoever asks (a GCS command, a pilot's switch in fault injection)."""
        if self.armed:
            self.armed = self.vehicle.powered = False
            self._text(_M.MAV_SEVERITY_INFO, "Throttle disarmed")

    def _report_prearm(self, failures: list[str]) -> None:
        for failure in failures:
            self._text(_M.MAV_SEVERITY_CRITICAL, f"PreArm: {failure}")

    def _cmd_arm_disarm(self, cmd: Command) -> int:
        if cmd.params[0] == 1.0:
            if not self.armed:
                failures = [] if cmd.params[1] == FORCE_ARM else self._prearm_failures()
                if failures:
                    self._report_prearm(failures)
                    return _M.MAV_RESULT_FAILED
                self.armed = self.vehicle.powered = True
                self._text(_M.MAV_SEVERITY_INFO, "Throttle armed")
            return _M.MAV_RESULT_ACCEPTED
        if cmd.params[0] == 0.0:
            self.disarm()
            return _M.MAV_RESULT_ACCEPTED
        return _M.MAV_RESULT_UNSUPPORTED

    def _cmd_set_message_interval(self, cmd: Command) -> int:
        msg_id, interval_us = int(cmd.params[0]), int(cmd.params[1])
        if msg_id not in self._builders:
            self._text(_M.MAV_SEVERITY_INFO, f"No ap_message for mavlink id ({msg_id})")
            return _M.MAV_RESULT_FAILED
        if interval_us == 0:  # back to the default rate, if it has one
            if msg_id not in self.STREAMS:
                return _M.MAV_RESULT_FAILED
            interval = self.STREAMS[msg_id]
        elif interval_us == -1:
            interval = 0.0  # stop sending
        else:
            interval = min(max(interval_us, 1000), 60_000_000) / 1e6
        self._intervals[msg_id] = interval
        self._due.pop(msg_id, None)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_get_message_interval(self, cmd: Command) -> int:
        msg_id = int(cmd.params[0])
        if msg_id not in self._builders:
            self._emit(self._mav.message_interval_encode(msg_id, 0))
            return _M.MAV_RESULT_FAILED
        interval = self._intervals.get(msg_id, 0.0)
        self._emit(self._mav.message_interval_encode(msg_id, round(interval * 1e6) if interval > 0 else -1))
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_request_message(self, cmd: Command) -> int:
        builder = self._builders.get(int(cmd.params[0]))
        if builder is None:
            return _M.MAV_RESULT_FAILED
        self._emit(builder())  # e.g. no HOME_POSITION before home is set, yet ACCEPTED (as ArduPilot)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_request_capabilities(self, cmd: Command) -> int:
        if cmd.params[0] == 1.0:
            self._emit(self._msg_autopilot_version())
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_set_relay(self, cmd: Command) -> int:
        # libraries/GCS_MAVLink/GCS_ServoRelay.cpp: ACCEPTED when AP_ServoRelayEvents::do_set_relay(instance, state) succeeds
        instance, state = int(cmd.params[0]), int(cmd.params[1])
        if not 0 <= instance < RELAYS or state not in (0, 1):
            return _M.MAV_RESULT_FAILED
        self.relays[instance] = bool(state)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_set_home(self, cmd: Command) -> int:
        lat, lon = cmd.lat_lon
        use_current = cmd.params[0] == 1.0 or (lat == 0.0 and lon == 0.0)
        if not use_current and not _valid_latlon(lat, lon):
            return _M.MAV_RESULT_DENIED
        if not self.position_ok:  # needs the current location, or at least the EKF origin
            return _M.MAV_RESULT_FAILED
        self.home = (self.vehicle.lat, self.vehicle.lon) if use_current else (lat, lon)
        self._emit(self._msg_home_position())
        return _M.MAV_RESULT_ACCEPTED

    # -- outgoing messages -----------------------------------------------------------------------

    def _msg_heartbeat(self) -> MAVLinkMessage:
        base_mode = _M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if self.mode in self.MANUAL_INPUT_MODES:
            base_mode |= _M.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
        if self.mode in self.AUTOPILOT_MODES:
            base_mode |= _M.MAV_MODE_FLAG_GUIDED_ENABLED
        if self.mode in self.STABILIZE_MODES:
            base_mode |= _M.MAV_MODE_FLAG_STABILIZE_ENABLED
        if self.armed and self.booted:
            base_mode |= _M.MAV_MODE_FLAG_SAFETY_ARMED
        return self._mav.heartbeat_encode(self.profile.mav_type, _M.MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode, self.mode_number, self._system_status())

    def sensor_status(self) -> tuple[int, int, int]:
        """SYS_STATUS present, enabled and health bits, from the firmware's state (libraries/GCS_MAVLink/GCS.cpp).

        The pre-arm bit is healthy exactly when armed or when the pre-arm checks pass (AP_Notify's
        pre_arm_check, set from AP_Arming::pre_arm_checks once a second in Rover.cpp, Plane.cpp...):
        a ground station's "armable" never says yes while arming would be refused.
        """
        present = SENSORS | STARTED_AFTER_BOOT | _M.MAV_SYS_STATUS_PREARM_CHECK
        enabled = health = SENSORS
        enabled |= _M.MAV_SYS_STATUS_PREARM_CHECK  # ARMING_CHECK enables all checks
        if self.booted:
            enabled |= STARTED_AFTER_BOOT
            health |= STARTED_AFTER_BOOT
        if self.armed or not self._prearm_failures():
            health |= _M.MAV_SYS_STATUS_PREARM_CHECK
        controls, enabled_controls = self._control_sensors()
        return present | controls, enabled | enabled_controls, health | enabled_controls

    def _control_sensors(self) -> tuple[int, int]:
        """The controllers this firmware reports (present) and those the current mode uses (enabled and healthy)."""
        return 0, 0

    def _msg_sys_status(self) -> MAVLinkMessage:
        current = self._current_a()
        remaining = max(0.0, 1.0 - self.consumed_mah / BATTERY_MAH)
        volts = BATTERY_EMPTY_V + (BATTERY_FULL_V - BATTERY_EMPTY_V) * remaining - BATTERY_SAG_V_PER_A * current
        battery = (round(volts * 1000), round(current * 100), round(remaining * 100))
        return self._mav.sys_status_encode(*self.sensor_status(), 150, *battery, 0, 0, 0, 0, 0, 0)

    def _msg_gps_raw_int(self) -> MAVLinkMessage:
        v = self.vehicle
        vn, ve, _ = v.velocity_ned
        cog = round(math.degrees(math.atan2(ve, vn)) % 360 * 100) % 36000
        return self._mav.gps_raw_int_encode(
            self._us(), _M.GPS_FIX_TYPE_3D_FIX, _e7(v.lat), _e7(v.lon), round(v.alt_m * 1000), 121, 200, round(math.hypot(vn, ve) * 100), cog, 10
        )

    def _msg_attitude(self) -> MAVLinkMessage:
        yaw = (math.radians(self.vehicle.heading_deg) + math.pi) % (2 * math.pi) - math.pi
        return self._mav.attitude_encode(self._ms(), 0.0, 0.0, yaw, 0.0, 0.0, self.vehicle.yaw_rate_rad_s)

    def _msg_global_position_int(self) -> MAVLinkMessage:
        hdg = round(self.vehicle.heading_deg * 100) % 36000
        if not self.ekf_ready:  # no origin yet: the start point, a wrong altitude, no velocity
            alt_mm = round(WAITING_REL_ALT_M * 1000)
            return self._mav.global_position_int_encode(self._ms(), _e7(self.start[0]), _e7(self.start[1]), alt_mm, alt_mm, 0, 0, 0, hdg)
        v = self.vehicle
        vn, ve, vd = v.velocity_ned
        alt_mm = round(v.alt_m * 1000)
        return self._mav.global_position_int_encode(
            self._ms(), _e7(v.lat), _e7(v.lon), alt_mm, alt_mm, round(vn * 100), round(ve * 100), round(vd * 100), hdg
        )

    def _msg_vfr_hud(self) -> MAVLinkMessage:
        vn, ve, vd = self.vehicle.velocity_ned
        speed = math.hypot(vn, ve)
        throttle = round(self._throttle() * 100)
        return self._mav.vfr_hud_encode(speed, speed, int(self.vehicle.heading_deg) % 360, throttle, self.vehicle.alt_m, -vd)

    def _msg_rc_channels(self) -> MAVLinkMessage:
        return self._mav.rc_channels_encode(self._ms(), len(self.rc_channels), *self.rc_channels, 0, 0, 255)

    def _msg_servo_output_raw(self) -> MAVLinkMessage:
        return self._mav.servo_output_raw_encode(self._us() & 0xFFFFFFFF, 0, *self._servo_outputs())

    def _msg_ekf_status_report(self) -> MAVLinkMessage:
        if self.ekf_ready:
            return self._mav.ekf_status_report_encode(EKF_FLAGS_READY, 0.02, 0.01, 0.01, 0.03, 0.0)
        return self._mav.ekf_status_report_encode(EKF_FLAGS_WAITING, 0.0, 0.0, 0.0, 0.0, 0.0)

    def _msg_nav_controller_output(self) -> MAVLinkMessage | None:
        if self.mode not in self.AUTOPILOT_MODES:
            return None
        target = self._desired_location()
        distance, bearing = (self.vehicle.distance_to(*target), round(self.vehicle.bearing_to(*target))) if target else (0.0, 0)
        return self._mav.nav_controller_output_encode(0.0, 0.0, bearing, bearing, min(round(distance), 65535), 0.0, 0.0, 0.0)

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        target = self._desired_location()
        if target is None:
            return None
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL, TARGET_REPORT_MASK, _e7(target[0]), _e7(target[1]), 0.0, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def _msg_home_position(self) -> MAVLinkMessage | None:
        if self.home is None:
            return None
        return self._mav.home_position_encode(_e7(self.home[0]), _e7(self.home[1]), 0, 0, 0, 0, (1.0, 0.0, 0.0, 0.0), 0, 0, 0, self._us())

    def _msg_gps_global_origin(self) -> MAVLinkMessage | None:
        if not self.ekf_ready:
            return None
        return self._mav.gps_global_origin_encode(_e7(self.start[0]), _e7(self.start[1]), 0, self._us())

    def _msg_autopilot_version(self) -> MAVLinkMessage:
        major, minor = (int(part) for part in self.VERSION.lstrip("V").split("-")[0].split(".")[:2])
        capabilities = (
            _M.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | _M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | _M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | _M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT | _M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
        )  # fmt: skip
        version = major << 24 | minor << 16 | _M.FIRMWARE_VERSION_TYPE_DEV
        return self._mav.autopilot_version_encode(capabilities, version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, 0)


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
    NAV_WAYPOINT of the mission in turn, then stops and stays in AUTO (MIS_DONE_BEHAVE=0); it is
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
    PARAMS: ClassVar[Mapping[str, float]] = {
        "MODE_CH": 8, "CRUISE_SPEED": 2.0, "FRAME_CLASS": 1.0, "SERVO1_FUNCTION": 26.0, "SERVO3_FUNCTION": 70.0, **FIRMWARE_DEFAULTS,
    }  # fmt: skip
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset({
        "MODE_CH", "FRAME_CLASS", "WP_PIVOT_ANGLE", "WP_PIVOT_RATE", "SERVO1_FUNCTION", "SERVO3_FUNCTION",
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
    limits: Limits
    motion: RoverMotion
    _auto_waiting = False  # in AUTO, waiting for an EKF origin to start the mission
    _auto_item: tuple[int | None, StoredCommand] | None = None  # the (seq, item) AUTO is executing
    _auto_hold_until = 0.0  # elapsed_s at which a waypoint's hold time ends

    @property
    def is_boat(self) -> bool:
        return self.profile.mav_type == _M.MAV_TYPE_SURFACE_BOAT

    @property
    def base_limits(self) -> Limits:
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

    def _vehicle_model(self, home: Home, limits: Limits) -> SurfaceVehicle:
        return SurfaceVehicle(home[0], home[1], home[2], limits)

    def _navigator(self, speed_m_s: float | None = None) -> RoverNavigator:
        """A fresh AR_WPNav (a mode's entry calls wp_nav.init(): the default speed again), driving the vehicle."""
        self._nav = RoverNavigator(self.motion, speed_m_s)
        assert isinstance(self.vehicle, SurfaceVehicle)
        self.vehicle.follow(self._nav)
        return self._nav

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {**super()._message_handlers(), "SET_POSITION_TARGET_GLOBAL_INT": self._on_position_target}

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
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
            self._auto_waiting, self._auto_item = True, None
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
        """
        if self._auto_waiting:
            if not self.position_ok:
                return
            self._auto_waiting = False
            self.mission.start_or_resume()
        item = self.mission.current
        if item is None:  # complete (ArduRover stays in AUTO, stopped), or the mission was cleared
            if self._driving or self._loitering:
                self._stop()
            return
        if (self.mission.current_seq, item) == self._auto_item:
            if self._driving and self.vehicle.arrived:
                self._driving = False
                hold_s = item.params[0]  # ModeAuto::verify_nav_wp: a hold time waits there, counted from arrival
                self._auto_hold_until = self.elapsed_s + hold_s
                seq = self.mission.current_seq
                self._text(_M.MAV_SEVERITY_INFO, f"Reached waypoint #{seq}" + (f". Loiter for {hold_s:.0f} seconds" if hold_s else ""))
            if self._driving or self.elapsed_s < self._auto_hold_until - _EPSILON_S:
                return
            item = self.mission.advance()
            if item is None:
                self._stop()
                return
        # the next item, a set-current, or an upload replaced it
        self._auto_item = (self.mission.current_seq, item)
        if item.command == _M.MAV_CMD_NAV_WAYPOINT:
            self._drive(item.lat, item.lon, then=self._next_corner(item))
        else:
            self.mission.advance()

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
        return min(1.0, abs(self.vehicle.speed_m_s) / self.limits.max_m_s) if self.armed else 0.0

    def _servo_outputs(self) -> Sequence[int]:
        """ArduRover's default outputs: SERVO1 ground steering, SERVO3 throttle."""
        steer = max(-1.0, min(1.0, self.vehicle.yaw_rate_rad_s / math.radians(self.limits.turn_rate_deg_s)))
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
        if not msg.type_mask & POS_BITS and not _valid_latlon(lat, lon):
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
        if not _valid_latlon(lat, lon) or (lat == 0.0 and lon == 0.0):
            return _M.MAV_RESULT_DENIED
        if self.mode != "GUIDED" and not self.set_mode(self.profile.modes["GUIDED"]):
            return _M.MAV_RESULT_FAILED
        if cmd.params[0] > 0:
            (self._nav if self._nav is not None else self._navigator()).set_speed(cmd.params[0])
        self._drive(lat, lon, guided=True)
        return _M.MAV_RESULT_ACCEPTED


class _Firmwares(Mapping[str, type[ArduPilotSim]]):
    """Vehicle kind -> simulated firmware class, imported on first use: the other modules' classes subclass this one's."""

    _WHERE: ClassVar[Mapping[str, str]] = MappingProxyType({
        "rover": "executive.sim.ardupilot.base:ArduRoverSim", "boat": "executive.sim.ardupilot.base:ArduRoverSim",
        "bunker": "executive.sim.ardupilot.bunker:BunkerSim", "sub": "executive.sim.ardupilot.sub:ArduSubSim",
        "vtol": "executive.sim.ardupilot.plane:QuadPlaneSim",
    })  # fmt: skip

    def __getitem__(self, kind: str) -> type[ArduPilotSim]:
        module, name = self._WHERE[kind].split(":")
        cls: type[ArduPilotSim] = getattr(importlib.import_module(module), name)
        return cls

    def __iter__(self) -> Iterator[str]:
        return iter(self._WHERE)

    def __len__(self) -> int:
        return len(self._WHERE)


#: The simulated firmware for each vehicle kind (``executive sim --vehicle``).
AUTOPILOTS: Mapping[str, type[ArduPilotSim]] = _Firmwares()
#: Kinds that are another kind's profile on a different vehicle model (a Bunker is an ArduRover rover).
PROFILE_OF: Mapping[str, str] = MappingProxyType({"bunker": "rover"})


#: The simulated autopilot firmwares (``executive sim --autopilot``).
FIRMWARES = ("ardupilot", "px4")


def firmwares_for(autopilot: str) -> Mapping[str, type[ArduPilotSim]]:
    """Vehicle kind -> simulated firmware class, for one autopilot (``ardupilot`` or ``px4``)."""
    if autopilot == "px4":
        from executive.sim.px4.base import PX4_AUTOPILOTS  # subclasses this module's classes

        return PX4_AUTOPILOTS
    if autopilot != "ardupilot":
        raise ValueError(f"no simulated autopilot {autopilot!r} (known: {', '.join(FIRMWARES)})")
    return AUTOPILOTS


def make_autopilot(kind: str, clock: Clock, home: Home = DEFAULT_HOME, *, autopilot: str = "ardupilot", **options: float) -> ArduPilotSim:
    """The simulated autopilot for a vehicle kind; ``options`` go to its class (:class:`ArduPilotSim` and the firmware's own)."""
    firmwares = firmwares_for(autopilot)
    if kind not in firmwares:
        raise ValueError(f"no simulated vehicle of kind {kind!r} on {autopilot} (known: {', '.join(firmwares)})")
    return firmwares[kind](PROFILES[PROFILE_OF.get(kind, kind)], clock, home, **options)
