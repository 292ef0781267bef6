"""The MAVLink reader: drains the link each tick and writes what the autopilot says on the blackboard.

It is the only consumer of incoming messages (``recv_match`` would drop the others). The autopilot
is the one named by ``target_system``/``target_component`` (``--target-system``), else the first
component whose HEARTBEAT names a real autopilot; vehicle facts from anyone else (another vehicle
on the same link, a ground station, another companion computer) are ignored. Every autopilot heard
is listed in :attr:`MavlinkReader.autopilots_heard`, so that a link carrying several vehicles is
noticed before one is commanded. Values that cannot be true (no fix,
coordinates off the globe, NaN) never reach the blackboard.
"""

from __future__ import annotations

import logging
import math
import operator
import struct
from collections import deque
from collections.abc import Callable

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.link import Link
from executive.io.mavlink.link_health import LinkHealth
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.modes import mode_table
from executive.io.mavlink.vehicle_clock import VehicleClockWatch
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import AUTOPILOT_COMPONENT, MAVLinkMessage, mavlink
from executive.world.state import (
    Attitude,
    Battery,
    BatteryStatus,
    EkfFlags,
    EkfStatus,
    FenceStatus,
    GlobalPosition,
    GpsFix,
    HomePosition,
    PositionTarget,
    Rangefinder,
)

log = logging.getLogger(__name__)

#: Commands from others kept until taken: more than a ground station sends between two ticks.
COMMANDS_KEPT = 64
_NOT_AUTOPILOTS = {mavlink.MAV_TYPE_GCS, mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_TYPE_ADSB}


#: HEARTBEAT system_status values of an autopilot that is (re)starting.
_STARTING = {mavlink.MAV_STATE_UNINIT, mavlink.MAV_STATE_BOOT, mavlink.MAV_STATE_CALIBRATING}

#: Message types that carry the sender's boot clock (``time_boot_ms``): a reboot shows in any of them.
_EKF_FAILSAFE_TEXTS = {"EKF failsafe": True, "EKF failsafe cleared": False}
_BOOT_TIME_KINDS = frozenset(cls.msgname for cls in mavlink.mavlink_map.values() if "time_boot_ms" in cls.fieldnames)
#: ESTIMATOR_STATUS is taken as stale (SYS_STATUS health bits stand in for it on PX4) after this long.
_ESTIMATOR_STATUS_STALE_S = 3.0
#: STATUSTEXT's text field: a chunk this long is not the last one.
_STATUSTEXT_CHUNK = 50
#: ESTIMATOR_STATUS_FLAGS that mean what EKF_STATUS_REPORT's flags of the same value mean (bits 0-9).
_SHARED_ESTIMATOR_FLAGS = 0x3FF


def _estimator_flags(flags: int) -> EkfFlags:
    """ESTIMATOR_STATUS flags as EkfFlags: bits 0-9 alike; ESTIMATOR_GPS_GLITCH (1024) is EKF_GPS_GLITCHING, not EKF_UNINITIALIZED."""
    ekf = EkfFlags(flags & _SHARED_ESTIMATOR_FLAGS)
    if flags & mavlink.ESTIMATOR_GPS_GLITCH:
        ekf |= EkfFlags.GPS_GLITCHING
    return ekf


def _ekf_from_health(present: int, health: int, now: float) -> EkfStatus:
    """An estimator status from SYS_STATUS alone: attitude while the AHRS bit is healthy, a position while the GPS bit is healthy too."""
    healthy = present & health
    flags = EkfFlags(0)
    if healthy & mavlink.MAV_SYS_STATUS_AHRS:
        flags |= EkfFlags.ATTITUDE | EkfFlags.VELOCITY_VERT | EkfFlags.POS_VERT_ABS
        if healthy & mavlink.MAV_SYS_STATUS_SENSOR_GPS:
            flags |= EkfFlags.VELOCITY_HORIZ | EkfFlags.POS_HORIZ_ABS | EkfFlags.POS_HORIZ_REL | EkfFlags.PRED_POS_HORIZ_ABS
    return EkfStatus(flags, 0.0, 0.0, 0.0, 0.0, 0.0, now)


