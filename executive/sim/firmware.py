"""What every simulated autopilot does alike, whatever its firmware: MAVLink messages in, MAVLink messages out, no sockets.

:class:`FirmwareSim` runs the clock-driven loop (the mode's logic, the vehicle model, the battery, the
telemetry streams at their intervals), routes COMMAND_LONG / COMMAND_INT to a handler per command and
answers with COMMAND_ACK, keeps the mission store, the proximity sensor and the relays, and answers
the requests every firmware answers alike (message intervals, REQUEST_MESSAGE, AUTOPILOT_VERSION,
PARAM_REQUEST_READ, DO_SET_HOME, DO_SET_RELAY, DO_SET_MISSION_CURRENT). A firmware's subclass adds
its own modes, arming, HEARTBEAT, SYS_STATUS and position messages: ArduPilot's in
:mod:`executive.sim.ardupilot`, PX4's in :mod:`executive.sim.px4`.

Everything runs in the injected clock's time (a ScaledClock shared with the executive gives the
speed-up; a ManualClock steps it in tests).
"""

from __future__ import annotations

import math
import struct
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import ClassVar

from executive.sim.battery import SPECS, SimBattery
from executive.sim.mission_store import MissionStore
from executive.sim.physics.vehicle import VehicleModel
from executive.sim.proximity import Proximity
from executive.world.clock import Clock
from executive.world.dialect import AUTOPILOT_COMPONENT, MAVLinkMessage, encoder, mavlink
from executive.world.vehicles import VehicleProfile

Home = tuple[float, float, float]  # latitude, longitude (degrees), heading (degrees)

#: Where ArduPilot's own simulator starts: Canberra Model Aircraft Club.
DEFAULT_HOME: Home = (-35.363261, 149.165230, 353.0)

RELAYS = 16  # ArduPilot 4.5: RELAY1..RELAY16 (AP_Relay)

_M = mavlink
_HEARTBEAT = _M.MAVLINK_MSG_ID_HEARTBEAT
EPSILON_S = 1e-6  # clock times closer than this are the same instant


def valid_latlon(lat: float, lon: float) -> bool:
    """A latitude and longitude (degrees) on the globe."""
    return abs(lat) <= 90.0 and abs(lon) <= 180.0


def e7(degrees: float) -> int:
    """Degrees as MAVLink's integer 1e-7 degrees."""
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


#: A command's handler: the MAV_RESULT to acknowledge it with (None: no COMMAND_ACK at all).
CommandHandler = Callable[[Command], "int | None"]


@dataclass(slots=True)
class _TelemetryStream:
    """A message sent unasked every ``interval`` seconds, built by ``build``; ``due``: when next (None: at once)."""

    msg_id: int
    interval: float
    build: Callable[[], MAVLinkMessage | None]
    due: float | None = None


