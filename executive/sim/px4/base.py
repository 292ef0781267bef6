"""PX4 as the simulated vehicles' autopilot: a standard VTOL (the simulated QuadPlane airframe) and a rover.

It reuses the simulated ArduPilot's machinery (clock, vehicle models, telemetry streams, mission
store, fault injection) and replaces what PX4 does differently, as PX4 main (2025) behaved over
MAVLink (issue 12) and as its source reads:

- HEARTBEAT autopilot 12 (MAV_AUTOPILOT_PX4), type 22 for a standard VTOL, 10 for a rover; ``custom_mode`` packs
  the main mode in bits 16-23 and the sub mode in bits 24-31; it sits in AUTO.LOITER (0x03040000)
  from boot, on the ground too.
- Commands go from the MAVLink receiver to the commander (src/modules/mavlink/mavlink_receiver.cpp,
  handle_message_command_both): the receiver acks only its own few (message intervals, autopilot
  version, REQUEST_MESSAGE), the commander (src/modules/commander/Commander.cpp, handle_command /
  answer_command) acks the rest on its next loop, here the next :meth:`update`. MAV_CMD_DO_SET_MODE
  is acked twice: the receiver passes it on yet acks it ACCEPTED at once, then the commander's result (ACCEPTED, or TEMPORARILY_REJECTED after a
  STATUSTEXT "Switching to <mode> is currently not available", Commander::printRejectMode). A
  SET_MODE message is a DO_SET_MODE for the commander: its ack carries command 176.
- Arming is refused (TEMPORARILY_REJECTED, "Arming denied: Resolve system health failures first")
  until the estimator has a position, ~3 s after boot on the SIH simulation; param2 21196 does not
  skip the checks for a command from outside (Commander::arm runs them when ``from_external``).
  Armed and never taken off, it disarms itself after COM_SPOOLUP_TIME + COM_DISARM_PRFLT (1 + 10 s),
  "Disarmed by auto preflight disarming"; landed after a flight, after COM_DISARM_LAND (2 s), "Disarmed by
  landing" (Commander::handleAutoDisarm; defaults in src/modules/commander/commander_params.c).
- Estimator health is in ESTIMATOR_STATUS flags and SYS_STATUS health bits; there is no
  EKF_STATUS_REPORT. At rest on the ground the flags carry ESTIMATOR_CONST_POS_MODE (128) beside the
  GNSS position: 0x3ff, as the real SITL showed before arming (src/modules/ekf2/EKF/ekf_helper.cpp
  get_ekf_soln_status sets it for ``vehicle_at_rest``, which src/modules/land_detector/LandDetector.cpp
  publishes as landed and no IMU vibration for 1 s); armed, the spinning motors shake the IMU: 0x37f on
  the ground (real SITL, 0.8 s after arming) and in flight, 0x3ff again 1 s after a landing's disarm.
- Disarmed (by landing, pre-flight, a command), it goes back to the last mode a user asked for that
  does not prevent arming (Commander::disarm -> UserModeIntention::onDisarm; AUTO.RTL, AUTO.LAND and
  AUTO.PRECLAND prevent it, ModeUtil/mode_requirements.cpp; the take-off's and the mission's end in
  AUTO.LOITER count as asked): after a take-off and an RTL landing, AUTO.LOITER, as the real SITL showed.
- OFFBOARD needs a recent setpoint (SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT younger than
  COM_OF_LOSS_T = 1 s, HealthAndArmingChecks/checks/offboardCheck.cpp); a gap longer than that in
  OFFBOARD is the offboard failsafe (failsafe/failsafe.cpp checkModeFallback): without RC, POSCTL
  (holding), then AUTO.LAND after COM_FAIL_ACT_T, then it disarms on the ground.
- NAV_TAKEOFF param7 is an altitude AMSL (NaN: MIS_TAKEOFF_ALT above home): AUTO.TAKEOFF, then
  AUTO.LOITER once there (Commander::checkForMissionUpdate). Finite param5/param6 are the take-off
  point's latitude and longitude (navigator_main.cpp, VEHICLE_CMD_NAV_TAKEOFF; NaN: here): the
  multicopter takes off only if the straight climb towards it asks for more than 0.3 m/s upwards
  (flight_mode_manager FlightTaskAuto.cpp ``_want_takeoff``, FlightTask::_checkTakeoff): 0, 0, a point
  thousands of kilometres off, is ACCEPTED, shows AUTO.TAKEOFF and never climbs (as the real SITL did)
  until the pre-flight auto-disarm. DO_REPOSITION needs the change-mode
  flag (else UNSUPPORTED) and flies to the point in AUTO.LOITER.
- Missions: the upload is driven with MISSION_REQUEST_INT and item 0 is the first item (no home
  slot); AUTO.MISSION is refused for ~1 s after the upload while PX4 checks it; a finished mission
  shows MISSION_CURRENT mission_state 5 (COMPLETE) and the vehicle loiters (AUTO.LOITER) in the air.
- MAV_CMD_DO_VTOL_TRANSITION in flight: EXTENDED_SYS_STATE vtol_state 3 (MC) -> 1 (TRANSITION_TO_FW)
  -> 4 (FW) once the airspeed reaches ~9.7 m/s (as the real standard VTOL did), and 2
  (TRANSITION_TO_MC) -> 3 back. In FW, holding a point is circling it at NAV_LOITER_RAD (80 m).
- It watches the HEARTBEATs of ground stations and mission computers (Commander::dataLinkCheck): after
  COM_DL_LOSS_T (10 s) without one from a GCS, "Connection to ground station lost"; after COM_OBC_LOSS_T
  (5 s) without one from an onboard controller (the executive), "Connection to mission computer lost";
  each says "... regained" when they resume. With NAV_DLL_ACT at its default (disabled) nothing else happens.
- Messages outside the ardupilotmega dialect go out as raw MAVLink 2 frames (CURRENT_EVENT_SEQUENCE
  411, TIME_ESTIMATE_TO_TARGET 380), and OPEN_DRONE_ID_LOCATION; STATUSTEXTs over 50 bytes go in
  chunks sharing an ``id`` (``chunk_seq`` 0, 1...).

Not simulated, or simplified: RC (so the manual modes, POSCTL included, cannot be selected), velocity
and acceleration setpoints (they keep OFFBOARD alive; the vehicle holds), events (EVENT, 410), the
return to OFFBOARD when the stream comes back during the failsafe, parameters; RTL flies straight to
home at RTL_RETURN_ALT (no climb first, no descent stage); in fixed-wing flight every point is
circled at NAV_LOITER_RAD and a waypoint counts as reached on that circle; the failsafe texts are
ours (PX4 reports them as events); unknown mission items are passed over.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from abc import abstractmethod
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import ClassVar

from executive.clock import Clock
from executive.io.mavlink.dialect import MAVLinkMessage, mavlink
from executive.io.mavlink.modes import PX4_MODES
from executive.sim.ardupilot.base import DEFAULT_HOME, ArduPilotSim, Command, Home, _e7, _valid_latlon
from executive.sim.mission_store import MissionState, MissionStore, StoredCommand
from executive.sim.physics.aircraft import QUADPLANE_LIMITS, AircraftLimits, QuadPlaneModel, Regime
from executive.sim.physics.vehicle import ROVER_LIMITS, Limits, SurfaceVehicle, VehicleModel
from executive.vehicles import VehicleProfile

_M = mavlink

MAV_TYPE_VTOL_FIXEDROTOR = 22  # a standard VTOL ("VTOL_RESERVED2" in pymavlink's older dialect)
FORCE_ARM_DISARM = 21196  # Commander.cpp: param2 that forces a disarm (and an internal arm)
ESTIMATOR_READY_S = 3.0  # the SIH estimator's position came 2-4 s after boot (issue 12)
HOME_AMSL_M = 584.0  # the start point's altitude above sea level (ArduPilot SITL's CMAC field)
COM_OF_LOSS_T = 1.0  # offboard signal lost after this long without a setpoint
COM_FAIL_ACT_T = 5.0  # failsafe: hold this long before the action
COM_DISARM_PRFLT = 10.0  # armed without taking off: disarm this long after the spool-up
COM_SPOOLUP_TIME = 1.0  # the motors' spool-up after arming (counted before COM_DISARM_PRFLT)
MPC_XY_CRUISE = 5.0  # the multicopter's cruise speed along a straight path (m/s)
WANT_TAKEOFF_M_S = 0.3  # FlightTaskAuto: a take-off needs an upward velocity setpoint over this
COM_DISARM_LAND = 2.0  # landed: disarm after this long
MIS_TAKEOFF_ALT = 2.5  # NAV_TAKEOFF with param7 NaN: this high above home
NAV_LOITER_RAD = 80.0  # fixed-wing loiter radius
NAV_ACC_RAD = 10.0  # mission waypoint acceptance radius (multicopter)
RTL_RETURN_ALT = 60.0  # RTL flies home at least this high
ROVER_NAV_ACC_RAD = 0.5  # a rover's waypoint acceptance radius (ROMFS rc.rover_differential_defaults)
TRANSITION_AIRSPEED_M_S = 9.7  # the real standard VTOL's front transition ended at ~9.7 m/s (issue 12)
VT_B_TRANS_DUR = 4.0  # back transition: at most this long
MISSION_CHECK_S = 1.0  # after an upload, AUTO.MISSION is refused this long (issue 12)
COM_DL_LOSS_T = 10.0  # no ground-station HEARTBEAT this long: "Connection to ground station lost"
COM_OBC_LOSS_T = 5.0  # no onboard-computer HEARTBEAT this long: "Connection to mission computer lost"
DISARMED_TIMEOUT_S = math.inf

#: PX4 mode name -> custom_mode, as the executive's mode table numbers them.
PX4_MODE_NUMBERS: Mapping[str, int] = MappingProxyType(dict(PX4_MODES))
#: Names PX4 reports modes by in STATUSTEXT (mode_util::nav_state_names).
NAV_STATE_NAMES: Mapping[str, str] = MappingProxyType({
    "MANUAL": "Manual", "ALTCTL": "Altitude", "POSCTL": "Position", "AUTO.MISSION": "Mission", "AUTO.LOITER": "Hold",
    "AUTO.RTL": "Return", "OFFBOARD": "Offboard", "STABILIZED": "Stabilized", "AUTO.TAKEOFF": "Takeoff", "AUTO.LAND": "Land",
    "AUTO.FOLLOW_TARGET": "Follow Target", "AUTO.PRECLAND": "Precision Land", "ACRO": "Acro", "AUTO.READY": "Ready",
    "RATTITUDE": "Rattitude",
})  # fmt: skip
#: Modes that need the pilot's sticks (mode requirement "manual control"): never available without RC.
PILOT_MODES = frozenset({"MANUAL", "ALTCTL", "POSCTL", "STABILIZED", "ACRO", "RATTITUDE"})
#: Modes with mode_req_prevent_arming (ModeUtil/mode_requirements.cpp): never the mode PX4 goes back to once disarmed.
PREVENT_ARMING_MODES = frozenset({"AUTO.RTL", "AUTO.LAND", "AUTO.PRECLAND", "AUTO.FOLLOW_TARGET"})
NOT_SIMULATED = frozenset({"AUTO.READY", "AUTO.FOLLOW_TARGET", "AUTO.PRECLAND"})
#: Commands the MAVLink receiver answers itself, at once (mavlink_receiver.cpp).
RECEIVER_COMMANDS = frozenset({
    _M.MAV_CMD_SET_MESSAGE_INTERVAL, _M.MAV_CMD_GET_MESSAGE_INTERVAL, _M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
    _M.MAV_CMD_REQUEST_MESSAGE,
})  # fmt: skip

#: The estimator with a GNSS position, moving (0x37f): ekf_helper.cpp get_ekf_soln_status; PRED_POS_HORIZ_REL is "an aiding
#: source is fused" (isHorizontalAidingActive), PRED_POS_HORIZ_ABS "GNSS position fused".
ESTIMATOR_OK = (
    _M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_VELOCITY_HORIZ | _M.ESTIMATOR_VELOCITY_VERT | _M.ESTIMATOR_POS_HORIZ_REL
    | _M.ESTIMATOR_POS_HORIZ_ABS | _M.ESTIMATOR_POS_VERT_ABS | _M.ESTIMATOR_POS_VERT_AGL | _M.ESTIMATOR_PRED_POS_HORIZ_REL
    | _M.ESTIMATOR_PRED_POS_HORIZ_ABS
)  # fmt: skip
#: The same at rest on the ground (0x3ff, as the real SITL reported before take-off): const_pos_mode is set for vehicle_at_rest too.
ESTIMATOR_AT_REST = ESTIMATOR_OK | _M.ESTIMATOR_CONST_POS_MODE
#: LandDetector::UpdateVehicleAtRest: at rest once no movement for this long (and landed).
AT_REST_AFTER_S = 1.0
ESTIMATOR_NO_POSITION = _M.ESTIMATOR_ATTITUDE | _M.ESTIMATOR_VELOCITY_VERT | _M.ESTIMATOR_POS_VERT_ABS | _M.ESTIMATOR_CONST_POS_MODE
# SYS_STATUS (src/modules/mavlink/streams/SYS_STATUS.hpp): each component's present/enabled/health from the health
# report; the AHRS bit is the local position estimate; the pre-arm bit is only ever set in the health field.
SENSORS = (
    _M.MAV_SYS_STATUS_SENSOR_3D_GYRO | _M.MAV_SYS_STATUS_SENSOR_3D_ACCEL | _M.MAV_SYS_STATUS_SENSOR_3D_MAG
    | _M.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE | _M.MAV_SYS_STATUS_SENSOR_DIFFERENTIAL_PRESSURE | _M.MAV_SYS_STATUS_SENSOR_GPS
    | _M.MAV_SYS_STATUS_AHRS | _M.MAV_SYS_STATUS_SENSOR_BATTERY | _M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
)  # fmt: skip
POSITION_SENSORS = _M.MAV_SYS_STATUS_SENSOR_GPS | _M.MAV_SYS_STATUS_AHRS  # healthy only with a position estimate

# Messages of MAVLink's common set that pymavlink's ardupilotmega dialect lacks: id, name, wire fields (type, name).
CURRENT_EVENT_SEQUENCE = (411, "CURRENT_EVENT_SEQUENCE", (("uint16_t", "sequence"), ("uint8_t", "flags")))
TIME_ESTIMATE_TO_TARGET = (
    380, "TIME_ESTIMATE_TO_TARGET",
    tuple(("int32_t", f) for f in ("safe_return", "land", "mission_next_item", "mission_end", "commanded_action")),
)  # fmt: skip

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
})  # fmt: skip

#: HEARTBEAT type -> what the commander says when its heartbeats stop, and when they come back (Commander.cpp).
LINK_LOSS_TEXTS: Mapping[int, tuple[str, str]] = MappingProxyType({
    _M.MAV_TYPE_GCS: ("Connection to ground station lost", "GCS connection regained"),
    _M.MAV_TYPE_ONBOARD_CONTROLLER: ("Connection to mission computer lost", "Onboard controller regained"),
})  # fmt: skip

#: Mission items the simulated PX4 takes (others: MAV_MISSION_UNSUPPORTED), those with a position, and their frames.
PX4_LOCATION_COMMANDS = frozenset({
    _M.MAV_CMD_NAV_WAYPOINT, _M.MAV_CMD_NAV_LOITER_UNLIM, _M.MAV_CMD_NAV_LOITER_TIME, _M.MAV_CMD_NAV_TAKEOFF,
    _M.MAV_CMD_NAV_LAND, _M.MAV_CMD_NAV_VTOL_TAKEOFF, _M.MAV_CMD_NAV_VTOL_LAND,
})  # fmt: skip
PX4_MISSION_COMMANDS = PX4_LOCATION_COMMANDS | {
    _M.MAV_CMD_NAV_RETURN_TO_LAUNCH, _M.MAV_CMD_DO_VTOL_TRANSITION, _M.MAV_CMD_DO_CHANGE_SPEED, _M.MAV_CMD_DO_JUMP,
}  # fmt: skip
PX4_MISSION_FRAMES = frozenset({
    _M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
})  # fmt: skip

_TYPES = {"uint8_t": "B", "int8_t": "b", "uint16_t": "H", "int16_t": "h", "uint32_t": "I", "int32_t": "i", "float": "f"}


class RawMessage(MAVLinkMessage):
    """A MAVLink 2 message of a definition the loaded dialect lacks, packed from its wire fields (in wire order)."""

    def __init__(self, msg_id: int, name: str, fields: Sequence[tuple[str, str]], values: Sequence[int | float]) -> None:
        super().__init__(msg_id, name)
        self._fieldnames = [field for _, field in fields]
        for field, value in zip(self._fieldnames, values, strict=True):
            setattr(self, field, value)
        self._raw_payload = struct.pack("<" + "".join(_TYPES[kind] for kind, _ in fields), *values)
        self._crc_extra = crc_extra(name, fields)

    def pack(self, mav: mavlink.MAVLink, force_mavlink1: bool = False) -> bytes:
        return self._pack(mav, self._crc_extra, self._raw_payload, force_mavlink1=force_mavlink1)


def crc_extra(name: str, fields: Sequence[tuple[str, str]]) -> int:
    """A message definition's CRC_EXTRA, as mavgen computes it (scalar fields, in wire order)."""
    crc = mavlink.x25crc(f"{name} ".encode())
    for kind, field in fields:
        crc.accumulate(f"{kind} {field} ".encode())
    return (crc.crc & 0xFF) ^ (crc.crc >> 8)