def _finite(*values: float) -> bool:
    return all(map(math.isfinite, values))


#: Hostile-input bounds. An Euler roll or pitch is within +-pi, a yaw within +-pi or [0, 2pi); a little over is float32
#: rounding, far over is no attitude. No vehicle turns faster than 100 rad/s (16 turns a second).
_MAX_ANGLE_RAD = math.pi + 0.01
_MAX_RATE_RAD_S = 100.0
#: RC PWM a receiver can report, µs; outside it (UINT16_MAX = unused channel, or nonsense) a channel has no signal (0).
_PWM_MIN_US, _PWM_MAX_US = 500, 2500
#: Every whole PWM a receiver can report, and 0: a message's channels all in it need no look one by one (the wire's are ints).
_PWM_OR_NONE = frozenset(range(_PWM_MIN_US, _PWM_MAX_US + 1)) | {0}
_GPS_FIX_TYPES = frozenset(mavlink.enums["GPS_FIX_TYPE"])


def _on_the_globe(lat: float, lon: float) -> bool:
    """A real position: on the globe and not 0/0 (what autopilots send for 'no fix' or 'not set')."""
    return -90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and (lat, lon) != (0.0, 0.0)


_RC_CHANNELS = operator.attrgetter(*(f"chan{i}_raw" for i in range(1, 19)))  # RC_CHANNELS chan1_raw..chan18_raw, as a tuple
_SERVOS = operator.attrgetter(*(f"servo{i}_raw" for i in range(1, 17)))  # SERVO_OUTPUT_RAW servo1_raw..servo16_raw


