"""The blackboard's documented keys, who writes them, and their defaults.

Namespaces:

- ``/link``: the MAVLink link to the autopilot (mavlink reader), its mission transfers (mission transfer) and route uploads (route keeper).
- ``/vehicle``: the vehicle's state as the autopilot reports it (mavlink reader; its mission: mission transfer).
- ``/rc``: the RC receiver, from MAVLink RC_CHANNELS or the CAN bus (mavlink / CAN reader).
- ``/base``: the AgileX tracked base over CAN: its state frames (CAN reader) and the drive commands sent to it (drive bridge).
- ``/heading``: the heading sanity filter's verdict (heading filter).
- ``/obstacles``: a camera's obstacle distances (obstacle receiver) and their forwarding to the autopilot (obstacle forwarder).
- ``/runtime``: the loop itself: late and skipped ticks, the rate it achieves (tick pacer).
- ``/mission``: the mission lifecycle, route progress and sample log (executive.mission), and what the running tree waits for (tree watch).
- ``/operator``: requests from the operator (control socket, RC switches, ground station).
- ``/sampler``: the sample-taking instrument (sampler).
- ``/command``: the latest command of each outcome asked of the autopilot (mode, arming, reposition...) and its ack (commander).
- ``/plugin/<name>``: keys a plugin's behaviours declare (:func:`declare`) and write; nothing of ours writes there.

Our behaviours only read; a plugin's behaviour may write the keys of its own ``/plugin/<name>/``
namespace it declares. Every key exists from :func:`reset` on, holding its default, so a guard
never trips over a missing key. Each runtime has a board of its own (:class:`Board`,
:func:`for_runtime`): py_trees' blackboard is one per process.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.blackboard import Blackboard
from py_trees.common import Access

from executive.world.state import Outcome


@dataclass(frozen=True)
class Key:
    """One documented blackboard key."""

    name: str
    default: Any
    writer: str
    doc: str


_KEYS: tuple[Key, ...] = (
    Key("/link/up", False, "mavlink reader", "an autopilot HEARTBEAT arrived within the link timeout"),
    Key("/link/last_heartbeat", None, "mavlink reader", "clock time of the autopilot's last HEARTBEAT"),
    Key("/link/system_id", None, "mavlink reader", "the autopilot's MAVLink system id"),
    Key("/link/component_id", None, "mavlink reader", "the autopilot's MAVLink component id"),
    Key("/link/heartbeat_age_s", None, "mavlink reader", "seconds since the autopilot's last HEARTBEAT"),
    Key("/link/up_since", None, "mavlink reader", "clock time of the HEARTBEAT that brought the link up (last); None while it is down"),
    Key("/link/messages", 0, "mavlink reader", "messages received from the autopilot"),
    Key("/link/packets_lost", 0, "mavlink reader", "packets from the autopilot lost on the way (sequence gaps)"),
    Key("/link/loss_pct", 0.0, "mavlink reader", "packets lost / packets sent by the autopilot, percent"),
    Key("/link/reboots", 0, "mavlink reader", "autopilot reboots seen (its boot clock ran backwards)"),
    Key("/link/bad_data", 0, "mavlink reader", "undecodable byte runs received"),
    Key("/link/unsigned_dropped", 0, "mavlink reader", "unsigned packets dropped while signing is on"),
    Key("/link/device_lost", None, "mavlink reader", "why the serial device is gone while it is opened again (None: it is there, or no serial link)"),
    Key("/link/mission_transfer", None, "mission transfer", "MissionTransferStatus of the latest mission upload, download, clear or set-current"),
    Key("/link/route_upload", None, "route keeper", "RouteUpload: the latest edited route (and home) sent to the autopilot, read back, retried"),
    Key("/vehicle/mav_type", None, "mavlink reader", "HEARTBEAT type (MAV_TYPE)"),
    Key("/vehicle/armed", False, "mavlink reader", "the autopilot reports itself armed"),
    Key("/vehicle/mode", None, "mavlink reader", "flight mode name, e.g. GUIDED"),
    Key(
        "/vehicle/mode_set_by",
        None,
        "intervention watch",
        "who set the mode: 'us' (we asked for it), 'autopilot' (its own transition, by cause: executive.autopilot.mode_cause), 'others' (a person, "
        "a GCS); None = unknown (boot)",
    ),
    Key("/vehicle/position_target", None, "mavlink reader", "PositionTarget (POSITION_TARGET_GLOBAL_INT): the point the autopilot steers to"),
    Key(
        "/vehicle/target_set_by",
        None,
        "intervention watch",
        "who set the point the autopilot reports steering to: 'us' (the target we asked, reported since), 'others' (a person: "
        "executive.autopilot.target_watch); None = not judged (no report, or ours not reported yet since the last ask or mode change)",
    ),
    Key("/vehicle/custom_mode", None, "mavlink reader", "flight mode number"),
    Key("/vehicle/system_status", None, "mavlink reader", "HEARTBEAT system_status (MAV_STATE)"),
    Key("/vehicle/position", None, "mavlink reader", "GlobalPosition (GLOBAL_POSITION_INT)"),
    Key("/vehicle/attitude", None, "mavlink reader", "Attitude (ATTITUDE)"),
    Key("/vehicle/ekf", None, "mavlink reader", "EkfStatus (EKF_STATUS_REPORT)"),
    Key("/vehicle/ekf_failsafe", False, "mavlink reader", "the autopilot's own EKF failsafe acted ('EKF failsafe') and has not cleared"),
    Key("/vehicle/battery", None, "mavlink reader", "Battery (SYS_STATUS)"),
    Key("/vehicle/battery_status", None, "mavlink reader", "BatteryStatus (BATTERY_STATUS of battery 0): consumed mAh and Wh, remaining"),
    Key("/vehicle/statustext", None, "mavlink reader", "(severity, text) of the last STATUSTEXT"),
    Key("/vehicle/params", None, "mavlink reader", "parameters the autopilot sent (PARAM_VALUE): name -> value; None until one came"),
    Key("/rc/chancount", None, "mavlink reader", "RC_CHANNELS chancount: channels the receiver has (every field present is read whatever it says)"),
    Key("/vehicle/mission_home", None, "mission transfer", "home as item 0 of the last mission read back (MissionItem); None = not read"),
    Key("/vehicle/mission_items", None, "mission transfer", "the mission items 1..n the vehicle holds (tuple of MissionItem); None = unknown"),
    Key("/vehicle/fence_status", None, "mavlink reader", "FenceStatus of the autopilot's own fence (FENCE_STATUS); None = never reported"),
    Key("/vehicle/fence_items", None, "mission transfer", "the fence items the vehicle holds, read back (tuple of MissionItem); None = unknown"),
    Key("/vehicle/rally_items", None, "mission transfer", "the rally points the vehicle holds, read back (tuple of MissionItem); None = unknown"),
    Key("/vehicle/mission_current", None, "mission transfer", "MissionCurrent (MISSION_CURRENT): the item the vehicle is on"),
    Key("/vehicle/mission_reached", None, "mission transfer", "MissionItemReached: the last item the vehicle reported reached"),
    Key("/vehicle/home", None, "mavlink reader", "HomePosition (HOME_POSITION)"),
    Key("/vehicle/ground_speed_m_s", None, "mavlink reader", "ground speed (VFR_HUD)"),
    Key("/vehicle/altitude_above_bottom_m", None, "mavlink reader", "height above seabed/ground, m (downward rangefinder); None = no valid reading"),
    Key("/vehicle/rangefinder", None, "mavlink reader", "Rangefinder: the downward DISTANCE_SENSOR's reading, range and verdict; None = none yet"),
    Key("/vehicle/altitude_last_update", None, "mavlink reader", "clock time of the last downward DISTANCE_SENSOR or RANGEFINDER read"),
    Key("/vehicle/heading_deg", None, "mavlink reader", "heading the autopilot believes, degrees (VFR_HUD)"),
    Key("/vehicle/gps", None, "mavlink reader", "GpsFix (GPS_RAW_INT)"),
    Key("/vehicle/servo_outputs", (), "mavlink reader", "servo output PWM per channel, µs (SERVO_OUTPUT_RAW, port 0)"),
    Key("/vehicle/vtol_state", None, "mavlink reader", "MC, FW, TRANSITION_TO_FW, TRANSITION_TO_MC (EXTENDED_SYS_STATE)"),
    Key("/vehicle/landed_state", None, "mavlink reader", "ON_GROUND, IN_AIR, TAKEOFF, LANDING (EXTENDED_SYS_STATE)"),
    Key("/rc/channels", (), "mavlink reader", "RC input PWM per channel, µs; 0 = no signal"),
    Key("/rc/rssi", None, "mavlink reader", "receiver RSSI, 0-254; None if unknown"),
    Key("/rc/last_update", None, "mavlink reader", "clock time of the last RC report"),
    Key("/rc/connected", False, "mavlink reader", "the receiver reports a transmitter (channels non-zero)"),
    Key("/rc/fresh", False, "rc reader", "RC reports arrive (within rc.fresh_timeout_s) and are not frozen"),
    Key("/rc/switches", None, "rc reader", "RcSwitches: SWA..SWD and knob VRA, from RC channels or CAN"),
    Key("/rc/stale_reason", "no RC report yet", "rc reader", "why /rc/fresh is False; empty when fresh"),
    Key("/rc/sticks", None, "can reader", "RcSticks: the AgileX transmitter's sticks in [-100, 100] (CAN 0x241)"),
    Key("/base/up", False, "can reader", "a valid frame from the base arrived within the CAN reader's base timeout"),
    Key("/base/last_update", None, "can reader", "clock time of the last valid frame from the base (0x211, 0x221, 0x241, 0x311)"),
    Key("/base/system", None, "can reader", "BaseSystem (0x211): vehicle state, control mode (RC/CAN), battery voltage, fault code"),
    Key("/base/faults", (), "can reader", "names of the faults the base reports (0x211), e.g. ('RC_SIGNAL_LOSS',); () = none"),
    Key("/base/motion", None, "can reader", "BaseMotion (0x221): linear m/s and angular rad/s the base measures"),
    Key("/base/odometry", None, "can reader", "BaseOdometry (0x311): distance each track has run, m"),
    Key("/base/frames", 0, "can reader", "CAN frames received"),
    Key("/base/bad_frames", 0, "can reader", "AgileX frames that could not be used: wrong length, values out of range"),
    Key("/base/other_frames", 0, "can reader", "CAN frames with ids the executive does not read"),
    Key("/base/rc_counter_repeats", 0, "can reader", "0x241 frames whose rolling counter did not move (a frozen counter = stale RC)"),
    Key("/base/bus_errors", 0, "can reader", "errors reading the CAN bus"),
    Key("/base/drive", None, "drive bridge", "DriveStatus: the motion command sent to the base (0x111) and why it is zero, if it is"),
    Key("/base/send_errors", 0, "drive bridge", "CAN frames the drive bridge could not send"),
    Key("/heading/deg", None, "heading filter", "filtered heading, degrees [0, 360)"),
    Key("/heading/ok", None, "heading filter", "the compass agrees with the filter; None = not judged yet"),
    Key("/heading/bias_deg", None, "heading filter", "estimated compass bias against course over ground"),
    Key("/heading/reason", "", "heading filter", "why the compass is not ok (empty when it is, or is not judged)"),
    Key("/heading/last_update", None, "heading filter", "clock time the attitude the verdict rests on was received (ATTITUDE); None = none yet"),
    Key(
        "/energy/estimate",
        None,
        "energy watch",
        "EnergyEstimate: left above the reserve, what the route and the way home need; None = none",
    ),
    Key("/energy/unknown", "", "energy watch", "why no energy estimate can be made (what to set): refused; empty when one is"),
    Key(
        "/energy/not_judged",
        "",
        "energy watch",
        "why the battery cannot tell the energy of a mission that did not ask for the rule (no energy:): it runs, warned; else empty",
    ),
    Key("/obstacles/scan", None, "obstacle receiver", "ObstacleScan: the camera's latest valid scan"),
    Key("/obstacles/received", 0, "obstacle receiver", "valid scans received"),
    Key("/obstacles/rejected", 0, "obstacle receiver", "datagrams dropped as not a scan"),
    Key("/obstacles/last_error", "", "obstacle receiver", "why the latest dropped datagram was dropped (field: reason)"),
    Key("/obstacles/forwarded", 0, "obstacle forwarder", "OBSTACLE_DISTANCE messages sent to the autopilot"),
    Key("/runtime/late_ticks", 0, "tick pacer", "ticks that started more than half a period after they were due"),
    Key("/runtime/skipped_ticks", 0, "tick pacer", "ticks never run: the loop fell more than a period behind and restarted its schedule"),
    Key("/runtime/rate_hz", None, "tick pacer", "ticks per second of clock time over the last window (5 s); None until the first"),
    Key("/runtime/storage_lost", None, "storage", "the recordings that cannot write to the disk now, and why (None: all write)"),
    Key("/mission/state", "IDLE", "mission lifecycle", "IDLE, READY, RUNNING, PAUSED, COMPLETED or ABORTED"),
    Key("/mission/leg_index", 0, "route progress", "index of the waypoint the vehicle is heading for"),
    Key("/mission/leg_count", 0, "route progress", "number of legs (waypoints) in the mission"),
    Key("/mission/target", None, "route progress", "the Waypoint of the current leg; None when no leg is active"),
    Key("/mission/next_target", None, "route progress", "the Waypoint of the leg after the current one; None on the last leg"),
    Key("/mission/reason", "", "mission lifecycle", "why the last request was refused or the mission ended"),
    Key("/mission/samples", (), "sample log", "Samples recorded in this run, oldest first"),
    Key(
        "/mission/waiting",
        None,
        "tree watch",
        "Waiting: the tree's deepest running node, its feedback, since when (executive.tree.waiting); before the tree's first tick, "
        "the distance rule waiting for a position (told by the reach gate, executive.admission.reach); None = no tree runs",
    ),
    Key("/sampler/status", None, "sampler", "SamplerStatus of the latest sample request"),
    Key("/operator/request", None, "operator control", "the operator's latest request (start, pause, ...)"),
    Key(
        "/operator/command",
        None,
        "persons commands",
        "a person's latest arm, disarm or mode through the executive: {what, by, answer, refused, t}; None until one is sent",
    ),
)


def command_key(outcome: str) -> str:
    """The blackboard key holding the CommandStatus of an outcome (``Outcome.MODE`` -> ``/command/mode``).

    A plugin's raw MAV_CMD, one no outcome covers, has ``/command/<its name lowercase>`` (:func:`document_command`).
    """
    return f"/command/{outcome.lower()}"


def _command_doc(outcome: Outcome) -> Key:
    return Key(command_key(outcome), None, "commander", f"CommandStatus of the latest {_OUTCOME_DOCS[outcome]} asked of the autopilot")


_OUTCOME_DOCS: dict[Outcome, str] = {
    Outcome.MODE: "flight mode",
    Outcome.ARMING: "arm or disarm",
    Outcome.MESSAGE_RATE: "message rate (telemetry streams)",
    Outcome.HOME: "home",
    Outcome.SPEED: "cruise speed",
    Outcome.REPOSITION: "reposition (go to a point, acked)",
    Outcome.TRANSITION: "VTOL transition",
    Outcome.TAKE_OFF: "take-off",
    Outcome.LAND: "landing where the vehicle is",
    Outcome.VTOL_TAKE_OFF: "VTOL take-off (a climb as a multicopter)",
    Outcome.VTOL_LAND: "VTOL landing",
    Outcome.RETURN_HOME: "return home",
    Outcome.START_ROUTE: "start of the autopilot's route",
    Outcome.ROUTE_ITEM: "route item to head for",
    Outcome.MESSAGE: "message asked for once",
}

KEYS: dict[str, Key] = {k.name: k for k in _KEYS} | {command_key(o): _command_doc(o) for o in Outcome}


def document_command(name: str) -> str:
    """Document ``/command/<name>`` for a plugin's raw MAV_CMD kind (e.g. DO_SET_RELAY) that no outcome covers; returns the key."""
    key = command_key(name)
    if key not in KEYS:
        KEYS[key] = Key(key, None, "commander", f"CommandStatus of the latest MAV_CMD_{name}")
    _current.storage.setdefault(key, None)
    return key


