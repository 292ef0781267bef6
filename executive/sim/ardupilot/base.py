"""What every simulated ArduPilot firmware does alike: its modes and arming, the EKF, HEARTBEAT and SYS_STATUS.

:class:`ArduPilotSim` adds to the shared :class:`~executive.sim.firmware.FirmwareSim` what ArduPilot does:
modes set by ``custom_mode`` (DO_SET_MODE and SET_MODE, acked at once), arming and its pre-arm checks,
the EKF's slow start and its failsafe, EKF_STATUS_REPORT, RC_CHANNELS, STATUSTEXT notices. A subclass per
firmware adds its modes and the vehicle model they drive: :mod:`~executive.sim.ardupilot.rover` (rovers
and boats), :mod:`~executive.sim.ardupilot.sub`, :mod:`~executive.sim.ardupilot.plane` (QuadPlane).

The behaviour follows ArduPilot's source and what a real ArduRover did, quirks included: the firmware
is the reference, not the MAVLink spec.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import ClassVar

from executive.sim.ardupilot.mission_store import ArduPilotMissionStore
from executive.sim.firmware import DEFAULT_HOME, EPSILON_S, Command, CommandHandler, FirmwareSim, Home, e7
from executive.sim.mission_store import MissionStore
from executive.sim.zone_stores import ArduPilotFenceStore, ArduPilotRallyStore
from executive.world.clock import Clock
from executive.world.dialect import AUTOPILOT_COMPONENT, MAVLinkMessage, mavlink
from executive.world.vehicles import VehicleProfile

#: ArduPilot's magic param2 values for MAV_CMD_COMPONENT_ARM_DISARM (GCS_MAVLink/GCS.h).
#: 2989 skips the pre-arm checks; 21196 only forces a *disarm* (an arm with it is checked as usual).
FORCE_ARM = 2989.0

EKF_FLAGS_READY = 0x33F  # 831, as read on the real firmware once the EKF uses GPS
EKF_FLAGS_WAITING = 0xA7  # attitude, velocities, vertical position, constant-position mode: no GPS yet
WAITING_REL_ALT_M = 9.7  # the wrong altitude GLOBAL_POSITION_INT carries before the EKF has an origin
PREARM_AHRS = "AHRS: not using configured AHRS type"
PREARM_REPORT_S = 30.0  # a disarmed ArduPilot repeats its failing pre-arm checks this often

_M = mavlink
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
        _M.MAVLINK_MSG_ID_MISSION_CURRENT, _M.MAVLINK_MSG_ID_BATTERY_STATUS,  # BATTERY_STATUS: SRn_EXT_STAT, as SYS_STATUS
    ), _STREAM_S),
})  # fmt: skip


class ArduPilotSim(FirmwareSim):
    """The firmware-independent part of a simulated ArduPilot (see the module's docstring)."""

    VERSION: ClassVar[str] = "V4.7.0-dev"
    READY_TEXT: ClassVar[str]
    BOOT_MODE: ClassVar[str] = "INITIALISING"
    INITIAL_MODE: ClassVar[str] = "MANUAL"
    MANUAL_INPUT_MODES: ClassVar[frozenset[str]] = frozenset()  # HEARTBEAT MANUAL_INPUT_ENABLED
    STABILIZE_MODES: ClassVar[frozenset[str]] = frozenset()  # HEARTBEAT STABILIZE_ENABLED
    STREAMS: ClassVar[Mapping[int, float]] = DEFAULT_INTERVALS
    POSITION_MODES: ClassVar[frozenset[str]] = frozenset()  # refused while armed without a position estimate
    UNARMABLE_MODES: ClassVar[frozenset[str]] = frozenset()
    #: The firmware's own EKF failsafe (Rover/ekf_check.cpp): the mode it puts a vehicle in a position mode in; None: not modelled.
    EKF_FAILSAFE_MODE: ClassVar[str | None] = None
    #: ekf_check runs at 10 Hz and latches after EKF_CHECK_ITERATIONS_MAX (10) bad checks in a row; it clears 10 good ones later.
    EKF_CHECK_ITERATIONS_MAX: ClassVar[int] = 10
    MISSION_STORE: ClassVar[type[MissionStore]] = ArduPilotMissionStore  # the firmware's side of the mission protocol
    ZONE_STORES: ClassVar[tuple[type[MissionStore], ...]] = (ArduPilotFenceStore, ArduPilotRallyStore)
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset({"MODE_CH", "FLTMODE_CH"})  # answered as integers (MAV_PARAM_TYPE_INT8), the rest REAL32
    BATTERY_CAPACITY_PARAM = "BATT_CAPACITY"

    def battery_params(self, capacity_mah: float) -> dict[str, float]:
        """SITL's analog voltage-and-current monitor (BATT_MONITOR 4) on the pack (AP_BattMonitor_Params.cpp); arming asks nothing of it."""
        return {"BATT_MONITOR": 4.0, "BATT_CAPACITY": capacity_mah, "BATT_ARM_MAH": 0.0, "BATT_ARM_VOLT": 0.0}

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
        #: The firmware's EKF failsafe is latched (Rover ``failsafe.ekf``): position modes are refused meanwhile.
        self.failsafe_ekf = False
        self._ekf_fail_count = 0
        self._prearm_reported_at = -math.inf
        super().__init__(
            profile, clock, home, system_id=system_id, component_id=component_id, ekf_ready_after_s=ekf_ready_after_s, boot_s=boot_s, params=params
        )

    def _check_health(self) -> None:
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

    def _prearm_failures(self) -> list[str]:
        """Why arming would be refused now (without the "PreArm: " prefix)."""
        failures = [] if self.ekf_ready else [PREARM_AHRS]
        if self.mode in self.UNARMABLE_MODES:
            failures.append("Mode not armable")
        return failures

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {**super()._message_handlers(), "SET_MODE": self._on_set_mode}

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_SET_MODE: lambda cmd: self._set_mode_common(int(cmd.params[0]), int(cmd.params[1])),
            _M.MAV_CMD_COMPONENT_ARM_DISARM: self._cmd_arm_disarm,
        }

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        return {
            **super()._message_builders(),
            _M.MAVLINK_MSG_ID_RC_CHANNELS: self._msg_rc_channels,
            _M.MAVLINK_MSG_ID_EKF_STATUS_REPORT: self._msg_ekf_status_report,
        }

    # -- time-driven behaviour -------------------------------------------------------------------

    def _events(self) -> None:
        if not self._booted and self.elapsed_s >= self.boot_s - EPSILON_S:
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

    # -- incoming messages -----------------------------------------------------------------------

    def _on_set_mode(self, msg: MAVLinkMessage) -> None:
        # ArduPilot acks the SET_MODE message with a COMMAND_ACK whose command is the message id (11)
        self._ack_first(msg, _M.MAVLINK_MSG_ID_SET_MODE, lambda: self._set_mode_common(msg.base_mode, msg.custom_mode))

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

    def _msg_global_position_int(self) -> MAVLinkMessage:
        hdg = round(self.vehicle.heading_deg * 100) % 36000
        if not self.ekf_ready:  # no origin yet: the start point, a wrong altitude, no velocity
            alt_mm = round(WAITING_REL_ALT_M * 1000)
            return self._mav.global_position_int_encode(self._ms(), e7(self.start[0]), e7(self.start[1]), alt_mm, alt_mm, 0, 0, 0, hdg)
        v = self.vehicle
        vn, ve, vd = v.velocity_ned
        alt_mm = round(v.alt_m * 1000)
        return self._mav.global_position_int_encode(
            self._ms(), e7(v.lat), e7(v.lon), alt_mm, alt_mm, round(vn * 100), round(ve * 100), round(vd * 100), hdg
        )

    def _msg_rc_channels(self) -> MAVLinkMessage:
        return self._mav.rc_channels_encode(self._ms(), len(self.rc_channels), *self.rc_channels, 0, 0, 255)

    def _msg_ekf_status_report(self) -> MAVLinkMessage:
        if self.ekf_ready and self.ekf_position_lost:  # as an injected loss rewrites it (executive.sim.faults): said by the EKF itself
            return self._mav.ekf_status_report_encode((EKF_FLAGS_READY & ~_M.EKF_POS_HORIZ_ABS) | _M.EKF_CONST_POS_MODE, 0.02, 0.01, 0.01, 0.03, 0.0)
        if self.ekf_ready:
            return self._mav.ekf_status_report_encode(EKF_FLAGS_READY, 0.02, 0.01, 0.01, 0.03, 0.0)
        return self._mav.ekf_status_report_encode(EKF_FLAGS_WAITING, 0.0, 0.0, 0.0, 0.0, 0.0)

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        target = self._desired_location()
        if target is None:
            return None
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL, TARGET_REPORT_MASK, e7(target[0]), e7(target[1]), 0.0, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def _msg_home_position(self) -> MAVLinkMessage | None:
        if self.home is None:
            return None
        return self._mav.home_position_encode(e7(self.home[0]), e7(self.home[1]), 0, 0, 0, 0, (1.0, 0.0, 0.0, 0.0), 0, 0, 0, self._us())