class FirmwareSim(ABC):
    """The firmware-independent part of a simulated autopilot.

    Call :meth:`handle` with every received message and :meth:`update` often; both return the
    messages to send. Not thread-safe: the server serialises calls.
    """

    FIRMWARE: ClassVar[str]
    VERSION: ClassVar[str]
    BOOT_MODE: ClassVar[str]  # the mode reported while booting
    INITIAL_MODE: ClassVar[str]  # the mode once booted
    AUTOPILOT_MODES: ClassVar[frozenset[str]] = frozenset()  # the modes the autopilot steers in (NAV_CONTROLLER_OUTPUT)
    STREAMS: ClassVar[Mapping[int, float]]  # messages sent unasked, with their default interval (s)
    NAV_PERIOD_S: ClassVar[float] = 0.1  # how often mode logic runs, in clock time
    MISSION_STORE: ClassVar[type[MissionStore]]  # the firmware's side of the mission protocol
    ZONE_STORES: ClassVar[tuple[type[MissionStore], ...]] = ()  # its fence and rally points (executive.sim.zone_stores)
    PARAMS: ClassVar[Mapping[str, float]] = {}  # parameters answered to PARAM_REQUEST_READ, with the firmware's defaults
    INT_PARAMS: ClassVar[frozenset[str]] = frozenset()  # answered as integers (MAV_PARAM_TYPE_INT8), the rest REAL32
    #: battery_remaining counted from a full pack at boot (ArduPilot's analog monitor), else the charge the pack holds (PX4).
    BATTERY_COUNTED_FROM_FULL: ClassVar[bool] = True
    #: energy_consumed reported (ArduPilot: consumed_wh * 36); PX4 sends -1.
    BATTERY_REPORTS_ENERGY: ClassVar[bool] = True
    #: The parameter holding the pack's capacity in mAh (set in ``params``, it sizes the simulated pack too).
    BATTERY_CAPACITY_PARAM: ClassVar[str] = ""
    #: The pack the simulated vehicle carries when its profile's kind has none of its own (a plugin's kind riding it).
    BATTERY_OF: ClassVar[str] = "rover"

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
        spec = SPECS.get(profile.kind, SPECS[self.BATTERY_OF])
        if params and self.BATTERY_CAPACITY_PARAM in params:  # a pack of another size fitted (and the autopilot told so)
            spec = replace(spec, capacity_mah=float(params[self.BATTERY_CAPACITY_PARAM]))
        self.battery = SimBattery(spec)
        self.params = {**self.battery_params(spec.capacity_mah), **self.params}
        self.load_factor = 1.0  # a headwind or a current (fault injection) makes the same work draw more
        self._mav = encoder(system_id, component_id)
        self._t0 = self._t = clock.now()
        self._mode_names = {number: name for name, number in profile.modes.items()}
        self._intervals = dict(self.STREAMS)  # every message's interval (s; 0: not sent unasked), in the order they are sent
        self._streams: list[_TelemetryStream] = []  # those sent now, planned again when an interval changes and at the boot
        self._out: list[MAVLinkMessage] = []
        self._booted = self._origin_set = False
        self._text_id = 0
        self.mission = self.MISSION_STORE(self, self._emit, self._text)
        self.zone_stores = {store.MISSION_TYPE: store(self, self._emit, self._text) for store in self.ZONE_STORES}
        self.proximity = Proximity()  # a MAVLink proximity sensor (PRX1_TYPE 2): what OBSTACLE_DISTANCE tells
        self.relays: dict[int, bool] = {}  # relay instance -> on, as MAV_CMD_DO_SET_RELAY left it
        self._builders = self._message_builders()
        self._plan_streams()
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
        return self._t - self._t0 >= self.ekf_ready_after_s - EPSILON_S  # elapsed_s, written out: asked many times a step

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
        while now - self._t > EPSILON_S:
            h = now - self._t if now - self._t < self.NAV_PERIOD_S else self.NAV_PERIOD_S
            self._check_health()
            self._update_mode()
            self.vehicle.step(h)
            self._drain_battery(h)
            self._t = now if now - self._t - h < EPSILON_S else self._t + h
        self.mission.update()
        for store in self.zone_stores.values():
            store.update()
        self._events()
        self._telemetry()
        return self._flush()

    def _check_health(self) -> None:
        """The firmware's own health checks, run before the mode's logic every ``NAV_PERIOD_S`` (none by default)."""
        return

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

    @abstractmethod
    def _events(self) -> None:
        """What happens at its time: the end of the boot, the estimator's origin, periodic notices."""

    @abstractmethod
    def set_mode(self, number: int) -> bool:
        """Change mode as a GCS command would (``custom_mode``); True on success."""

    @abstractmethod
    def disarm(self) -> None:
        """Disarm, whoever asks (a GCS command, a pilot's switch in fault injection)."""

    @abstractmethod
    def sensor_status(self) -> tuple[int, int, int]:
        """SYS_STATUS present, enabled and health bits, from the firmware's state."""

    @abstractmethod
    def _msg_heartbeat(self) -> MAVLinkMessage:
        """HEARTBEAT, as the firmware fills it."""

    @abstractmethod
    def _msg_global_position_int(self) -> MAVLinkMessage | None:
        """GLOBAL_POSITION_INT (None: not sent now)."""

    @abstractmethod
    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        """POSITION_TARGET_GLOBAL_INT: where the mode is taking the vehicle (None: nowhere)."""

    @abstractmethod
    def _msg_home_position(self) -> MAVLinkMessage | None:
        """HOME_POSITION (None: no home yet)."""

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
            **dict.fromkeys(self.mission.MESSAGES, self._on_mission_message),
            "OBSTACLE_DISTANCE": lambda msg: self.proximity.handle(msg, self.elapsed_s),
            "PARAM_REQUEST_READ": self._on_param_request_read,
            "PARAM_SET": self._on_param_set,
        }

    def _on_mission_message(self, msg: MAVLinkMessage) -> None:
        """A MISSION_* message, to the store of its mission type (the flight plan's refuses one it has no store for)."""
        self.zone_stores.get(getattr(msg, "mission_type", _M.MAV_MISSION_TYPE_MISSION), self.mission).handle(msg)

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {
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
            _M.MAVLINK_MSG_ID_BATTERY_STATUS: self._msg_battery_status,
            _M.MAVLINK_MSG_ID_GPS_RAW_INT: self._msg_gps_raw_int,
            _M.MAVLINK_MSG_ID_ATTITUDE: self._msg_attitude,
            _M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: self._msg_global_position_int,
            _M.MAVLINK_MSG_ID_VFR_HUD: self._msg_vfr_hud,
            _M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: self._msg_servo_output_raw,
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
        return int((self._t - self._t0) * 1000) & 0xFFFFFFFF  # elapsed_s, written out: most messages carry it

    def _us(self) -> int:
        return int((self._t - self._t0) * 1e6)

    # -- time-driven behaviour -------------------------------------------------------------------

    def _telemetry(self) -> None:
        """Each stream's message when it is due (every update: the streams' times are kept with them, nothing else is looked up)."""
        if self._streams_booted is not self._booted:
            self._plan_streams()
        t, emit = self._t, self._emit
        soon = t + EPSILON_S
        for stream in self._streams:
            due = t if stream.due is None else stream.due
            if soon >= due:
                emit(stream.build())
                # at a high speed-up several intervals may pass between updates: send once, no burst
                interval = stream.interval
                stream.due = due + interval if due + interval > t else t + interval

    def _plan_streams(self, restart: int | None = None) -> None:
        """The streams sent now, in the order of :attr:`_intervals` (before the boot, the HEARTBEAT only), keeping when each is due;
        ``restart``'s (its interval just set) is due at once."""
        due = {stream.msg_id: stream.due for stream in self._streams if stream.msg_id != restart}
        self._streams_booted = booted = self._booted
        self._streams = [
            _TelemetryStream(msg_id, interval, self._builders[msg_id], due.get(msg_id))
            for msg_id, interval in self._intervals.items()
            if interval > 0 and (booted or msg_id == _HEARTBEAT)
        ]

    def battery_params(self, capacity_mah: float) -> dict[str, float]:
        """The battery monitor's parameters, as the firmware answers them for a pack of ``capacity_mah``."""
        return {}

    def _drain_battery(self, dt: float) -> None:
        self.battery.draw(self._current_a(), dt)

    def _current_a(self) -> float:
        return self.battery.load_a(self._throttle(), self.armed, self.load_factor)

    @property
    def consumed_mah(self) -> float:
        """The charge drawn since boot."""
        return self.battery.consumed_mah

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

    #: PARAM_SET's float carries an integer parameter's bytes (PX4, src/modules/mavlink/mavlink_parameters.cpp), else its value.
    PARAM_SET_BYTEWISE: ClassVar[bool] = False

    def _on_param_set(self, msg: MAVLinkMessage) -> None:
        """A parameter the firmware has takes the value, answered by its PARAM_VALUE (GCS_Param.cpp handle_param_set); others: nothing."""
        name = msg.param_id.rstrip("\x00") if isinstance(msg.param_id, str) else msg.param_id.decode("ascii", "replace").rstrip("\x00")
        if name not in self.params or not math.isfinite(msg.param_value):
            return
        value = msg.param_value
        if self.PARAM_SET_BYTEWISE and msg.param_type == _M.MAV_PARAM_TYPE_INT32:
            value = float(struct.unpack("<i", struct.pack("<f", value))[0])
        self.params[name] = float(int(value)) if name in self.INT_PARAMS else value
        names = sorted(self.params)
        kind = _M.MAV_PARAM_TYPE_INT8 if name in self.INT_PARAMS else _M.MAV_PARAM_TYPE_REAL32
        self._emit(self._mav.param_value_encode(name.encode(), self.params[name], kind, len(names), names.index(name)))

    def _ack_first(self, msg: MAVLinkMessage, command: int, run: Callable[[], int]) -> None:
        """Run a command; its COMMAND_ACK goes out before whatever the command itself sent."""
        mark = len(self._out)
        result = run()
        self._out.insert(mark, self._mav.command_ack_encode(command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()))

    # -- commands every firmware answers alike -----------------------------------------------------

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
        self._plan_streams(restart=msg_id)
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
        if not use_current and not valid_latlon(lat, lon):
            return _M.MAV_RESULT_DENIED
        if not self.position_ok:  # needs the current location, or at least the EKF origin
            return _M.MAV_RESULT_FAILED
        self.home = (self.vehicle.lat, self.vehicle.lon) if use_current else (lat, lon)
        self._emit(self._msg_home_position())
        return _M.MAV_RESULT_ACCEPTED

    # -- outgoing messages -----------------------------------------------------------------------

    @property
    def voltage_only(self) -> bool:
        """ArduPilot's BATT_MONITOR 3 (AP_BattMonitor_Analog, no current pin): the current, the charge drawn and the remaining
        charge reported unknown (-1, GCS_Common.cpp send_battery_status / battery_remaining_pct)."""
        return self.BATTERY_CAPACITY_PARAM == "BATT_CAPACITY" and self.params.get("BATT_MONITOR") == 3

    def _msg_sys_status(self) -> MAVLinkMessage:
        b = self.battery
        battery = (round(b.voltage_v * 1000), round(b.current_a * 100), b.remaining_pct(self.BATTERY_COUNTED_FROM_FULL))
        if self.voltage_only:
            battery = (battery[0], -1, -1)
        return self._mav.sys_status_encode(*self.sensor_status(), 150, *battery, 0, 0, 0, 0, 0, 0)

    def _msg_battery_status(self) -> MAVLinkMessage:
        """BATTERY_STATUS of battery 0 as the firmware fills it (executive.sim.battery says how each does)."""
        b = self.battery
        cells = [min(round(b.voltage_v * 1000), 65534)] + [65535] * 9  # no cell voltages: the pack's in cell 0
        energy_hj = round(b.consumed_wh * 36) if self.BATTERY_REPORTS_ENERGY else -1
        counted = (round(b.current_a * 100), round(b.consumed_mah), energy_hj, b.remaining_pct(self.BATTERY_COUNTED_FROM_FULL))
        return self._mav.battery_status_encode(
            0, _M.MAV_BATTERY_FUNCTION_UNKNOWN, _M.MAV_BATTERY_TYPE_UNKNOWN, 32767, cells,
            *((-1, -1, -1, -1) if self.voltage_only else counted), 0, _M.MAV_BATTERY_CHARGE_STATE_OK,
        )  # fmt: skip

    def _msg_gps_raw_int(self) -> MAVLinkMessage:
        v = self.vehicle
        vn, ve, _ = v.velocity_ned
        cog = round(math.degrees(math.atan2(ve, vn)) % 360 * 100) % 36000
        return self._mav.gps_raw_int_encode(
            self._us(), _M.GPS_FIX_TYPE_3D_FIX, e7(v.lat), e7(v.lon), round(v.alt_m * 1000), 121, 200, round(math.hypot(vn, ve) * 100), cog, 10
        )

    def _msg_attitude(self) -> MAVLinkMessage:
        yaw = (math.radians(self.vehicle.heading_deg) + math.pi) % (2 * math.pi) - math.pi
        return self._mav.attitude_encode(self._ms(), 0.0, 0.0, yaw, 0.0, 0.0, self.vehicle.yaw_rate_rad_s)

    def _msg_vfr_hud(self) -> MAVLinkMessage:
        vn, ve, vd = self.vehicle.velocity_ned
        speed = math.hypot(vn, ve)
        throttle = round(self._throttle() * 100)
        return self._mav.vfr_hud_encode(speed, speed, int(self.vehicle.heading_deg) % 360, throttle, self.vehicle.alt_m, -vd)

    def _msg_servo_output_raw(self) -> MAVLinkMessage:
        return self._mav.servo_output_raw_encode(self._us() & 0xFFFFFFFF, 0, *self._servo_outputs())

    def _msg_nav_controller_output(self) -> MAVLinkMessage | None:
        if self.mode not in self.AUTOPILOT_MODES:
            return None
        target = self._desired_location()
        distance, bearing = (self.vehicle.distance_to(*target), round(self.vehicle.bearing_to(*target))) if target else (0.0, 0)
        return self._mav.nav_controller_output_encode(0.0, 0.0, bearing, bearing, min(round(distance), 65535), 0.0, 0.0, 0.0)

    def _msg_gps_global_origin(self) -> MAVLinkMessage | None:
        if not self.ekf_ready:
            return None
        return self._mav.gps_global_origin_encode(e7(self.start[0]), e7(self.start[1]), 0, self._us())

    def _msg_autopilot_version(self) -> MAVLinkMessage:
        major, minor = (int(part) for part in self.VERSION.lstrip("V").split("-")[0].split(".")[:2])
        capabilities = (
            _M.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | _M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | _M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | _M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT | _M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
        )  # fmt: skip
        version = major << 24 | minor << 16 | _M.FIRMWARE_VERSION_TYPE_DEV
        return self._mav.autopilot_version_encode(capabilities, version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, 0)
