"""The autopilot port: what behaviours and trees may ask of an autopilot, whatever its firmware.

Behaviours ask for *intents* (hold, go to a point, take off, land, return, transition, change
speed, start the autopilot's route, arm, disarm, a named mode where a tree really needs one) and
read *capabilities*; a back end (ArduPilot, PX4) turns them into that firmware's messages. Acked
intents return a :class:`Request`: its ticket and the outcome whose ack answers it
(``/command/<outcome>`` on the blackboard, :class:`~executive.world.state.Outcome`). Setpoints have no ack and return nothing. Nothing here
blocks: requests are sent after the tick, as the commander always did.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

from executive.mission.model import Waypoint
from executive.world.state import GlobalPosition, HomePosition, TargetAsk
from executive.world.vehicles import AutopilotName

VtolState = Literal["FW", "MC"]


@dataclass(frozen=True, slots=True)
class Request:
    """An acked request: its ticket, the outcome whose ack answers it (``blackboard.command_key(outcome)``) and how it was asked."""

    ticket: int
    outcome: str  # an Outcome (mode, arming, take_off...); a plugin's raw MAV_CMD: its name (DO_SET_RELAY)
    how: str = ""  # for feedback: the mode, or the command, that carries the intent


@dataclass(frozen=True, slots=True)
class Target:
    """A point to head for in the guided mode, with at most one of a depth below the surface and a height above the seabed (a sub's)."""

    lat: float
    lon: float
    alt_m: float = 0.0  # above home, when neither a depth nor a height above the seabed is given
    depth_m: float | None = None
    altitude_m: float | None = None  # above the seabed


@dataclass(frozen=True, slots=True)
class Capabilities:
    """What one autopilot firmware offers a mission (mode names as its heartbeat shows them)."""

    autopilot: AutopilotName
    safe_mode: str  # where Ctrl-C, a crash or the end of a mission leaves the vehicle
    guided_mode: str  # the mode that follows the executive's targets
    route_mode: str  # the mode that flies the autopilot's own route
    vehicles: frozenset[str]  # vehicle kinds (executive.world.vehicles) this firmware drives
    transition_anywhere: bool  # a VTOL transition is taken by command in any mode in flight
    takeoff_alt_amsl: bool  # NAV_TAKEOFF's altitude is above sea level (else above home)
    first_item_seq: int  # the seq of the route's first waypoint on the autopilot: 1 after ArduPilot's home item 0, 0 on PX4
    #: The autopilot takes MISSION_WRITE_PARTIAL_LIST (ArduPilot), so a horizon grows by appends; else (PX4) by the whole window again.
    partial_mission_writes: bool = True
    #: The parameter naming the RC channel whose position sets the mode by itself (ArduRover MODE_CH); None: no such channel.
    mode_switch_param: str | None = None
    #: Parameters that say how the vehicle drives to a point, read at pre-flight for GoTo's look-ahead (ArduRover:
    #: executive.autopilot.rover_motion.MOTION_PARAMS); empty: its driving is not modelled, every waypoint is a stop.
    motion_params: tuple[str, ...] = ()
    #: The battery's parameters, read at pre-flight for the energy rule (executive.energy.battery): ArduPilot BATT_MONITOR,
    #: BATT_CAPACITY, BATT_ARM_MAH, BATT_ARM_VOLT; PX4 BAT1_CAPACITY, BAT1_N_CELLS, BAT1_V_EMPTY, BAT1_V_CHARGED.
    battery_params: tuple[str, ...] = ()
    #: The fence's parameters read at pre-flight (logged, and what ``geofence.autopilot: enforce`` changes): ArduPilot
    #: FENCE_ENABLE, FENCE_TYPE, FENCE_ACTION, FENCE_RADIUS, FENCE_OPTIONS; PX4 GF_ACTION, GF_MAX_HOR_DIST.
    fence_params: tuple[str, ...] = ()
    #: Parameters that say where the autopilot itself ends a take-off (executive.autopilot.mode_cause judges whose the mode
    #: change after it is): PX4 NAV_MC_ALT_RAD.
    takeoff_params: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class FenceSettings:
    """What ``geofence.autopilot: enforce`` sets on this firmware (name -> (value, MAV_PARAM_TYPE)), or why it cannot (``refused``)."""

    params: dict[str, tuple[float, int]]
    refused: str = ""


class AutopilotPort(Protocol):
    """The intents and capabilities behaviours use; a back end per firmware implements them."""

    @property
    def capabilities(self) -> Capabilities: ...

    def mode_name(self, mode: str) -> str:
        """What the heartbeat shows for a mode the trees name the ArduPilot way (``GUIDED`` -> ``OFFBOARD`` on PX4)."""
        ...

    # -- acked intents -----------------------------------------------------------------------
    def set_mode(self, mode: str) -> Request:
        """A named mode, where a tree really needs one (KeyError if the firmware has no such mode)."""
        ...

    def hold(self) -> Request:
        """Stop and hold where the vehicle is: the safe mode."""
        ...

    def arm(self, *, force: bool = False) -> Request: ...

    def disarm(self, *, force: bool = False) -> Request: ...

    def reposition(self, lat: float, lon: float, alt_m: float) -> Request:
        """Go to a point (altitude above home), acked; the autopilot switches to the mode that does it."""
        ...

    def take_off(self, alt_m: float, *, home: HomePosition | None, position: GlobalPosition | None, airborne: bool) -> Request:
        """Climb to ``alt_m`` above home (already airborne: climb on above where the vehicle is)."""
        ...

    def land(self, mode: str | None = None) -> Request:
        """Land where the vehicle is (``mode``: the tree's landing mode, else the firmware's)."""
        ...

    def return_home(self) -> Request: ...

    def transition(
        self, to: VtolState, *, mode: str | None, position: GlobalPosition | None, heading_deg: float, mc_mode: str, ahead_m: float
    ) -> Request | None:
        """A VTOL to fixed-wing or multicopter flight; None when it cannot be asked (no position to go ahead from)."""
        ...

    def change_speed(self, speed_m_s: float, *, airspeed: bool = False) -> Request: ...

    def start_route(self) -> Request:
        """Fly the route held by the autopilot."""
        ...

    def set_home(self, lat: float | None = None, lon: float | None = None, alt_m: float = 0.0) -> Request: ...

    def cancel(self, request: Request | None) -> bool:
        """Forget a request that no longer matters (its behaviour was interrupted); whether one was pending."""
        ...

    def read_parameter(self, name: str) -> None:
        """Ask for a parameter's value; it arrives on ``/vehicle/params`` (never acked: ask again if it does not come)."""
        ...

    # -- what was asked (to tell our mode changes from a person's) ----------------------------
    def mode_asked_at(self, mode: str) -> float | None:
        """When ``mode`` (as the heartbeat shows it) was last asked for, or put by a request of ours; None if never."""
        ...

    @property
    def target_asked(self) -> TargetAsk | None:
        """The point we last asked the autopilot to steer to (a setpoint, a DO_REPOSITION) and when; None if never."""
        ...

    @property
    def takeoff_alt_msl_m(self) -> float | None:
        """The altitude above mean sea level the latest take-off of ours climbs to, as sent; None: none asked, or the
        autopilot's default height."""
        ...

    # -- setpoints (no ack; re-sent by the behaviour) ------------------------------------------
    def go_to(self, target: Target) -> None:
        """Head for a point in the guided mode (a sub's with its depth or height above the seabed)."""
        ...

    def go_to_local(self, north_m: float, east_m: float, down_m: float) -> None:
        """Head for a point of the local NED frame in the guided mode."""
        ...

    def hold_depth(self, lat: float, lon: float, *, depth_m: float | None = None, altitude_m: float | None = None) -> None:
        """A sub's depth (below the surface) or height above the seabed at a point."""
        ...

    # -- the autopilot's own route -------------------------------------------------------------
    def route_differs(self, waypoints: Sequence[Waypoint], held: object | None) -> str | None:
        """Why the autopilot's route (``/vehicle/mission_items``) is not ``waypoints``; None when it is."""
        ...

    @property
    def route_transfer_idle(self) -> bool:
        """No route transfer is running (another may have started one)."""
        ...

    def upload_route(self, waypoints: Sequence[Waypoint], home: HomePosition | None) -> int:
        """Upload a route (read back before it counts); the transfer's ticket (``/link/mission_transfer``)."""
        ...

    def horizon_differs(self, waypoints: Sequence[Waypoint], leg: int, horizon: int, held: object | None) -> str | None:
        """drive: auto: why the autopilot's route (``/vehicle/mission_items``) is not the route's first waypoints through leg ``leg``'s
        and at most ``horizon`` beyond it; None when it is."""
        ...

    def extend_route(self, waypoints: Sequence[Waypoint]) -> int:
        """Add waypoints after those the autopilot holds, one partial write each, back to back (read back before it counts);
        the transfer's ticket."""
        ...

    def set_route_leg(self, leg: int) -> int:
        """Make the autopilot's route go on with leg ``leg`` (to its waypoint ``leg``); the transfer's ticket, confirmed by MISSION_CURRENT."""
        ...

    # -- the autopilot's fence and rally points ---------------------------------------------------
    def upload_zones(self, items: Sequence[object], mission_type: int) -> int:
        """Replace the autopilot's fence or rally points (``mission_type`` MAV_MISSION_TYPE_FENCE / _RALLY) with ``items``
        (executive.autopilot.fence), read back item by item before it counts; the transfer's ticket (``/link/mission_transfer``)."""
        ...

    def zones_differ(self, items: Sequence[object], held: object) -> str | None:
        """How the fence or rally items held (``/vehicle/fence_items``, ``/vehicle/rally_items``) differ from ``items``; None if alike."""
        ...

    def set_parameter(self, name: str, value: float, param_type: int) -> None:
        """Ask the autopilot to hold ``value`` in ``name``; its PARAM_VALUE answer lands on ``/vehicle/params`` (no ack: ask again)."""
        ...

    def fence_settings(self, *, radius_m: float | None, inclusion_shapes: Sequence[str], held: dict[str, float]) -> FenceSettings:
        """What enforcing the uploaded fence sets (``radius_m``: the mission's max_distance_from_home_m), from the fence
        parameters ``held`` now (:attr:`Capabilities.fence_params`)."""
        ...
