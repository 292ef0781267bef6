"""What the simulated PX4 sends: its streams and their rates, HEARTBEAT, SYS_STATUS, ESTIMATOR_STATUS, positions above sea level.

src/modules/mavlink/streams/*.hpp fill each message; :class:`Px4Streams` builds them from the state the
commander and the navigator keep (:class:`~executive.sim.px4.base.Px4Sim`).
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import ClassVar

from executive.sim.firmware import FirmwareSim, e7
from executive.sim.px4.modes import PILOT_MODES
from executive.sim.px4.raw_messages import CURRENT_EVENT_SEQUENCE, TIME_ESTIMATE_TO_TARGET, RawMessage
from executive.world.dialect import MAVLinkMessage, mavlink

_M = mavlink

#: The estimator with a GNSS position, moving (0x37f): ekf_helper.cpp get_ekf_soln_status; PRED_POS_HORIZ_REL is "an aiding
#: source is fused" (isHorizontalAidingActive), PRED_POS_HORIZ_ABS "GNSS position fused".
ESTIMATOR_OK = (
    _M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_VELOCITY_HORIZ | _M.ESTIMATOR_VELOCITY_VERT | _M.ESTIMATOR_POS_HORIZ_REL
    | _M.ESTIMATOR_POS_HORIZ_ABS | _M.ESTIMATOR_POS_VERT_ABS | _M.ESTIMATOR_POS_VERT_AGL | _M.ESTIMATOR_PRED_POS_HORIZ_REL
    | _M.ESTIMATOR_PRED_POS_HORIZ_ABS
)  # fmt: skip
#: The same at rest on the ground (0x3ff, as the real SITL reported before take-off): const_pos_mode is set for vehicle_at_rest too.
ESTIMATOR_AT_REST = ESTIMATOR_OK | _M.ESTIMATOR_CONST_POS_MODE
ESTIMATOR_NO_POSITION = _M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_VELOCITY_VERT | _M.ESTIMATOR_POS_VERT_ABS | _M.ESTIMATOR_CONST_POS_MODE
# SYS_STATUS (src/modules/mavlink/streams/SYS_STATUS.hpp): each component's present/enabled/health from the health
# report; the AHRS bit is the local position estimate; the pre-arm bit is only ever set in the health field.
SENSORS = (
    _M.MAV_SYS_STATUS_SENSOR_3D_GYRO | _M.MAV_SYS_STATUS_SENSOR_3D_ACCEL | _M.MAV_SYS_STATUS_SENSOR_3D_MAG
    | _M.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE | _M.MAV_SYS_STATUS_SENSOR_DIFFERENTIAL_PRESSURE | _M.MAV_SYS_STATUS_SENSOR_GPS
    | _M.MAV_SYS_STATUS_AHRS | _M.MAV_SYS_STATUS_SENSOR_BATTERY | _M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
)  # fmt: skip
POSITION_SENSORS = _M.MAV_SYS_STATUS_SENSOR_GPS | _M.MAV_SYS_STATUS_AHRS  # healthy only with a position estimate

#: Messages sent unasked, with their interval (s), as PX4's "normal" MAVLink mode streams them (mavlink_main.cpp,
#: configure_streams: ESTIMATOR_STATUS 0.5 Hz, EXTENDED_SYS_STATE 1 Hz, GLOBAL_POSITION_INT 5 Hz, HOME_POSITION 0.5 Hz...);
#: ATTITUDE at 4 Hz, not 15, to spare the simulation.
PX4_INTERVALS: Mapping[int, float] = MappingProxyType({
    _M.MAVLINK_MSG_ID_HEARTBEAT: 1.0, _M.MAVLINK_MSG_ID_SYS_STATUS: 1.0, _M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 1.0,
    _M.MAVLINK_MSG_ID_ESTIMATOR_STATUS: 0.5, _M.MAVLINK_MSG_ID_ATTITUDE: 0.25, _M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 0.2,
    _M.MAVLINK_MSG_ID_GPS_RAW_INT: 1.0, _M.MAVLINK_MSG_ID_VFR_HUD: 0.25, _M.MAVLINK_MSG_ID_HOME_POSITION: 2.0,
    _M.MAVLINK_MSG_ID_MISSION_CURRENT: 1.0, _M.MAVLINK_MSG_ID_POSITION_TARGET_GLOBAL_INT: 1.0,
    _M.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: 1.0, _M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: 1.0,
    _M.MAVLINK_MSG_ID_OPEN_DRONE_ID_LOCATION: 1.0, CURRENT_EVENT_SEQUENCE[0]: 1.0, TIME_ESTIMATE_TO_TARGET[0]: 1.0,
    _M.MAVLINK_MSG_ID_BATTERY_STATUS: 2.0,  # configure_stream_local("BATTERY_STATUS", 0.5f)
})  # fmt: skip


class Px4Streams(FirmwareSim):
    """The messages a simulated PX4 sends, as its MAVLink streams fill them (a subclass keeps the state they report)."""

    STREAMS: ClassVar[Mapping[int, float]] = PX4_INTERVALS
    home_amsl_m: float  # the start point's altitude above sea level
    _goal: tuple[float, float, float] | None  # lat, lon, height above home the mode flies to
    _landed: bool
    _event_sequence = 0

    @property
    @abstractmethod
    def at_rest(self) -> bool:
        """The estimator's ``vehicle_at_rest``."""

    @property
    @abstractmethod
    def landed_state(self) -> int:
        """EXTENDED_SYS_STATE landed_state (MAV_LANDED_STATE)."""

    @property
    @abstractmethod
    def vtol_state(self) -> int:
        """EXTENDED_SYS_STATE vtol_state (MAV_VTOL_STATE)."""

    @abstractmethod
    def can_arm(self) -> bool:
        """What the health and arming checks say now (SYS_STATUS MAV_SYS_STATUS_PREARM_CHECK)."""

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        return {
            **super()._message_builders(),
            _M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self._msg_extended_sys_state,
            _M.MAVLINK_MSG_ID_ESTIMATOR_STATUS: self._msg_estimator_status,
            _M.MAVLINK_MSG_ID_OPEN_DRONE_ID_LOCATION: self._msg_open_drone_id_location,
            CURRENT_EVENT_SEQUENCE[0]: self._msg_current_event_sequence,
            TIME_ESTIMATE_TO_TARGET[0]: self._msg_time_estimate_to_target,
        }

    def _msg_heartbeat(self) -> MAVLinkMessage:
        base_mode = _M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if self.mode in self.AUTOPILOT_MODES:
            base_mode |= _M.MAV_MODE_FLAG_AUTO_ENABLED | _M.MAV_MODE_FLAG_GUIDED_ENABLED | _M.MAV_MODE_FLAG_STABILIZE_ENABLED
        elif self.mode in PILOT_MODES:
            base_mode |= _M.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED | _M.MAV_MODE_FLAG_STABILIZE_ENABLED
        if self.armed:
            base_mode |= _M.MAV_MODE_FLAG_SAFETY_ARMED
        return self._mav.heartbeat_encode(self.profile.mav_type, _M.MAV_AUTOPILOT_PX4, base_mode, self.mode_number, self._system_status())

    def sensor_status(self) -> tuple[int, int, int]:
        """SYS_STATUS present, enabled, health: the pre-arm bit healthy when arming in the current mode would pass."""
        health = SENSORS if self.position_ok else SENSORS & ~POSITION_SENSORS
        if self.can_arm():
            health |= _M.MAV_SYS_STATUS_PREARM_CHECK
        return SENSORS, SENSORS, health

    def _msg_estimator_status(self) -> MAVLinkMessage:
        if self.position_ok:
            flags = ESTIMATOR_AT_REST if self.at_rest else ESTIMATOR_OK
            return self._mav.estimator_status_encode(self._us(), flags, 0.05, 0.1, 0.1, 0.1, 0.0, 0.0, 0.5, 0.8)
        return self._mav.estimator_status_encode(self._us(), ESTIMATOR_NO_POSITION, 0.0, 0.0, 0.1, 0.1, 0.0, 0.0, 0.0, 0.0)

    def _msg_extended_sys_state(self) -> MAVLinkMessage:
        return self._mav.extended_sys_state_encode(self.vtol_state, self.landed_state)

    def _msg_global_position_int(self) -> MAVLinkMessage | None:
        if not self.position_ok:
            return None  # no global position yet: PX4 does not send one
        v = self.vehicle
        vn, ve, vd = v.velocity_ned
        rel = round(v.alt_m * 1000)
        return self._mav.global_position_int_encode(
            self._ms(), e7(v.lat), e7(v.lon), round(self.home_amsl_m * 1000) + rel, rel,
            round(vn * 100), round(ve * 100), round(vd * 100), round(v.heading_deg * 100) % 36000,
        )  # fmt: skip

    def _msg_gps_raw_int(self) -> MAVLinkMessage:
        msg = super()._msg_gps_raw_int()
        msg.alt += round(self.home_amsl_m * 1000)
        return msg

    def _msg_vfr_hud(self) -> MAVLinkMessage:
        msg = super()._msg_vfr_hud()
        msg.alt += self.home_amsl_m
        return msg

    def _msg_home_position(self) -> MAVLinkMessage | None:
        if self.home is None:
            return None
        alt_mm = round(self.home_amsl_m * 1000)
        return self._mav.home_position_encode(e7(self.home[0]), e7(self.home[1]), alt_mm, 0, 0, 0, (1.0, 0.0, 0.0, 0.0), 0, 0, 0, self._us())

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        """The navigator's current setpoint (streams/POSITION_TARGET_GLOBAL_INT.hpp); none in OFFBOARD, where the navigator
        publishes its triplet invalid once (navigator_main.cpp Navigator::run, the modes it does not fly: reset_triplets)."""
        if self._goal is None or self.mode == "OFFBOARD":
            return None
        lat, lon, alt = self._goal
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL_INT, 0xFF8, e7(lat), e7(lon), alt + self.home_amsl_m, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def _msg_open_drone_id_location(self) -> MAVLinkMessage | None:
        if not self.position_ok:
            return None
        v = self.vehicle
        amsl = self.home_amsl_m + v.alt_m
        return self._mav.open_drone_id_location_encode(
            0, 0, bytes(20), _M.MAV_ODID_STATUS_AIRBORNE if not self._landed else _M.MAV_ODID_STATUS_GROUND,
            round(v.heading_deg) % 360, round(v.speed_m_s * 100), 0, e7(v.lat), e7(v.lon), amsl, amsl, _M.MAV_ODID_HEIGHT_REF_OVER_TAKEOFF,
            v.alt_m, _M.MAV_ODID_HOR_ACC_1_METER, _M.MAV_ODID_VER_ACC_1_METER, _M.MAV_ODID_VER_ACC_1_METER, _M.MAV_ODID_SPEED_ACC_1_METERS_PER_SECOND,
            self.elapsed_s % 3600, _M.MAV_ODID_TIME_ACC_0_1_SECOND,
        )  # fmt: skip

    def _msg_current_event_sequence(self) -> MAVLinkMessage:
        return RawMessage(CURRENT_EVENT_SEQUENCE[0], CURRENT_EVENT_SEQUENCE[1], CURRENT_EVENT_SEQUENCE[2], (self._event_sequence, 0))

    def _msg_time_estimate_to_target(self) -> MAVLinkMessage:
        return RawMessage(TIME_ESTIMATE_TO_TARGET[0], TIME_ESTIMATE_TO_TARGET[1], TIME_ESTIMATE_TO_TARGET[2], (-1, -1, -1, -1, -1))
