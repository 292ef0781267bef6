"""The commander: behaviours ask it for commands; it sends them after the tick.

Requests never block. A COMMAND_LONG / COMMAND_INT is queued, sent at :meth:`Commander.flush`,
matched to its COMMAND_ACK on ``command`` (MAVLink allows one command of a kind in flight), retried
with ``confirmation + 1`` when no ack comes, and its fate is written to ``/command/<outcome>`` (the
outcome the MAV_CMD carries, :data:`COMMAND_OUTCOMES`) as a :class:`~executive.world.state.CommandStatus`.
Setpoints (no ack exists) are just queued and sent.
"""

from __future__ import annotations

import itertools
import struct
from collections.abc import Sequence
from dataclasses import dataclass, replace

from py_trees.common import Access

from executive.io.mavlink.link import Link
from executive.io.mavlink.modes import ArduPilotModes, ModeTable
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, encoder, mavlink
from executive.world.state import CommandState, CommandStatus, Outcome, TargetAsk
from executive.world.vehicles import VehicleProfile

#: SET_POSITION_TARGET_GLOBAL_INT type_mask: use position only (ignore velocity, acceleration, yaw).
POSITION_ONLY_MASK = 0x0DF8
#: ... use position and velocity (ignore acceleration, yaw): ArduSub keeps a height above the seabed only with a velocity.
POSITION_VELOCITY_MASK = 0x0DC0
#: param2 values that skip ArduPilot's checks: 2989 forces an arm, 21196 a disarm (MAVLink's 21196 for both is PX4's).
FORCE_ARM_MAGIC = 2989.0
FORCE_DISARM_MAGIC = 21196.0
NAN = float("nan")


@dataclass(frozen=True, slots=True)
class RefusalRetry:
    """Ask again, every ``every_s``, a request refused TEMPORARILY_REJECTED, until ``for_s`` after it was first due; then the refusal stands.

    Meanwhile its ``/command/<outcome>`` shows RETRYING with the refusal's result: one ticket, one final answer.
    """

    every_s: float
    for_s: float


@dataclass
class _InFlight:
    status: CommandStatus
    params: tuple[float, ...]
    frame: int | None  # set for COMMAND_INT
    due: float | None  # when to (re)send; None = waiting for an ack until ``deadline``
    deadline: float
    provisional_seen: bool = False  # a double-acked command's first ACCEPTED came: the next ack decides
    retry: RefusalRetry | None = None
    retry_until: float = 0.0  # no new ask after this (vehicle time)
    refusals: int = 0  # sends answered by a refusal and asked again (not lost sends: they do not count toward the retries)


def result_name(result: int | None) -> str:
    """``1`` -> ``TEMPORARILY_REJECTED``; None -> ``no ack``."""
    entry = mavlink.enums["MAV_RESULT"].get(result) if result is not None else None
    return entry.name.removeprefix("MAV_RESULT_") if entry else "no ack"


#: The outcome each MAV_CMD the executive sends carries: its ack goes to ``/command/<outcome>``.
COMMAND_OUTCOMES: dict[int, Outcome] = {
    mavlink.MAV_CMD_DO_SET_MODE: Outcome.MODE,
    mavlink.MAV_CMD_COMPONENT_ARM_DISARM: Outcome.ARMING,
    mavlink.MAV_CMD_SET_MESSAGE_INTERVAL: Outcome.MESSAGE_RATE,
    mavlink.MAV_CMD_DO_SET_HOME: Outcome.HOME,
    mavlink.MAV_CMD_DO_CHANGE_SPEED: Outcome.SPEED,
    mavlink.MAV_CMD_DO_REPOSITION: Outcome.REPOSITION,
    mavlink.MAV_CMD_DO_VTOL_TRANSITION: Outcome.TRANSITION,
    mavlink.MAV_CMD_NAV_TAKEOFF: Outcome.TAKE_OFF,
    mavlink.MAV_CMD_NAV_LAND: Outcome.LAND,
    mavlink.MAV_CMD_NAV_VTOL_TAKEOFF: Outcome.VTOL_TAKE_OFF,
    mavlink.MAV_CMD_NAV_VTOL_LAND: Outcome.VTOL_LAND,
    mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH: Outcome.RETURN_HOME,
    mavlink.MAV_CMD_MISSION_START: Outcome.START_ROUTE,
    mavlink.MAV_CMD_DO_SET_MISSION_CURRENT: Outcome.ROUTE_ITEM,
    mavlink.MAV_CMD_REQUEST_MESSAGE: Outcome.MESSAGE,
}