#: Where plugins' own keys live: ``/plugin/<plugin name>/<key>``.
PLUGIN_NAMESPACE = "/plugin/"


def declare(key: Key) -> str:
    """Document a plugin's own key (``/plugin/<plugin name>/<key>``), set to its default; returns its name.

    Declaring the same key again the same way is harmless; another default or doc for a documented
    key, or a key outside ``/plugin/``, is a ValueError: the executive's own keys are written by its
    IO readers and mission state only.
    """
    parts = key.name.split("/")
    if not key.name.startswith(PLUGIN_NAMESPACE) or len(parts) < 4 or not all(parts[2:]):
        raise ValueError(f"blackboard key {key.name!r}: a plugin declares keys under {PLUGIN_NAMESPACE}<plugin name>/<key>")
    known = KEYS.get(key.name)
    if known is not None and known != key:
        raise ValueError(f"blackboard key {key.name!r} is already declared differently (by {known.writer})")
    if known is None:
        KEYS[key.name] = key
    _current.storage.setdefault(key.name, key.default)  # on the current board: another runtime's was made before it was documented
    return key.name


def reset(*, activity_stream: bool = False) -> Board:
    """The current board emptied, every documented key at its default, and no runtime's any more (the next one may take it).

    The activity stream (every read and write, for debugging displays) costs time on each
    access, so it is off unless asked for.
    """
    _current.clear(activity_stream=activity_stream)
    _current.runtime = None
    return _current


