"""The PX4 back end of the autopilot port, as PX4 (main, 2025) behaves over MAVLink (issue 12).

- Modes live in ``custom_mode`` (main mode bits 16-23, sub mode 24-31); trees name them the
  ArduPilot way and get the equivalent (GUIDED is OFFBOARD, QLOITER AUTO.LOITER, QRTL AUTO.RTL).
  DO_SET_MODE is acked twice, ACCEPTED by the MAVLink receiver at once and the real result by the
  commander after (src/modules/commander/Commander.cpp handle_command answers it on its loop): the
  commander here takes the first ACCEPTED as "received" only; a mode is confirmed by the heartbeat.
- OFFBOARD is entered only while setpoints stream (the offboard signal counts as lost when the
  last setpoint is older than COM_OF_LOSS_T, 1 s by default:
  src/modules/commander/HealthAndArmingChecks/checks/offboardCheck.cpp). The stream starts before
  the mode is asked (the request goes out :data:`STREAM_LEAD_S` later), runs at
  :data:`STREAM_PERIOD_S` while OFFBOARD is asked for or shown, and stops only once the heartbeat
  shows another mode: leaving OFFBOARD is asking for another mode (AUTO.LOITER, the safe mode),
  never stopping the stream, which is PX4's offboard failsafe.
- NAV_TAKEOFF param7 is an altitude above sea level (home's plus the height; NaN: PX4's default).
- AUTO.MISSION is refused while PX4 checks a mission it was just given: it is asked
  :data:`MISSION_CHECK_S` after the upload's MISSION_ACK at the earliest, and, refused
  TEMPORARILY_REJECTED ("Switching to Mission is currently not available": the commander's answer
  when the mode's checks fail, src/modules/commander/Commander.cpp handle_command DO_SET_MODE),
  asked again per :data:`ROUTE_START_RETRY` before the refusal stands.
- VTOL transitions go as MAV_CMD_DO_VTOL_TRANSITION, which PX4 takes in flight in any mode.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from executive.autopilot.mavlink_port import MavlinkPort
from executive.autopilot.mode_cause import PX4_TAKEOFF_ALT_RAD_PARAM
from executive.autopilot.port import Capabilities, FenceSettings, Request, Target
from executive.io.mavlink.commander import FORCE_DISARM_MAGIC, Commander, RefusalRetry
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, HomePosition, MissionTransferStatus, TransferOperation, TransferState
from executive.world.vehicles import AUTOPILOT_VEHICLES, VehicleProfile

OFFBOARD = "OFFBOARD"
#: Setpoints go out this often while OFFBOARD is wanted or shown: PX4 needs > 2 Hz.
STREAM_PERIOD_S = 0.1
#: The stream runs this long before OFFBOARD is asked (offboardCheck.cpp wants a recent setpoint when the commander looks).
STREAM_LEAD_S = 0.5
#: AUTO.MISSION is asked this long after the upload's MISSION_ACK at the earliest (PX4 checks the new mission meanwhile).
MISSION_CHECK_S = 1.2
#: A refused AUTO.MISSION is asked again every second for up to 10 s (vehicle time) before the refusal stands.
ROUTE_START_RETRY = RefusalRetry(every_s=1.0, for_s=10.0)


class OffboardStream:
    """The setpoint stream OFFBOARD lives on: the latest target (else where the vehicle is), re-sent every :data:`STREAM_PERIOD_S`."""

    def __init__(self, commander: Commander) -> None:
        self._commander = commander
        self._bb = blackboard.reader("offboard stream", ["/vehicle/mode", "/vehicle/position"])
        self.wanted = False  # OFFBOARD asked for, and no other mode since
        self.target: Callable[[], None] | None = None  # queues the current setpoint
        self.started_at: float | None = None
        self._last_sent = -math.inf

    @property
    def running(self) -> bool:
        return self.started_at is not None

    def aim(self, send: Callable[[], None]) -> None:
        """A new target (a setpoint): sent now and streamed from now on."""
        self.target = send
        self._send(self._commander.clock.now())

    def service(self) -> None:
        """Send the setpoint when due while OFFBOARD is wanted or shown; stop once the heartbeat shows another mode."""
        now = self._commander.clock.now()
        if not (self.wanted or self._bb.get("/vehicle/mode") == OFFBOARD):
            self.target, self.started_at = None, None
            return
        if now - self._last_sent >= STREAM_PERIOD_S * 0.9:
            self._send(now)

    def _send(self, now: float) -> None:
        if self.target is None:
            position: GlobalPosition | None = self._bb.get("/vehicle/position")
            if position is None:
                return  # nothing to hold on to yet: no stream, and PX4 refuses OFFBOARD
            lat, lon, alt = position.lat, position.lon, position.alt_rel_m
            self.target = lambda: self._commander.goto(lat, lon, alt, mode=OFFBOARD)
        self.target()
        self._last_sent = now
        if self.started_at is None:
            self.started_at = now


class Px4Port(MavlinkPort):
    """PX4: main/sub modes, the offboard setpoint stream, NAV_TAKEOFF above sea level, VTOL transitions by command in flight."""

    name = "px4"

    def __init__(self, commander: Commander, transfer: MissionTransfer | None, profile: VehicleProfile) -> None:
        super().__init__(commander, transfer, profile)
        self.capabilities = Capabilities(
            autopilot="px4",
            safe_mode="AUTO.LOITER",
            guided_mode=OFFBOARD,
            route_mode="AUTO.MISSION",
            vehicles=AUTOPILOT_VEHICLES["px4"],
            transition_anywhere=True,
            takeoff_alt_amsl=True,
            first_item_seq=0,  # PX4's mission has no home slot: src/modules/mavlink/mavlink_mission.cpp stores item 0 as the first item
            # mavlink_mission.cpp handle_message has no MISSION_WRITE_PARTIAL_LIST (ignored: no answer, tests/data/px4/README.md); a
            # whole upload keeps the navigator's item when no item is flagged current (mission_base.cpp updateMavlinkMission:
            # current_seq < 0 -> the old one, constrained to the new count), in AUTO.MISSION too
            partial_mission_writes=False,
            # src/lib/battery/module.yaml: BAT1_CAPACITY mAh (-1: unknown, the default), BAT1_N_CELLS (0: unknown), per-cell
            # BAT1_V_EMPTY (3.6 V) and BAT1_V_CHARGED (4.05 V); the height RTL climbs to first (navigator/rtl_params.c, 60 m): the
            # way home's cost (executive.sensing.energy)
            battery_params=("BAT1_CAPACITY", "BAT1_N_CELLS", "BAT1_V_EMPTY", "BAT1_V_CHARGED", "RTL_RETURN_ALT"),
            fence_params=("GF_ACTION", "GF_MAX_HOR_DIST"),
            # the altitude acceptance of a multicopter's (a VTOL's) take-off (navigator/navigator_params.c); a rover takes none
            takeoff_params=(PX4_TAKEOFF_ALT_RAD_PARAM,) if profile.aircraft else (),
        )
        self.stream = OffboardStream(commander)
        self._bb = blackboard.reader("px4 port", ["/link/mission_transfer", "/vehicle/home"])

    def service(self) -> None:
        self.stream.service()

    bytewise_params = True  # src/modules/mavlink/mavlink_parameters.cpp: an INT32's bytes in PARAM_SET's float

    def fence_settings(self, *, radius_m: float | None, inclusion_shapes: Sequence[str], held: dict[str, float]) -> FenceSettings:
        """PX4 acts on any fence it holds at GF_ACTION (navigator/geofence_params.c: default 2, Hold): enforce sets GF_ACTION 2 and
        GF_MAX_HOR_DIST the mission's max_distance_from_home_m. Several inclusion shapes are refused: PX4 holds a vehicle inside
        every one at once (navigator/geofence.cpp isInsidePolygonOrCircle), where the mission allows any of them."""
        if len(inclusion_shapes) > 1:
            return FenceSettings(
                {},
                f"PX4 keeps a vehicle inside every inclusion shape at once (navigator/geofence.cpp), the mission inside any of "
                f"{', '.join(inclusion_shapes)}: make them one polygon, or geofence.autopilot: off",
            )
        params = {"GF_ACTION": (2.0, mavlink.MAV_PARAM_TYPE_INT32)}
        if radius_m is not None:
            params["GF_MAX_HOR_DIST"] = (radius_m, mavlink.MAV_PARAM_TYPE_REAL32)
        return FenceSettings(params)

    def set_mode(self, mode: str) -> Request:
        name = self.mode_name(mode)
        delay, retry = 0.0, None
        if name == OFFBOARD:
            self.stream.wanted = True
            now = self.commander.clock.now()
            if not self.stream.running:
                self.stream.service()  # the first setpoint goes with this tick
            started = self.stream.started_at if self.stream.started_at is not None else now
            delay = max(0.0, started + STREAM_LEAD_S - now)
        else:
            self.stream.wanted = False  # the stream goes on until the heartbeat shows we left OFFBOARD
            if name == self.capabilities.route_mode:
                delay, retry = self._mission_check_wait(), ROUTE_START_RETRY
        return self._request(self.commander.set_mode(mode, delay_s=delay, retry=retry), mavlink.MAV_CMD_DO_SET_MODE, name)

    def _mission_check_wait(self) -> float:
        status: MissionTransferStatus | None = self._bb.get("/link/mission_transfer")
        if status is None or status.operation is not TransferOperation.UPLOAD or status.state is not TransferState.DONE:
            return 0.0
        return max(0.0, status.time + MISSION_CHECK_S - self.commander.clock.now())

    def _leaving_offboard(self) -> None:
        self.stream.wanted = False

    def reposition(self, lat: float, lon: float, alt_m: float) -> Request:
        """DO_REPOSITION as COMMAND_INT (lat/lon x1e7) with the change-mode flag: PX4 flies there in AUTO.LOITER.

        Its param7 is taken as an altitude above sea level whatever the frame (src/modules/navigator/navigator_main.cpp,
        VEHICLE_CMD_DO_REPOSITION): home's plus ``alt_m`` (NaN, keep the altitude, before home is known).
        """
        self._leaving_offboard()
        self.commander.note_mode_asked("AUTO.LOITER")  # the mode it puts PX4 in: ours, not a person's
        self.commander.note_target_asked(lat, lon)  # the navigator's setpoint it makes: ours, not a person's
        home: HomePosition | None = self._bb.get("/vehicle/home")
        amsl = home.alt_m + alt_m if home is not None else math.nan
        flags = float(mavlink.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)
        ticket = self.commander.command_int(mavlink.MAV_CMD_DO_REPOSITION, mavlink.MAV_FRAME_GLOBAL_INT, (-1, flags, 0, math.nan, lat, lon, amsl))
        return self._request(ticket, mavlink.MAV_CMD_DO_REPOSITION)

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        self._leaving_offboard()  # NAV_TAKEOFF: AUTO.TAKEOFF, then AUTO.LOITER (a follow-on mode)
        self.commander.note_mode_asked("AUTO.TAKEOFF")
        amsl = home.alt_m + alt_m if home is not None else math.nan
        self.commander.takeoff_alt_msl_m = amsl if home is not None else None  # how the end of the climb is told (mode_cause)
        return self._request(self.commander.takeoff(amsl), mavlink.MAV_CMD_NAV_TAKEOFF)

    def arm(self, *, force: bool = False) -> Request:
        """Forced with MAVLink's 21196 (Commander.cpp: param2 21196), not ArduPilot's 2989."""
        return self._request(self.commander.arm(force=force, force_magic=FORCE_DISARM_MAGIC), mavlink.MAV_CMD_COMPONENT_ARM_DISARM)

    def land(self, mode: str | None = None) -> Request:
        """NAV_LAND (Commander.cpp: AUTO.LAND, "Landing at current position"); PX4 answers no NAV_VTOL_LAND command."""
        self._leaving_offboard()
        if mode is not None:
            return self.set_mode(mode)
        self.commander.note_mode_asked("AUTO.LAND")
        return self._request(self.commander.land(), mavlink.MAV_CMD_NAV_LAND)

    def go_to(self, target: Target) -> None:
        # OFFBOARD's setpoints, even those the stream sends on after another mode was asked (until the heartbeat shows it)
        self.stream.aim(lambda: self.commander.goto(target.lat, target.lon, target.alt_m, mode=OFFBOARD))

    def go_to_local(self, north_m: float, east_m: float, down_m: float) -> None:
        self.stream.aim(lambda: self.commander.local_setpoint(north_m, east_m, down_m))