class Px4MissionStore(MissionStore):
    """PX4's side of the mission protocol: MISSION_REQUEST_INT, no home slot, no STATUSTEXT on upload or completion.

    It stores the VTOL items ArduPilot's store lacks (take-off, landing, transitions) with their
    parameters as sent (NaN included: PX4 keeps a NaN yaw as "unchanged").
    """

    HOME_SLOT = False
    AUTO_MODE = "AUTO.MISSION"

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        if msg.command not in PX4_MISSION_COMMANDS:
            return _M.MAV_MISSION_UNSUPPORTED
        if msg.command not in PX4_LOCATION_COMMANDS:
            return StoredCommand(msg.command, (msg.param1, msg.param2, msg.param3, msg.param4), 0, 0, 0, _M.MAV_FRAME_MISSION)
        if msg.frame not in PX4_MISSION_FRAMES:
            return _M.MAV_MISSION_UNSUPPORTED_FRAME
        if abs(msg.x) > 90 * 10**7 or abs(msg.y) > 180 * 10**7 or not math.isfinite(msg.z):
            return _M.MAV_MISSION_INVALID
        frame = _M.MAV_FRAME_GLOBAL if msg.frame in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT) else _M.MAV_FRAME_GLOBAL_RELATIVE_ALT
        return StoredCommand(msg.command, (msg.param1, msg.param2, msg.param3, msg.param4), msg.x, msg.y, round(msg.z * 100), frame)

    def _request(self) -> None:
        self._last_request_at = self._owner.clock.now()
        self._emit(self._mav.mission_request_int_encode(*self._uploader, self._request_i, _M.MAV_MISSION_TYPE_MISSION))

    def _received(self) -> None:
        pass

    def _completed(self) -> None:
        pass