def for_runtime(name: str) -> Board:
    """A board for one runtime (``name``: what it drives), made current: the current one emptied, or a new one if a runtime has it.

    So two runtimes in one process (two vehicles in one test) never share keys, while what a test
    made before building its first runtime (a tree, a client that scripts inputs) is on that
    runtime's board. What is made while another runtime's board is current stays on that one: a
    second runtime's tree is built by the runtime (or after it).
    """
    if _current.runtime is not None:
        Board().install()
    board = reset()
    board.runtime = name
    return board


def current() -> Board:
    """The board py_trees' process-wide :class:`~py_trees.blackboard.Blackboard` stands for now."""
    return _current


def value(key: str) -> Any:
    """The value of ``key`` now on the current board (None if it is not there), read without a client: for recorders, never for behaviours."""
    return _current.storage.get(key)


def documented_values() -> list[tuple[str, Any]]:
    """Every documented key and its value now on the current board, in :data:`KEYS`' order: for recorders, never for behaviours."""
    get = _current.storage.get
    return [(key, get(key)) for key in KEYS]


def keys_under(*prefixes: str) -> list[str]:
    """Documented keys whose names start with one of ``prefixes`` (e.g. ``"/vehicle/"``)."""
    return [name for name in KEYS if name.startswith(prefixes)]