class MavlinkReader:
    """Drains a :class:`Link`, dispatches each message by type, keeps ``/link``, ``/vehicle`` and ``/rc``."""

    def __init__(
        self,
        link: Link,
        clock: Clock,
        commander: Commander,
        *,
        link_timeout_s: float = 3.0,
        mission: MissionTransfer | None = None,
        rc_source: bool = True,
        target_system: int | None = None,
        target_component: int = AUTOPILOT_COMPONENT,
        on_autopilot: Callable[[int, int], None] | None = None,
        on_reconnect: Callable[[], None] | None = None,
    ) -> None:
        """``rc_source``: the autopilot's RC_CHANNELS are the RC receiver (False when the RC is read from CAN).

        ``target_system``: bind only to the autopilot of that system (and ``target_component``);
        None: the first autopilot heard. ``on_autopilot``, ``on_reconnect``: see the attributes.
        """
        self._link = link
        self._rc_source = rc_source
        self._clock = clock
        self._commander = commander
        self._mission = mission
        self.link_timeout_s = link_timeout_s
        self._bb = blackboard.writer("mavlink reader", blackboard.keys_under("/link/", "/vehicle/", "/rc/"))
        self._autopilot: tuple[int, int] | None = None
        self.target_system = target_system
        self.target_component = target_component
        #: system id -> MAV_TYPE of every autopilot whose HEARTBEAT was heard (the bound one included).
        self.autopilots_heard: dict[int, int] = {}
        if target_system is not None:  # everything is addressed to it from the first message, before its heartbeat
            self._set_targets((target_system, target_component))
        self._messages = 0
        self._bad_data = 0
        self._distance_sensor_seen = False  # a downward DISTANCE_SENSOR seen: the one source of the height above the bottom
        self._px4 = False  # the autopilot's HEARTBEAT says PX4: its estimator reports in ESTIMATOR_STATUS and SYS_STATUS
        self._estimator_status_at = float("-inf")
        self._chunks: dict[int, list[str]] = {}  # STATUSTEXT id -> the chunks so far
        self.health = LinkHealth()
        #: The autopilot's clock against ours: a simulator at another speed-up is warned about.
        self.clock_watch = VehicleClockWatch(clock)
        #: Called when the autopilot is first found, comes back after a link loss, or rebooted.
        self.on_reconnect = on_reconnect
        #: Called with the HEARTBEAT's (``autopilot``, ``type``) when the autopilot is first found: the port picks its back end.
        self.on_autopilot = on_autopilot
        #: The COMMAND_LONGs that did not come from the autopilot (a ground station's, routed by it), oldest first, until
        #: taken (:meth:`take_commands`); the oldest are dropped beyond :data:`COMMANDS_KEPT`.
        self._commands: deque[MAVLinkMessage] = deque(maxlen=COMMANDS_KEPT)
        self._handlers: dict[str, Callable[[MAVLinkMessage, float], None]] = {
            "HEARTBEAT": self._on_heartbeat,
            "GLOBAL_POSITION_INT": self._on_global_position,
            "ATTITUDE": self._on_attitude,
            "EKF_STATUS_REPORT": self._on_ekf_status,
            "ESTIMATOR_STATUS": self._on_estimator_status,
            "SYS_STATUS": self._on_sys_status,
            "BATTERY_STATUS": self._on_battery_status,
            "RC_CHANNELS": self._on_rc_channels,
            "COMMAND_ACK": self._on_command_ack,
            "STATUSTEXT": self._on_statustext,
            "HOME_POSITION": self._on_home_position,
            "POSITION_TARGET_GLOBAL_INT": self._on_position_target,
            "VFR_HUD": self._on_vfr_hud,
            "GPS_RAW_INT": self._on_gps_raw,
            "SERVO_OUTPUT_RAW": self._on_servo_output,
            "EXTENDED_SYS_STATE": self._on_extended_sys_state,
            "DISTANCE_SENSOR": self._on_distance_sensor,
            "RANGEFINDER": self._on_rangefinder,
            "PARAM_VALUE": self._on_param_value,
            "FENCE_STATUS": self._on_fence_status,
        }
        if mission is not None:  # the mission protocol's replies go to the transfer, as COMMAND_ACK goes to the commander
            self._handlers |= {
                "MISSION_REQUEST_INT": mission.on_request,
                "MISSION_REQUEST": mission.on_request,
                "MISSION_ACK": mission.on_ack,
                "MISSION_COUNT": mission.on_count,
                "MISSION_ITEM_INT": mission.on_item,
                "MISSION_CURRENT": mission.on_current,
                "MISSION_ITEM_REACHED": mission.on_reached,
            }

    @property
    def kinds_read(self) -> frozenset[str]:
        """The message kinds whose fields it reads; of any other it needs the header alone (and ``time_boot_ms``): a link may skim them."""
        return frozenset(self._handlers) | {"COMMAND_LONG"}  # a ground station's COMMAND_LONG is kept for take_commands

    @property
    def autopilot(self) -> tuple[int, int] | None:
        """(system id, component id) of the autopilot, once its HEARTBEAT was seen."""
        return self._autopilot

    @property
    def bad_data(self) -> int:
        """Undecodable byte runs received so far (bytes that are not MAVLink, or at the wrong baud rate)."""
        return self._bad_data

    def take_commands(self) -> list[MAVLinkMessage]:
        """The COMMAND_LONGs from others than the autopilot since the last call (a ground station's, routed by the autopilot), oldest first."""
        commands = list(self._commands)
        self._commands.clear()
        return commands

    def drain(self, max_messages: int = 10_000) -> int:
        """Handle every message waiting on the link (at most ``max_messages``); returns how many."""
        now = self._clock.now()
        count = 0
        recv, dispatch = self._link.recv, self.dispatch
        while count < max_messages:
            msg = recv()
            if msg is None:
                break
            count += 1
            dispatch(msg, now)
        if count and (boot_ms := self.health.last_boot_ms) is not None:
            self.clock_watch.sample(boot_ms / 1000.0, now)
        self._update_link_health(now)
        return count

    def dispatch(self, msg: MAVLinkMessage, now: float) -> None:
        """Handle one message received at clock time ``now``."""
        kind = msg.get_type()
        if kind == "BAD_DATA":
            if str(getattr(msg, "reason", "")).startswith("Invalid signature"):
                return  # counted by the link as unsigned_dropped
            self._bad_data += 1
            self._bb.set("/link/bad_data", self._bad_data)
            return
        if kind.startswith("UNKNOWN_"):  # outside our dialect (PX4's EVENT 410, CURRENT_EVENT_SEQUENCE 411...): only its sequence counts
            self._on_unknown(msg)
            return
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "HEARTBEAT" and source != self._autopilot:
            self._heard_heartbeat(msg, source)
        if self._autopilot != source:
            if kind == "COMMAND_LONG":
                self._commands.append(msg)  # a ground station (routed by the autopilot) commanding us: the operator side answers
            return
        self._messages += 1
        self.health.on_packet(msg.get_seq())
        if kind in _BOOT_TIME_KINDS and self.health.on_boot_time(msg.time_boot_ms):
            log.warning("autopilot rebooted")
            self._bb.set("/vehicle/ekf_failsafe", False)  # a booting autopilot has none latched
            self._reconnected()
        handler = self._handlers.get(kind)
        if handler is not None:
            handler(msg, now)

    # -- handlers ----------------------------------------------------------------------------
    def _heard_heartbeat(self, msg: MAVLinkMessage, source: tuple[int, int]) -> None:
        """A HEARTBEAT from someone other than our autopilot: note an autopilot, adopt it if it is the one we want."""
        if msg.autopilot == mavlink.MAV_AUTOPILOT_INVALID or msg.type in _NOT_AUTOPILOTS:
            return
        if source[0] not in self.autopilots_heard:
            self.autopilots_heard[source[0]] = msg.type
            if self._autopilot is not None:
                log.warning("another autopilot on the link: system %d component %d (MAV_TYPE %d): ignored", *source, msg.type)
        wanted = self._autopilot is None and (self.target_system is None or source == (self.target_system, self.target_component))
        if wanted:
            self._adopt_autopilot(msg, source)

    def _set_targets(self, autopilot: tuple[int, int]) -> None:
        self._commander.target_system, self._commander.target_component = autopilot
        if self._mission is not None:
            self._mission.target_system, self._mission.target_component = autopilot

    def _adopt_autopilot(self, msg: MAVLinkMessage, source: tuple[int, int]) -> None:
        self._autopilot = source
        self._set_targets(source)
        self._commander.modes = mode_table(msg.autopilot, msg.type)
        self._px4 = msg.autopilot == mavlink.MAV_AUTOPILOT_PX4
        if self.on_autopilot is not None:
            self.on_autopilot(msg.autopilot, msg.type)
        self._bb.set("/link/system_id", self._autopilot[0])
        self._bb.set("/link/component_id", self._autopilot[1])
        log.info("autopilot found: system %d component %d (MAV_TYPE %d)", *self._autopilot, msg.type)
        self._reconnected()

    def _reconnected(self) -> None:
        if self.on_reconnect is not None:
            self.on_reconnect()

    def _on_heartbeat(self, msg: MAVLinkMessage, now: float) -> None:
        previous = self._bb.get("/vehicle/system_status")
        if previous is not None and previous not in _STARTING and msg.system_status in _STARTING:
            self.health.reboots += 1
            log.warning("autopilot rebooted (heartbeat says it is starting up)")
            self._bb.set("/vehicle/ekf_failsafe", False)
            self._reconnected()
        self._bb.set("/link/last_heartbeat", now)
        self._bb.set("/vehicle/mav_type", msg.type)
        self._bb.set("/vehicle/armed", bool(msg.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED))
        self._bb.set("/vehicle/custom_mode", msg.custom_mode)
        self._bb.set("/vehicle/mode", self._commander.modes.decode(msg.custom_mode))
        self._bb.set("/vehicle/system_status", msg.system_status)

    def _on_global_position(self, msg: MAVLinkMessage, now: float) -> None:
        lat, lon = msg.lat / 1e7, msg.lon / 1e7
        if not _on_the_globe(lat, lon):
            return  # no fix yet, or nonsense
        heading = msg.hdg / 100.0 if msg.hdg < 36000 else None  # 0..35999 cdeg; UINT16_MAX = unknown, the rest nonsense
        speeds = msg.vx / 100.0, msg.vy / 100.0, msg.vz / 100.0
        position = GlobalPosition(lat, lon, msg.relative_alt / 1000.0, *speeds, heading, now, msg.time_boot_ms / 1000.0, msg.alt / 1000.0)
        self._bb.set("/vehicle/position", position)

    def _on_attitude(self, msg: MAVLinkMessage, now: float) -> None:
        if not _finite(msg.roll, msg.pitch, msg.yaw, msg.yawspeed):
            return
        if max(abs(msg.roll), abs(msg.pitch), abs(msg.yaw) / 2.0) > _MAX_ANGLE_RAD or abs(msg.yawspeed) > _MAX_RATE_RAD_S:
            return  # no attitude at all (a yaw may come in [0, 2pi))
        yaw = math.degrees(msg.yaw) % 360.0  # -1e-30 % 360 == 360.0
        self._bb.set(
            "/vehicle/attitude",
            Attitude(
                math.degrees(msg.roll),
                math.degrees(msg.pitch),
                0.0 if yaw == 360.0 else yaw,
                math.degrees(msg.yawspeed),
                now,
                msg.time_boot_ms / 1000.0,
            ),
        )

    def _on_ekf_status(self, msg: MAVLinkMessage, now: float) -> None:
        variances = (msg.velocity_variance, msg.pos_horiz_variance, msg.pos_vert_variance, msg.compass_variance, msg.terrain_alt_variance)
        if not _finite(*variances) or min(variances) < 0.0:
            return
        self._bb.set("/vehicle/ekf", EkfStatus(EkfFlags(msg.flags), *variances, now))

    def _on_estimator_status(self, msg: MAVLinkMessage, now: float) -> None:
        """PX4's estimator: ESTIMATOR_STATUS flags (ESTIMATOR_STATUS_FLAGS; src/modules/mavlink/streams/ESTIMATOR_STATUS.hpp sends
        estimator_status.solution_status_flags) and innovation test ratios (1.0 = at the gate) in place of the variances."""
        # hagl_ratio is estimator_status.hagl_test_ratio: NaN while no height above the ground is fused (seen on real PX4 SIH
        # standard_vtol from ~100 m up, out of its range sensor's reach): a test not made, not a broken report (issue 44)
        hagl = msg.hagl_ratio if _finite(msg.hagl_ratio) else 0.0
        ratios = (msg.vel_ratio, msg.pos_horiz_ratio, msg.pos_vert_ratio, msg.mag_ratio, hagl)
        if not _finite(*ratios) or min(ratios) < 0.0:
            return
        self._estimator_status_at = now
        self._bb.set("/vehicle/ekf", EkfStatus(_estimator_flags(msg.flags), *ratios, now, const_pos_at_rest=True))

    def _on_sys_status(self, msg: MAVLinkMessage, now: float) -> None:
        if self._px4 and now - self._estimator_status_at > _ESTIMATOR_STATUS_STALE_S:
            # PX4 without ESTIMATOR_STATUS (a link that does not stream it): its health bits say whether it has a position
            self._bb.set("/vehicle/ekf", _ekf_from_health(msg.onboard_control_sensors_present, msg.onboard_control_sensors_health, now))
        self._bb.set(
            "/vehicle/battery",
            Battery(
                None if msg.voltage_battery == 65535 else msg.voltage_battery / 1000.0,
                None if msg.current_battery == -1 else msg.current_battery / 100.0,
                msg.battery_remaining if 0 <= msg.battery_remaining <= 100 else None,  # -1 = unknown; the rest nonsense
                now,
            ),
        )

    def _on_battery_status(self, msg: MAVLinkMessage, now: float) -> None:
        if msg.id != 0:  # the main battery; ArduPilot numbers its monitors from 0, PX4 its battery 1 as 0 (BATTERY_STATUS.hpp: id - 1)
            return
        cells = [v for v in msg.voltages if v != 65535]  # UINT16_MAX: no such cell (common.xml)
        self._bb.set(
            "/vehicle/battery_status",
            BatteryStatus(
                None if msg.current_consumed < 0 else float(msg.current_consumed),
                None if msg.energy_consumed < 0 else msg.energy_consumed / 36.0,  # hJ -> Wh
                msg.battery_remaining if 0 <= msg.battery_remaining <= 100 else None,
                getattr(msg, "time_remaining", 0) or None,  # 0: not estimated (a MAVLink 2 extension)
                sum(cells) / 1000.0 if cells else None,
                None if msg.current_battery == -1 else msg.current_battery / 100.0,
                getattr(msg, "charge_state", 0),
                now,
            ),
        )

    def _on_rc_channels(self, msg: MAVLinkMessage, now: float) -> None:
        # every field, whatever chancount says: ArduPilot acts on an RC override of a channel past it (chancount 8, chan9_raw 1500)
        channels = _RC_CHANNELS(msg)
        if not _PWM_OR_NONE.issuperset(channels) and not all(_PWM_MIN_US <= c <= _PWM_MAX_US or c == 0 for c in channels):
            channels = tuple(c if _PWM_MIN_US <= c <= _PWM_MAX_US else 0 for c in channels)
        self._bb.set("/rc/channels", channels)
        self._bb.set("/rc/rssi", None if msg.rssi == 255 else msg.rssi)
        if self._bb.get("/rc/chancount") != msg.chancount:
            self._bb.set("/rc/chancount", msg.chancount)
        if self._rc_source:  # with RC on CAN, only a new 0x241 counter says the receiver is alive
            self._bb.set("/rc/last_update", now)
        self._bb.set("/rc/connected", any(channels))

    def _on_param_value(self, msg: MAVLinkMessage, now: float) -> None:
        name = msg.param_id.rstrip("\x00") if isinstance(msg.param_id, str) else msg.param_id.decode("ascii", "replace").rstrip("\x00")
        value = msg.param_value
        if self._px4 and msg.param_type == mavlink.MAV_PARAM_TYPE_INT32:
            # PX4 copies an INT32 parameter's bytes into the float (src/modules/mavlink/mavlink_parameters.cpp send_param:
            # memcpy); ArduPilot casts it to a float. BAT1_N_CELLS 4 arrives as 5.6e-45 read as a float.
            value = float(struct.unpack("<i", struct.pack("<f", value))[0])
        if name and _finite(value):
            self._bb.set("/vehicle/params", {**(self._bb.get("/vehicle/params") or {}), name: value})

    def _on_fence_status(self, msg: MAVLinkMessage, now: float) -> None:
        self._bb.set("/vehicle/fence_status", FenceStatus(bool(msg.breach_status), msg.breach_count, msg.breach_type, now))

    def _on_command_ack(self, msg: MAVLinkMessage, now: float) -> None:
        self._commander.on_ack(msg)

    def _on_statustext(self, msg: MAVLinkMessage, now: float) -> None:
        text = msg.text.rstrip("\x00") if isinstance(msg.text, str) else msg.text.decode("utf-8", "replace").rstrip("\x00")
        if getattr(msg, "id", 0):  # one chunk of a long text (MAVLink 2 id, chunk_seq): joined, said once whole
            joined = self._join_chunk(msg.id, msg.chunk_seq, text)
            if joined is None:
                return
            text = joined
        log.log(logging.WARNING if msg.severity <= mavlink.MAV_SEVERITY_WARNING else logging.INFO, "autopilot: %s", text)
        self._bb.set("/vehicle/statustext", (msg.severity, text))
        # Rover/ekf_check.cpp: failsafe_ekf_event says "EKF failsafe" once it has put a position mode in HOLD, and
        # failsafe_ekf_off_event "EKF failsafe cleared"; meanwhile Mode::enter refuses every position mode (mode.cpp)
        if text in _EKF_FAILSAFE_TEXTS:
            self._bb.set("/vehicle/ekf_failsafe", _EKF_FAILSAFE_TEXTS[text])

    def _join_chunk(self, text_id: int, seq: int, text: str) -> str | None:
        """The whole text once its last chunk (shorter than the 50-byte field) came; a lost chunk shows as "..."."""
        for other in [i for i in self._chunks if i != text_id]:  # a new text began: the unfinished one is said as it is
            log.info("autopilot: %s", "".join(self._chunks.pop(other)))
        chunks = self._chunks.setdefault(text_id, [])
        if seq > len(chunks):
            chunks.append("...")
        chunks.append(text)
        if len(text.encode("utf-8")) >= _STATUSTEXT_CHUNK:
            return None
        return "".join(self._chunks.pop(text_id))

    def _on_unknown(self, msg: MAVLinkMessage) -> None:
        """A message our dialect lacks: counted for the link's health when it comes from the autopilot (its header read from the frame)."""
        buf = msg.get_msgbuf()
        if len(buf) < 7:
            return
        seq, source = (buf[4], (buf[5], buf[6])) if buf[0] == mavlink.PROTOCOL_MARKER_V2 else (buf[2], (buf[3], buf[4]))
        if source == self._autopilot:
            self._messages += 1
            self.health.on_packet(seq)

    def _on_home_position(self, msg: MAVLinkMessage, now: float) -> None:
        lat, lon = msg.latitude / 1e7, msg.longitude / 1e7
        if _on_the_globe(lat, lon):  # 0/0: no home yet
            self._bb.set("/vehicle/home", HomePosition(lat, lon, msg.altitude / 1000.0, now))

    def _on_position_target(self, msg: MAVLinkMessage, now: float) -> None:
        """The point the autopilot steers to: ArduPilot's mode's desired location (Rover/GCS_MAVLink_Rover.cpp
        send_position_target_global_int), PX4's navigator's current setpoint (mavlink/streams/POSITION_TARGET_GLOBAL_INT.hpp)."""
        lat, lon = msg.lat_int / 1e7, msg.lon_int / 1e7
        if _on_the_globe(lat, lon) and _finite(msg.alt):
            self._bb.set("/vehicle/position_target", PositionTarget(lat, lon, msg.alt, now))

    def _on_vfr_hud(self, msg: MAVLinkMessage, now: float) -> None:
        if _finite(msg.groundspeed) and 0.0 <= msg.groundspeed < 1000.0:
            self._bb.set("/vehicle/ground_speed_m_s", msg.groundspeed)
        if 0 <= msg.heading <= 360:  # int16, degrees
            self._bb.set("/vehicle/heading_deg", float(msg.heading % 360))

    def _on_gps_raw(self, msg: MAVLinkMessage, now: float) -> None:
        if msg.fix_type not in _GPS_FIX_TYPES:
            return  # fix_type 200 is not a 3D fix
        satellites = None if msg.satellites_visible == 255 else msg.satellites_visible
        hdop = None if msg.eph == 65535 else msg.eph / 100.0
        self._bb.set("/vehicle/gps", GpsFix(msg.fix_type, satellites, hdop, now))

    def _on_servo_output(self, msg: MAVLinkMessage, now: float) -> None:
        if msg.port == 0:
            self._bb.set("/vehicle/servo_outputs", _SERVOS(msg))

    def _on_extended_sys_state(self, msg: MAVLinkMessage, now: float) -> None:
        vtol = mavlink.enums["MAV_VTOL_STATE"].get(msg.vtol_state)
        landed = mavlink.enums["MAV_LANDED_STATE"].get(msg.landed_state)
        self._bb.set("/vehicle/vtol_state", vtol.name.removeprefix("MAV_VTOL_STATE_") if vtol else None)
        self._bb.set("/vehicle/landed_state", landed.name.removeprefix("MAV_LANDED_STATE_") if landed else None)

    def _on_distance_sensor(self, msg: MAVLinkMessage, now: float) -> None:
        """The downward rangefinder: the one source of the height above the bottom (and of its validity).

        A reading counts only within the sensor's own range (min/max_distance: RNGFND1_MIN/MAX):
        ArduPilot sends the raw distance whatever the sensor's status (AP_RangeFinder_Backend.cpp
        update_status: beyond max is OutOfRangeHigh; GCS_Common.cpp send_distance_sensor).
        """
        if msg.orientation != mavlink.MAV_SENSOR_ROTATION_PITCH_270:
            return  # not looking down: an obstacle sensor
        self._distance_sensor_seen = True
        distance, low, high = msg.current_distance / 100.0, msg.min_distance / 100.0, msg.max_distance / 100.0
        if getattr(msg, "signal_quality", 0) == 1:  # 1 = invalid (0 = unknown)
            status = "invalid"
        elif distance > high:
            status = "too_far"
        elif distance < low:
            status = "too_close"
        else:
            status = "good"
        self._bb.set("/vehicle/rangefinder", Rangefinder(distance, low, high, status, now))
        self._bb.set("/vehicle/altitude_above_bottom_m", distance if status == "good" else None)
        self._bb.set("/vehicle/altitude_last_update", now)

    def _on_rangefinder(self, msg: MAVLinkMessage, now: float) -> None:
        """RANGEFINDER carries no range and no status (GCS_Common.cpp send_rangefinder sends distance() whatever the
        sensor's status): it is read only from an autopilot that never sent a downward DISTANCE_SENSOR, which then
        alone judges the reading, so the two never overwrite each other's verdict (issue 14: 915 holds in 400 s).
        """
        if self._distance_sensor_seen:
            return
        valid = _finite(msg.distance) and msg.distance >= 0.0
        self._bb.set("/vehicle/altitude_above_bottom_m", float(msg.distance) if valid else None)
        self._bb.set("/vehicle/altitude_last_update", now)

    def _update_link_health(self, now: float) -> None:
        last = self._bb.get("/link/last_heartbeat")
        up = last is not None and now - last <= self.link_timeout_s
        if up != self._bb.get("/link/up"):
            was_lost = last is not None and self._bb.get("/link/heartbeat_age_s") is not None
            self._bb.set("/link/up", up)
            self._bb.set("/link/up_since", last if up else None)  # a reading's age counts from here (guards: stale while heard)
            if up:
                log.info("link up")
                if was_lost:
                    self._reconnected()
            elif last is not None:
                log.warning("link lost: no heartbeat for %.1f s", now - last)
        self._bb.set("/link/heartbeat_age_s", None if last is None else now - last)
        self._set_if_changed("/link/messages", self._messages)
        self._set_if_changed("/link/packets_lost", self.health.lost)
        self._set_if_changed("/link/loss_pct", self.health.loss_pct)
        self._set_if_changed("/link/reboots", self.health.reboots)
        self._set_if_changed("/link/unsigned_dropped", getattr(self._link, "unsigned_dropped", 0))
        self._set_if_changed("/link/device_lost", getattr(self._link, "device_lost", None))

    def _set_if_changed(self, key: str, value: object) -> None:
        if self._bb.get(key) != value:
            self._bb.set(key, value)