class Px4Sim(ArduPilotSim):
    """What every simulated PX4 does alike (see the module's docstring); a subclass per airframe moves its vehicle model.

    ``home_amsl_m`` is the start point's altitude above sea level (NAV_TAKEOFF's param7 counts from
    sea level). Like every simulated autopilot, :meth:`handle` and :meth:`update` return what to send.
    """

    FIRMWARE = "PX4"
    VERSION = "V1.16.0-dev"
    READY_TEXT = ""
    BOOT_MODE = INITIAL_MODE = "AUTO.LOITER"
    STREAMS = PX4_INTERVALS
    MISSION_STORE = Px4MissionStore
    AUTOPILOT_MODES = frozenset({"AUTO.LOITER", "AUTO.MISSION", "AUTO.RTL", "AUTO.LAND", "AUTO.TAKEOFF", "OFFBOARD"})
    MAV_TYPE: ClassVar[int]
    FLIES: ClassVar[bool]  # takes off and lands (mission take-off and landing items are passed over otherwise)
    UNAVAILABLE_MODES: ClassVar[frozenset[str]] = frozenset()  # modes this airframe has not

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
        self._goal_radius = NAV_LOITER_RAD
        self._landing = False
        self._takeoff_alt: float | None = None  # AUTO.TAKEOFF's height above home
        self._takeoff_point: tuple[float, float] | None = None  # NAV_TAKEOFF's finite param5/param6; None: here
        self._offboard_at = -math.inf  # when the last setpoint came (elapsed s)
        self._offboard_goal: tuple[float, float, float] | None = None
        self._failsafe_at: float | None = None  # when the offboard failsafe began
        self.mode_after_disarm = "AUTO.LOITER"  # UserModeIntention::_nav_state_after_disarming
        self._armed_at = 0.0
        self._taken_off = False
        self._landed = True
        self._landed_at: float | None = None
        self._moved_at = -math.inf  # the last time the land detector saw the vehicle move (or in the air)
        self._mission_item: tuple[int | None, object] | None = None
        self._event_sequence = 0
        # Commander::dataLinkCheck: HEARTBEAT type -> (last seen, lost), for a ground station and a mission computer
        self._links: dict[int, tuple[float, bool]] = {}
        modes = MappingProxyType(dict(PX4_MODE_NUMBERS))
        profile = dataclasses.replace(profile, mav_type=self.MAV_TYPE, modes=modes)
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
            return self.mission.present and checked
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
        if self._landed and self.mode != "AUTO.TAKEOFF":
            return  # the navigator does not take off to go somewhere
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
        v = self.vehicle
        self._update_links()
        self._update_land_detector()
        if not self.armed:
            return
        self._update_airframe()
        self._update_offboard_failsafe()
        if self.mode == "AUTO.TAKEOFF" and self._goal is not None and v.alt_m >= self._goal[2] - 0.5 and not self._landed:
            self._takeoff_alt, self._takeoff_point, there = None, None, self._goal
            self._user_intends("AUTO.LOITER")
            self._switch("AUTO.LOITER")  # the takeoff is done: loiter there (Commander::checkForMissionUpdate)
            self._fly_to(*there)
        elif self.mode == "AUTO.RTL" and not self._landing and self.home is not None:
            self._update_return(*self.home)
        elif self.mode == "AUTO.MISSION":
            self._update_mission()
        self._auto_disarm()

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
            if self.mission.state is MissionState.COMPLETE and not self._landed and self._goal is not None:
                self._user_intends("AUTO.LOITER")
                self._switch("AUTO.LOITER")  # Commander::checkForMissionUpdate: a finished mission loiters
            return
        key = (self.mission.current_seq, item)
        alt = item.alt_cm / 100.0 - (self.home_amsl_m if item.frame in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT) else 0.0)
        here = (item.lat_e7 == 0 and item.lon_e7 == 0) or not _valid_latlon(item.lat_e7 * 1e-7, item.lon_e7 * 1e-7)
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
            if not started:
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
                if msg.coordinate_frame not in frames or not _valid_latlon(msg.lat_int * 1e-7, msg.lon_int * 1e-7):
                    return
                goal = (msg.lat_int * 1e-7, msg.lon_int * 1e-7, msg.alt - frames[msg.coordinate_frame])
        self._offboard_at = self.elapsed_s
        if goal is not None:
            self._offboard_goal = goal
            if self.mode == "OFFBOARD" and goal != self._goal:
                self._fly_to(*goal)

    # -- commands (the commander, the navigator, vtol_att_control) --------------------------------

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
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

    def _cmd_arm_disarm(self, cmd: Command) -> int | None:  # type: ignore[override]
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
        if not (math.isfinite(lat) and math.isfinite(lon)) or not _valid_latlon(lat, lon):
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

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        builders = {
            **super()._message_builders(),
            _M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self._msg_extended_sys_state,
            _M.MAVLINK_MSG_ID_ESTIMATOR_STATUS: self._msg_estimator_status,
            _M.MAVLINK_MSG_ID_OPEN_DRONE_ID_LOCATION: self._msg_open_drone_id_location,
            CURRENT_EVENT_SEQUENCE[0]: self._msg_current_event_sequence,
            TIME_ESTIMATE_TO_TARGET[0]: self._msg_time_estimate_to_target,
        }
        for ardupilot_only in (_M.MAVLINK_MSG_ID_EKF_STATUS_REPORT, _M.MAVLINK_MSG_ID_RC_CHANNELS):
            del builders[ardupilot_only]
        return builders

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
            self._ms(), _e7(v.lat), _e7(v.lon), round(self.home_amsl_m * 1000) + rel, rel,
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
        return self._mav.home_position_encode(_e7(self.home[0]), _e7(self.home[1]), alt_mm, 0, 0, 0, (1.0, 0.0, 0.0, 0.0), 0, 0, 0, self._us())

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        if self._goal is None:
            return None
        lat, lon, alt = self._goal
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL_INT, 0xFF8, _e7(lat), _e7(lon), alt + self.home_amsl_m, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def _msg_open_drone_id_location(self) -> MAVLinkMessage | None:
        if not self.position_ok:
            return None
        v = self.vehicle
        amsl = self.home_amsl_m + v.alt_m
        return self._mav.open_drone_id_location_encode(
            0, 0, bytes(20), _M.MAV_ODID_STATUS_AIRBORNE if not self._landed else _M.MAV_ODID_STATUS_GROUND,
            round(v.heading_deg) % 360, round(v.speed_m_s * 100), 0, _e7(v.lat), _e7(v.lon), amsl, amsl, _M.MAV_ODID_HEIGHT_REF_OVER_TAKEOFF,
            v.alt_m, _M.MAV_ODID_HOR_ACC_1_METER, _M.MAV_ODID_VER_ACC_1_METER, _M.MAV_ODID_VER_ACC_1_METER, _M.MAV_ODID_SPEED_ACC_1_METERS_PER_SECOND,
            self.elapsed_s % 3600, _M.MAV_ODID_TIME_ACC_0_1_SECOND,
        )  # fmt: skip

    def _msg_current_event_sequence(self) -> MAVLinkMessage:
        return RawMessage(CURRENT_EVENT_SEQUENCE[0], CURRENT_EVENT_SEQUENCE[1], CURRENT_EVENT_SEQUENCE[2], (self._event_sequence, 0))

    def _msg_time_estimate_to_target(self) -> MAVLinkMessage:
        return RawMessage(TIME_ESTIMATE_TO_TARGET[0], TIME_ESTIMATE_TO_TARGET[1], TIME_ESTIMATE_TO_TARGET[2], (-1, -1, -1, -1, -1))