def command_outcome(command: int) -> str:
    """The outcome a MAV_CMD carries (``176`` -> ``mode``); a raw command no outcome covers is its own: ``DO_SET_RELAY``."""
    outcome = COMMAND_OUTCOMES.get(command)
    return outcome if outcome is not None else command_name(command)


def command_name(command: int) -> str:
    """``176`` -> ``DO_SET_MODE``."""
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name.removeprefix("MAV_CMD_") if entry else f"CMD_{command}"


class Commander:
    """Queues commands for the autopilot and tracks their acks on the blackboard."""

    def __init__(
        self,
        link: Link,
        clock: Clock,
        profile: VehicleProfile,
        *,
        system_id: int = 1,
        component_id: int = EXECUTIVE_COMPONENT,
        ack_timeout_s: float = 1.5,
        retries: int = 3,
    ) -> None:
        self._link = link
        self._clock = clock
        self.profile = profile
        self._encoder = encoder(system_id, component_id)
        self._ack_timeout_s = ack_timeout_s
        self._retries = retries
        self._tickets = itertools.count(1)
        self._in_flight: dict[int, _InFlight] = {}
        self._outbox: list[MAVLinkMessage] = []
        self._bb = blackboard.writer("commander", [blackboard.command_key(o) for o in Outcome])
        self.target_system = 1
        self.target_component = 1
        #: The autopilot's mode table; the reader replaces it once the HEARTBEAT tells the firmware.
        self.modes: ModeTable = ArduPilotModes(profile.modes)
        #: Each mode asked for (its name as the heartbeat shows it) and when it was last asked: a mode change is ours or someone else's.
        self.modes_asked: dict[str, float] = {}
        #: The mode asked for last, if any.
        self.last_mode_asked: str | None = None
        #: The point we asked the autopilot to steer to last (a setpoint or a DO_REPOSITION): its report of another is someone else's.
        self.target_asked: TargetAsk | None = None
        #: The altitude above mean sea level the latest take-off of ours climbs to, as sent (None: none asked, or the autopilot's
        #: default height).
        self.takeoff_alt_msl_m: float | None = None
        #: Commands the autopilot acks twice, the first ACCEPTED saying only "received": PX4's MAVLink receiver
        #: acks DO_SET_MODE at once, its commander the real result after (issue 12). The first ACCEPTED is not final.
        self.double_acked: frozenset[int] = frozenset()

    @property
    def clock(self) -> Clock:
        return self._clock

    # -- requests (from behaviours; never block) ---------------------------------------------
    def command_long(self, command: int, params: Sequence[float] = (), *, delay_s: float = 0.0, retry: RefusalRetry | None = None) -> int:
        """Queue a COMMAND_LONG (sent ``delay_s`` from now; asked again per ``retry`` if refused for now); its ticket in ``/command/<outcome>``."""
        return self._request(command, params, frame=None, delay_s=delay_s, retry=retry)

    def command_int(self, command: int, frame: int, params: Sequence[float] = ()) -> int:
        """Queue a COMMAND_INT; ``params`` are param1-4, x, y (degrees: scaled here), z."""
        return self._request(command, params, frame=frame)

    def set_mode(self, mode: str | int | None = None, *, number: int | None = None, delay_s: float = 0.0, retry: RefusalRetry | None = None) -> int:
        """Ask for a flight mode by name or number (sent ``delay_s`` from now); given both, the name wins. KeyError if unknown."""
        chosen = mode if mode is not None else number
        if chosen is None:
            raise KeyError("no mode given")
        main, sub = self.modes.encode(chosen)
        self.note_mode_asked(self.modes.canonical(chosen) if isinstance(chosen, str) else self.modes.decode(int(main)))
        return self.command_long(mavlink.MAV_CMD_DO_SET_MODE, (mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main, sub), delay_s=delay_s, retry=retry)

    def note_mode_asked(self, name: str) -> None:
        """A mode our request puts the vehicle in (asked by name, or the effect of a command): not a person's change.

        Another mode than our point's ends the point: that mode steers by itself (PX4's RTL sets its own setpoint before its
        heartbeat shows AUTO.RTL), nothing is judged by the point any more."""
        self.modes_asked[name] = self._clock.now()
        self.last_mode_asked = name
        if self.target_asked is not None and self.target_asked.mode != name:
            self.target_asked = None

    def note_target_asked(self, lat: float | None, lon: float | None, mode: str | None = None) -> None:
        """A point our request (a setpoint, a DO_REPOSITION) has the autopilot steer to in ``mode`` (default: the mode asked last):
        not a person's target."""
        mode = mode or self.last_mode_asked
        asked = self.target_asked
        if asked is None or (asked.lat, asked.lon, asked.mode) != (lat, lon, mode):
            self.target_asked = TargetAsk(lat, lon, mode, self._clock.now())

    def arm(self, *, force: bool = False, force_magic: float = FORCE_ARM_MAGIC) -> int:
        """Arm; forced with ``force_magic`` in param2 (ArduPilot's 2989; PX4 takes MAVLink's 21196)."""
        return self.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0, force_magic if force else 0.0))

    def disarm(self, *, force: bool = False) -> int:
        return self.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0.0, FORCE_DISARM_MAGIC if force else 0.0))

    def set_home(self, lat: float | None = None, lon: float | None = None, alt_m: float = 0.0) -> int:
        """Home at the vehicle's current position (no arguments) or at a point (altitude above sea level).

        Roll and pitch 0 ("not set"), yaw NaN ("default heading", MAVLink common.xml): PX4 stores param4 as home's yaw
        (Commander.cpp VEHICLE_CMD_DO_SET_HOME), so a 0 there would point home north; ArduPilot reads param1, x, y, z only
        (GCS_Common.cpp handle_command_do_set_home).
        """
        if lat is None or lon is None:
            return self.command_long(mavlink.MAV_CMD_DO_SET_HOME, (1.0, 0.0, 0.0, NAN, NAN, NAN, NAN))
        return self.command_int(mavlink.MAV_CMD_DO_SET_HOME, mavlink.MAV_FRAME_GLOBAL, (0, 0, 0, NAN, lat, lon, alt_m))

    def change_speed(self, speed_m_s: float, *, airspeed: bool = False) -> int:
        """Cruise speed for GUIDED/AUTO legs (ground speed unless ``airspeed``)."""
        return self.command_long(mavlink.MAV_CMD_DO_CHANGE_SPEED, (0.0 if airspeed else 1.0, speed_m_s, -1.0))

    def reposition(self, lat: float, lon: float, alt_m: float = 0.0) -> int:
        """Go to a point (switching to GUIDED where the firmware does); acked, unlike a setpoint."""
        flags = float(mavlink.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)
        self.note_mode_asked(self.profile.guided_mode)  # the firmware switches to GUIDED itself: a mode we asked for
        self.note_target_asked(lat, lon)
        return self.command_int(
            mavlink.MAV_CMD_DO_REPOSITION, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, (-1, flags, 0, float("nan"), lat, lon, alt_m)
        )

    def vtol_transition(self, to: str) -> int:
        """Transition a VTOL to multicopter (``"MC"``) or fixed-wing (``"FW"``) flight."""
        state = {"MC": mavlink.MAV_VTOL_STATE_MC, "FW": mavlink.MAV_VTOL_STATE_FW}[to.upper()]
        return self.command_long(mavlink.MAV_CMD_DO_VTOL_TRANSITION, (state,))

    def takeoff(self, alt_m: float, *, vtol: bool = False) -> int:
        """Climb to ``alt_m`` (above home on ArduPilot, above sea level on PX4) where the vehicle is (a VTOL climbs as a multicopter).

        Yaw, latitude and longitude go as NaN, "unchanged, here": PX4 takes finite param5/param6 as the take-off point
        (navigator_main.cpp VEHICLE_CMD_NAV_TAKEOFF; 0, 0 is in the Gulf of Guinea and the vehicle never climbed);
        ArduPlane reads param7 alone (GCS_MAVLink_Plane.cpp convert_MAV_CMD_NAV_TAKEOFF_to_COMMAND_INT).
        """
        command = mavlink.MAV_CMD_NAV_VTOL_TAKEOFF if vtol else mavlink.MAV_CMD_NAV_TAKEOFF
        return self.command_long(command, (0, 0, 0, NAN, NAN, NAN, alt_m))

    def land(self) -> int:
        """MAV_CMD_NAV_LAND where the vehicle is: abort altitude 0 (the default), no precision landing, yaw, point and ground
        altitude NaN ("unchanged, here"; ArduPilot turns a NaN latitude/longitude of a COMMAND_LONG into 0, GCS_Common.cpp
        convert_COMMAND_LONG_loc_param). PX4 lands where it is whatever they say (Commander.cpp VEHICLE_CMD_NAV_LAND),
        ArduSub surfaces (GCS_MAVLink_Sub.cpp handle_MAV_CMD_NAV_LAND)."""
        return self.command_long(mavlink.MAV_CMD_NAV_LAND, (0, 0, 0, NAN, NAN, NAN, NAN))

    def goto(self, lat: float, lon: float, alt_m: float = 0.0, *, mode: str | None = None) -> None:
        """Queue a GUIDED position target (ArduPilot ignores it, silently, outside GUIDED); ``mode``: the one that follows it."""
        self.note_target_asked(lat, lon, mode)
        self._outbox.append(
            self._encoder.set_position_target_global_int_encode(
                0,
                self.target_system,
                self.target_component,
                mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                POSITION_ONLY_MASK,
                round(lat * 1e7),
                round(lon * 1e7),
                alt_m,
                0, 0, 0, 0, 0, 0, 0, 0,
            )
        )  # fmt: skip

    def depth_target(self, lat: float, lon: float, *, depth_m: float | None = None, altitude_m: float | None = None) -> None:
        """Queue an ArduSub depth target (``depth_m`` below the surface) or height above the seabed (``altitude_m``).

        A depth goes as ``alt = -depth`` in the relative-altitude frame: GUIDED goes to (lat, lon) at
        that depth, ALT_HOLD takes the depth alone. A height above the seabed goes in the terrain
        frame with a (zero) velocity, which only GUIDED understands. Never acknowledged.
        """
        if depth_m is not None and altitude_m is None:
            frame, mask, alt = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, POSITION_ONLY_MASK, -depth_m
        elif altitude_m is not None and depth_m is None:
            frame, mask, alt = mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT, POSITION_VELOCITY_MASK, altitude_m
        else:
            raise ValueError("give exactly one of depth_m and altitude_m")
        self.note_target_asked(lat, lon)
        self._outbox.append(
            self._encoder.set_position_target_global_int_encode(
                0, self.target_system, self.target_component, frame, mask, round(lat * 1e7), round(lon * 1e7), alt,
                0, 0, 0, 0, 0, 0, 0, 0,
            )
        )  # fmt: skip

    def local_setpoint(self, north_m: float, east_m: float, down_m: float) -> None:
        """Queue a position target in the local NED frame (MAV_FRAME_LOCAL_NED: from the EKF origin, z down). Never acknowledged."""
        self.note_target_asked(None, None)  # not comparable with a global report: ours is never confirmed, nothing judged
        self._outbox.append(
            self._encoder.set_position_target_local_ned_encode(
                0, self.target_system, self.target_component, mavlink.MAV_FRAME_LOCAL_NED, POSITION_ONLY_MASK,
                north_m, east_m, down_m, 0, 0, 0, 0, 0, 0, 0, 0,
            )
        )  # fmt: skip

    def request_parameter(self, name: str) -> None:
        """Queue a PARAM_REQUEST_READ by name; the PARAM_VALUE answer goes to ``/vehicle/params`` (no ack: ask again if none comes)."""
        self._outbox.append(self._encoder.param_request_read_encode(self.target_system, self.target_component, name.encode(), -1))

    def set_parameter(self, name: str, value: float, param_type: int, *, bytewise: bool = False) -> None:
        """Queue a PARAM_SET; the autopilot answers with the PARAM_VALUE it now holds (``/vehicle/params``; no ack: set again if none comes).

        ``bytewise``: an integer parameter's bytes go in the float (PX4, src/modules/mavlink/mavlink_parameters.cpp
        handle_message PARAM_SET: memcpy), else its value as a float (ArduPilot casts it).
        """
        sent = float(value)
        if bytewise and param_type == mavlink.MAV_PARAM_TYPE_INT32:
            sent = struct.unpack("<f", struct.pack("<i", round(value)))[0]
        self._outbox.append(self._encoder.param_set_encode(self.target_system, self.target_component, name.encode(), sent, param_type))

    def cancel(self, ticket: int | None) -> bool:
        """Forget a request that no longer matters (its behaviour was interrupted); returns whether one was pending.

        A mode change asked for while a guard failed must not be retried after the guard
        recovered: it would undo what the tree asked for since.
        """
        for command, entry in list(self._in_flight.items()):
            if entry.status.ticket == ticket:
                del self._in_flight[command]
                self._publish(entry, CommandState.CANCELLED, None, self._clock.now())
                return True
        return False

    # -- IO side (called by the runtime and the reader) --------------------------------------
    def on_ack(self, msg: MAVLinkMessage) -> None:
        """A COMMAND_ACK arrived (the reader calls this)."""
        entry = self._in_flight.get(msg.command)
        if entry is None:
            return
        now = self._clock.now()
        if entry.due is not None:
            return  # not sent yet (a delayed request): an ack of an earlier one of its kind says nothing of it
        first_of_two = msg.command in self.double_acked and not entry.provisional_seen and msg.result == mavlink.MAV_RESULT_ACCEPTED
        if msg.result == mavlink.MAV_RESULT_IN_PROGRESS or first_of_two:
            entry.provisional_seen = entry.provisional_seen or first_of_two
            entry.deadline = now + self._ack_timeout_s * 4
            entry.due = None
            self._publish(entry, CommandState.IN_PROGRESS, msg.result, now)
            return
        retry = entry.retry
        if msg.result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED and retry is not None and now + retry.every_s <= entry.retry_until:
            entry.due, entry.refusals = now + retry.every_s, entry.refusals + 1
            self._publish(entry, CommandState.RETRYING, msg.result, now)
            return
        state = CommandState.ACCEPTED if msg.result == mavlink.MAV_RESULT_ACCEPTED else CommandState.REJECTED
        self._publish(entry, state, msg.result, now)
        del self._in_flight[msg.command]

    def flush(self) -> int:
        """Send what is queued and due (first sends and retries); time out the hopeless. Returns messages sent."""
        now = self._clock.now()
        sent = 0
        for msg in self._outbox:
            self._link.send(msg)
            sent += 1
        self._outbox.clear()
        for command, entry in list(self._in_flight.items()):
            if entry.due is None and entry.deadline <= now:
                if entry.status.attempts - entry.refusals > self._retries:
                    self._publish(entry, CommandState.TIMED_OUT, None, now)
                    del self._in_flight[command]
                    continue
                entry.due = now
            if entry.due is not None and entry.due <= now:
                entry.provisional_seen = False  # a new send: its acks start again
                self._link.send(self._encode(command, entry))
                sent += 1
                entry.due = None
                entry.deadline = now + self._ack_timeout_s
                self._publish(entry, CommandState.SENT, None, now, attempts=entry.status.attempts + 1)
        return sent

    @property
    def idle(self) -> bool:
        """Nothing queued and no command waiting for an ack."""
        return not self._outbox and not self._in_flight

    # -- internals ---------------------------------------------------------------------------
    def _request(self, command: int, params: Sequence[float], frame: int | None, delay_s: float = 0.0, retry: RefusalRetry | None = None) -> int:
        if len(params) > 7:
            raise ValueError(f"a command has at most 7 parameters, got {len(params)}")
        now = self._clock.now()
        ticket = next(self._tickets)
        status = CommandStatus(ticket, command, command_name(command), CommandState.QUEUED, None, 0, now)
        padded = (*(float(p) for p in params), *([0.0] * (7 - len(params))))
        # A newer request of the same kind supersedes the one in flight: its ack could not be told apart.
        entry = _InFlight(status, padded, frame, due=now + delay_s, deadline=now + delay_s + self._ack_timeout_s, retry=retry)
        if retry is not None:
            entry.retry_until = now + delay_s + retry.for_s
        self._in_flight[command] = entry
        self._publish(entry, CommandState.QUEUED, None, now)
        return ticket

    def _encode(self, command: int, entry: _InFlight) -> MAVLinkMessage:
        p = entry.params
        if entry.frame is None:
            confirmation = entry.status.attempts - entry.refusals  # 0 on the first send (and on a new ask after a refusal), +1 on each retry
            return self._encoder.command_long_encode(self.target_system, self.target_component, command, confirmation, *p)
        return self._encoder.command_int_encode(
            self.target_system, self.target_component, entry.frame, command, 0, 0,
            p[0], p[1], p[2], p[3], round(p[4] * 1e7), round(p[5] * 1e7), p[6],
        )  # fmt: skip

    def _publish(self, entry: _InFlight, state: CommandState, result: int | None, now: float, attempts: int | None = None) -> None:
        if attempts is None:
            attempts = entry.status.attempts
        entry.status = replace(entry.status, state=state, result=result, time=now, attempts=attempts, result_name=result_name(result))
        key = blackboard.command_key(command_outcome(entry.status.command))
        if key not in self._bb.write:
            self._bb.register_key(key=blackboard.document_command(entry.status.name), access=Access.WRITE)
        self._bb.set(key, entry.status)