class Board:
    """One runtime's blackboard: its keys' values, py_trees' metadata of who reads and writes them, its clients.

    py_trees keeps these at class level, one set a process (``Blackboard.storage``, ``metadata``,
    ``clients``, ``activity_stream``); :meth:`install` points them at this board's, so py_trees'
    own code (a client's checked access, the activity stream, its displays) works on it. A client
    keeps the board current when it was made (:class:`Client`): its reads and writes go to that
    board whichever is installed, so a runtime's services and tree never see another's keys.
    """

    def __init__(self) -> None:
        self.storage: dict[str, Any] = {key.name: key.default for key in KEYS.values()}
        self.metadata: dict[str, Any] = {}
        self.clients: dict[Any, str] = {}
        self.activity_stream: Any = None
        #: The runtime that has this board (:func:`for_runtime`) until it is closed; None: the next runtime may take it.
        self.runtime: str | None = None

    def install(self) -> None:
        """Make this the board py_trees' class-level blackboard stands for (and :func:`value` reads)."""
        global _current
        if _current is not self:
            _current.activity_stream = Blackboard.activity_stream  # py_trees may have switched it on or off
        Blackboard.storage, Blackboard.metadata, Blackboard.clients = self.storage, self.metadata, self.clients
        Blackboard.activity_stream = self.activity_stream
        _current = self

    def clear(self, *, activity_stream: bool) -> None:
        """Empty it, every documented key at its default (it must be installed)."""
        Blackboard.clear()
        if activity_stream:
            Blackboard.enable_activity_stream()
        self.activity_stream = Blackboard.activity_stream
        for key in KEYS.values():
            self.storage[key.name] = key.default

    def value(self, key: str) -> Any:
        """The value of ``key`` on this board (None if it is not there), read without a client: for tests and recorders."""
        return self.storage.get(key)