class Px4VtolSim(Px4Sim):
    """PX4 on a standard VTOL, flying the simulated QuadPlane airframe (the ArduPilot VTOL's, for like-for-like runs)."""

    MAV_TYPE = MAV_TYPE_VTOL_FIXEDROTOR
    FLIES = True

    vehicle: QuadPlaneModel

    def __init__(
        self, profile: VehicleProfile, clock: Clock, home: Home = DEFAULT_HOME, *, limits: AircraftLimits = QUADPLANE_LIMITS, **options: float
    ) -> None:
        self._limits = limits
        self._vtol = _M.MAV_VTOL_STATE_MC
        self._back_started = 0.0
        super().__init__(profile, clock, home, **options)

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return QuadPlaneModel(home[0], home[1], home[2], self._limits)

    @property
    def vtol_state(self) -> int:
        """EXTENDED_SYS_STATE vtol_state (MAV_VTOL_STATE)."""
        return self._vtol

    def _throttle(self) -> float:
        return 0.0 if not self.armed or self._landed else self.vehicle.throttle()

    def _servo_outputs(self) -> Sequence[int]:
        """MAIN1-4 the lift motors, MAIN5 the pusher."""
        outputs = [0] * 16
        flying = self.armed and not self._landed
        lifting = flying and self._vtol != _M.MAV_VTOL_STATE_FW
        outputs[0:4] = [1500 if lifting else 900] * 4
        outputs[4] = round(1000 + 1000 * self._throttle()) if flying and self.vehicle.regime is Regime.FIXED_WING else 1000
        return outputs

    def _detect_landed(self) -> bool:
        v = self.vehicle
        return v.on_ground and not (self.armed and v.velocity_ned[2] < -0.1)

    def _hold_here(self) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            self._fly_to(v.lat, v.lon, v.alt_m)
        else:
            self._fly_to(*v.stopping_point(), v.alt_m)

    def _steer(self) -> None:
        """Give the airframe the order that takes it to the goal in the present VTOL state."""
        v, goal = self.vehicle, self._goal
        if goal is None or self._landing:
            return
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            v.orbit(*goal, self._goal_radius)
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_FW:
            v.cruise(goal[2])
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_MC:
            v.hover_at(*v.stopping_point(), goal[2])
        else:
            v.hover_at(*goal)

    def _start_landing(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_FW, _M.MAV_VTOL_STATE_TRANSITION_TO_FW):
            self._back_transition()  # a VTOL lands on its lift motors
        self._landing = True
        self._goal = None
        if not self._landed:
            self.vehicle.land()

    def _reached(self, lat: float, lon: float, alt: float) -> bool:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            return v.distance_to(lat, lon) <= self._goal_radius * 1.1
        return v.distance_to(lat, lon) <= NAV_ACC_RAD and abs(v.alt_m - alt) <= 1.0

    def _update_return(self, lat: float, lon: float) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW and v.distance_to(lat, lon) <= self._goal_radius * 1.1:
            self._back_transition()  # over the point: back to the lift motors
        elif self._vtol == _M.MAV_VTOL_STATE_MC and v.distance_to(lat, lon) <= NAV_ACC_RAD and v.arrived:
            self._start_landing()

    # -- transitions (vtol_att_control) ----------------------------------------------------------

    def _transition_to(self, state: int) -> None:
        if state == _M.MAV_VTOL_STATE_FW:
            self._front_transition()
        else:
            self._back_transition()

    def _front_transition(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_MC, _M.MAV_VTOL_STATE_TRANSITION_TO_MC):
            self._vtol = _M.MAV_VTOL_STATE_TRANSITION_TO_FW
            self._text(_M.MAV_SEVERITY_INFO, "Transition to fixed-wing")
            self._steer()

    def _back_transition(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_FW, _M.MAV_VTOL_STATE_TRANSITION_TO_FW):
            self._vtol, self._back_started = _M.MAV_VTOL_STATE_TRANSITION_TO_MC, self.elapsed_s
            self._text(_M.MAV_SEVERITY_INFO, "Transition to multicopter")
            self._steer()

    def _update_airframe(self) -> None:
        if self._landed:
            self._vtol = _M.MAV_VTOL_STATE_MC
            return
        self._update_transition()

    def _update_transition(self) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_FW and v.speed_m_s >= TRANSITION_AIRSPEED_M_S:
            self._vtol = _M.MAV_VTOL_STATE_FW
            self._text(_M.MAV_SEVERITY_INFO, "Transition to fixed-wing complete")
            self._steer()
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_MC and (
            v.speed_m_s <= self._limits.mc_speed_m_s or self.elapsed_s - self._back_started >= VT_B_TRANS_DUR
        ):
            self._vtol = _M.MAV_VTOL_STATE_MC
            self._text(_M.MAV_SEVERITY_INFO, "Transition to multicopter complete")
            if self._landing:
                v.land()
            else:
                self._steer()

    # -- commands --------------------------------------------------------------------------------

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_VTOL_TRANSITION: self._cmd_vtol_transition,
            _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed,
        }

    def _cmd_vtol_transition(self, cmd: Command) -> int:
        """vtol_att_control: a transition in flight; refused on the ground and, to fixed wing, in Takeoff, Land and Return."""
        state = int(cmd.params[0] + 0.5)
        if state not in (_M.MAV_VTOL_STATE_MC, _M.MAV_VTOL_STATE_FW):
            return _M.MAV_RESULT_DENIED
        if self._landed or (state == _M.MAV_VTOL_STATE_FW and self.mode in ("AUTO.TAKEOFF", "AUTO.LAND", "AUTO.RTL")):
            return _M.MAV_RESULT_TEMPORARILY_REJECTED
        self._transition_to(state)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_change_speed(self, cmd: Command) -> int:
        """The navigator's cruise speed (param2, m/s; ground and air speed alike): here the multicopter speed."""
        if not cmd.params[1] > 0:
            return _M.MAV_RESULT_DENIED
        self._limits = dataclasses.replace(self._limits, mc_speed_m_s=cmd.params[1])
        self.vehicle.limits = self._limits
        return _M.MAV_RESULT_ACCEPTED