class PyTreesBoard:
    """The one place the blackboard meets py_trees: the current board, and the clients below."""

    @staticmethod
    def client(name: str, keys: Iterable[str], access: Access) -> Client:
        """A client registered for ``keys`` (each documented) with ``access``."""
        client = Client(name=name)
        for key in keys:
            if key not in KEYS:
                raise KeyError(f"undocumented blackboard key {key!r}")
            client.register_key(key=key, access=access)
        return client


class Client(py_trees.blackboard.Client):
    """A py_trees blackboard client of the board current when it is made, whose ``get`` and ``set`` of its registered keys go straight to it.

    py_trees' own ``get`` and ``set`` resolve the name again, split it for nested attributes and go
    through ``__getattr__``/``__setattr__``: a few microseconds an access, and a tick makes dozens.
    The access rules are the same (read: any registered key; write: keys registered for writing).
    With the activity stream on (debugging displays), and for anything else (nested or relative
    names, unregistered keys: the errors, ``overwrite=False``), py_trees does the work, on this
    client's board.

    ``get`` and ``set`` are the client's own functions, made with it (:func:`_getter`, :func:`_setter`):
    py_trees' client class has ``__getattr__`` (its keys read as attributes), which puts every attribute
    read of a client on Python's slow path. A method would read itself and the client's board and keys
    that way at each call; these functions hold them.
    """

    get: Callable[[str], Any]
    set: Callable[..., bool]

    def __init__(self, *, name: str | None = None, namespace: str | None = None) -> None:
        super().__init__(name=name, namespace=namespace)
        object.__setattr__(self, "board", _current)
        object.__setattr__(self, "get", _getter(self, _current))
        object.__setattr__(self, "set", _setter(self, _current))

    def register_key(self, key: str, access: Access, required: bool = False, remap_to: str | None = None) -> None:
        """Register ``key`` with ``access`` (py_trees' own), noted on this client's board."""
        with _installed(self.board):
            super().register_key(key, access, required, remap_to)