class Px4RoverSim(Px4Sim):
    """PX4 on a rover (a :class:`SurfaceVehicle`): AUTO.LOITER stops, the other modes drive to their point and stop there.

    What PX4's rover modules do (src/modules/rover_differential, rover_ackermann, rover_mecanum; PX4 main
    a70a558393): RoverDifferential::generateSetpoints drives in AUTO.MISSION, AUTO.LOITER and AUTO.RTL
    (the auto mode), OFFBOARD and the manual modes, nothing in other modes. Its land detector
    (src/modules/land_detector/RoverLandDetector.cpp) says landed when disarmed, in AUTO.LAND or DESCEND,
    and in AUTO.RTL within NAV_ACC_RAD (0.5 m, ROMFS rc.rover_*_defaults) of the return point: so arming
    is a "take-off" (no pre-flight auto-disarm), and AUTO.LAND, or arriving home in AUTO.RTL, is a landing
    that disarms it after COM_DISARM_LAND. It has no take-off mode and no transitions (UNSUPPORTED).
    """

    MAV_TYPE = _M.MAV_TYPE_GROUND_ROVER
    FLIES = False
    UNAVAILABLE_MODES = frozenset({"AUTO.TAKEOFF"})

    vehicle: SurfaceVehicle

    def __init__(self, profile: VehicleProfile, clock: Clock, home: Home = DEFAULT_HOME, *, limits: Limits = ROVER_LIMITS, **options: float) -> None:
        self._limits = limits
        self._speed: float | None = None
        super().__init__(profile, clock, home, **options)

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return SurfaceVehicle(home[0], home[1], home[2], self._limits)

    def _throttle(self) -> float:
        return min(1.0, abs(self.vehicle.speed_m_s) / self._limits.max_m_s) if self.armed else 0.0

    def _servo_outputs(self) -> Sequence[int]:
        """MAIN1 steering, MAIN2 throttle."""
        steer = max(-1.0, min(1.0, self.vehicle.yaw_rate_rad_s / math.radians(self._limits.turn_rate_deg_s)))
        outputs = [0] * 16
        outputs[0], outputs[1] = round(1500 + 500 * steer), round(1500 + 500 * self._throttle())
        return outputs

    def _detect_landed(self) -> bool:
        """RoverLandDetector::_get_landed_state."""
        if self.mode == "AUTO.RTL" and self.home is not None:
            return self.vehicle.distance_to(*self.home) < ROVER_NAV_ACC_RAD
        return self.mode == "AUTO.LAND" or not self.armed

    def _hold_here(self) -> None:
        v = self.vehicle
        self._goal = (*v.stopping_point(), 0.0)
        v.hold()

    def _steer(self) -> None:
        if self._goal is not None and not self._landing:
            self.vehicle.drive_to(*self._goal[:2], self._speed)

    def _start_landing(self) -> None:
        self._landing, self._goal = True, None
        self.vehicle.hold()

    def _reached(self, lat: float, lon: float, alt: float) -> bool:
        return self.vehicle.arrived

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
        return {**super()._command_handlers(), _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed}

    def _cmd_change_speed(self, cmd: Command) -> int:
        """The navigator's cruise speed (param2, m/s), capped at the rover's top speed."""
        if not cmd.params[1] > 0:
            return _M.MAV_RESULT_DENIED
        self._speed = min(cmd.params[1], self._limits.max_m_s)
        self._steer()
        return _M.MAV_RESULT_ACCEPTED


#: The simulated PX4 vehicle for each kind (``executive sim --autopilot px4``).
PX4_AUTOPILOTS: Mapping[str, type[ArduPilotSim]] = MappingProxyType({"vtol": Px4VtolSim, "rover": Px4RoverSim})