def _getter(client: Client, board: Board) -> Callable[[str], Any]:
    """``client.get``: the value of ``name``, from ``board`` (py_trees' own get when the activity stream is on, or for another name)."""
    remappings = client.remappings  # py_trees adds and removes keys in place

    def get(name: str) -> Any:
        if board.activity_stream is None and Blackboard.activity_stream is None and "." not in name:
            try:
                return board.storage[remappings[name]]
            except KeyError:
                pass  # not registered, or not on the board: py_trees raises its own error
        with _installed(board):
            return py_trees.blackboard.Client.get(client, name)

    return get


def _setter(client: Client, board: Board) -> Callable[..., bool]:
    """``client.set``: write ``value`` to ``name`` on ``board`` (py_trees' own set when the activity stream is on, or for another name)."""
    remappings, write, exclusive = client.remappings, client.write, client.exclusive  # py_trees changes them in place

    def put(name: str, value: Any, overwrite: bool = True) -> bool:
        direct = overwrite and board.activity_stream is None and Blackboard.activity_stream is None and "." not in name
        if direct and (name in write or name in exclusive):
            board.storage[remappings[name]] = value
            return True
        with _installed(board):
            return py_trees.blackboard.Client.set(client, name, value, overwrite)

    return put


@contextmanager
def _installed(board: Board) -> Iterator[None]:
    """``board`` installed for py_trees' own code, the current one back after."""
    before = _current
    if before is board:
        yield
        return
    board.install()
    try:
        yield
    finally:
        before.install()


def writer(name: str, keys: Iterable[str]) -> py_trees.blackboard.Client:
    """A client that may write ``keys``: for IO readers and mission state code only."""
    return PyTreesBoard.client(name, keys, Access.WRITE)


def reader(name: str, keys: Iterable[str]) -> py_trees.blackboard.Client:
    """A read-only client (what a behaviour holds)."""
    return PyTreesBoard.client(name, keys, Access.READ)


_current = Board()
_current.install()
