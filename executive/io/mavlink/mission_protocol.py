"""The MAVLink mission protocol, executive side: upload, download, clear and set-current, never blocking.

A request (:meth:`MissionTransfer.upload`, :meth:`~MissionTransfer.download`, ...) returns a ticket
at once and starts a transfer. The transfer sends its messages at :meth:`MissionTransfer.flush`
(after the tick, like the commander), advances when the reader hands it the vehicle's replies,
resends its last message when a reply is late and gives up after ``retries`` resends in a row.
One transfer runs at a time: a new request supersedes the one in progress. Its fate is
``/link/mission_transfer`` (a :class:`MissionTransferStatus`); what the vehicle holds and does is
``/vehicle/mission_home``, ``/vehicle/mission_items``, ``/vehicle/mission_current`` and
``/vehicle/mission_reached``. Each request names its ``mission_type``: the flight plan (the default),
the fence or the rally points (MAV_MISSION_TYPE_FENCE, _RALLY), which the firmware keeps apart
(ArduPilot's GCS_MAVLink/MissionItemProtocol_Fence.cpp and _Rally.cpp, PX4's
src/modules/mavlink/mavlink_mission.cpp) and neither numbers from a home item; what the vehicle holds
of those is ``/vehicle/fence_items`` and ``/vehicle/rally_items``.

ArduPilot's conventions, which the firmware follows rather than the spec:

- item 0 is home: an upload carries a home item 0 (ArduPilot stores it, yet reports its own home
  there), a download returns it apart from the mission items 1..n;
- the vehicle asks for items with MISSION_REQUEST (ArduPilot) or MISSION_REQUEST_INT: both are
  answered with MISSION_ITEM_INT;
- items come back as the vehicle stores them (latitude and longitude to 1e-7 degree, altitude to
  the centimetre, non-INT frames), so an upload's read-back compares within those tolerances.
"""

from __future__ import annotations

import itertools
import logging
import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from enum import Enum
from typing import TYPE_CHECKING, Any

from executive.io.mavlink.link import Link
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, encoder, mavlink
from executive.world.state import MissionCurrent, MissionItemReached, MissionTransferStatus, TransferOperation, TransferState

if TYPE_CHECKING:
    from executive.mission.model import Waypoint

log = logging.getLogger(__name__)

_M = mavlink
_MISSION = _M.MAV_MISSION_TYPE_MISSION

#: Read-back tolerances: what ArduPilot's storage keeps (1e-7 degree, 1 cm) and float32 parameters.
LATLON_TOLERANCE_DEG = 1e-7
ALT_TOLERANCE_M = 0.01
PARAM_RELATIVE_TOLERANCE = 1e-6

# ArduPilot reports a frame in its non-INT form, and frame 0 for items without a location
_SAME_FRAME = {
    _M.MAV_FRAME_GLOBAL_INT: _M.MAV_FRAME_GLOBAL,
    _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: _M.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    _M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: _M.MAV_FRAME_GLOBAL_TERRAIN_ALT,
    _M.MAV_FRAME_MISSION: _M.MAV_FRAME_GLOBAL,
}

_FENCE = _M.MAV_MISSION_TYPE_FENCE
_RALLY = _M.MAV_MISSION_TYPE_RALLY
#: Where what the vehicle holds of the fence and the rally points goes (the flight plan: /vehicle/mission_items).
_HELD_KEY = {_FENCE: "/vehicle/fence_items", _RALLY: "/vehicle/rally_items"}
#: What a person calls each mission type, for the log and the failures.
MISSION_TYPE_NAMES = {_MISSION: "mission", _FENCE: "fence", _RALLY: "rally points"}

#: The blackboard keys a :class:`MissionTransfer` writes.
MISSION_KEYS = (
    "/link/mission_transfer", "/vehicle/mission_home", "/vehicle/mission_items", "/vehicle/mission_current", "/vehicle/mission_reached",
    *_HELD_KEY.values(),
)  # fmt: skip


def mission_result_name(result: int) -> str:
    """``4`` -> ``MAV_MISSION_NO_SPACE``."""
    entry = _M.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry else f"MAV_MISSION_RESULT({result})"


@dataclass(frozen=True, slots=True)
class MissionItem:
    """One mission item as MISSION_ITEM_INT carries it, but with ``x``/``y`` in degrees (1e-7 degree on the wire)."""

    seq: int
    frame: int  # MAV_FRAME
    command: int  # MAV_CMD
    current: int  # 1 on the item the vehicle is executing (downloads only)
    autocontinue: int
    param1: float
    param2: float
    param3: float
    param4: float
    x: float  # latitude, degrees
    y: float  # longitude, degrees
    z: float  # altitude, metres, in ``frame``
    mission_type: int = _MISSION  # MAV_MISSION_TYPE: the flight plan, the fence or the rally points

    @classmethod
    def waypoint(
        cls, seq: int, lat: float, lon: float, alt_m: float = 0.0, *, hold_s: float = 0.0, frame: int = _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    ) -> MissionItem:
        """A NAV_WAYPOINT to ``lat``/``lon`` at ``alt_m`` (above home by default), holding there ``hold_s``."""
        return cls(seq, frame, _M.MAV_CMD_NAV_WAYPOINT, 0, 1, hold_s, 0.0, 0.0, 0.0, lat, lon, alt_m)

    @classmethod
    def stop(cls, seq: int, lat: float, lon: float, alt_m: float = 0.0, *, frame: int = _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT) -> MissionItem:
        """A NAV_LOITER_UNLIM at ``lat``/``lon``: the vehicle stops there until its mission is moved on (MISSION_SET_CURRENT)."""
        return cls(seq, frame, _M.MAV_CMD_NAV_LOITER_UNLIM, 0, 1, 0.0, 0.0, 0.0, 0.0, lat, lon, alt_m)

    @classmethod
    def from_message(cls, msg: MAVLinkMessage) -> MissionItem:
        """From a MISSION_ITEM_INT."""
        return cls(
            msg.seq, msg.frame, msg.command, msg.current, msg.autocontinue,
            msg.param1, msg.param2, msg.param3, msg.param4, msg.x / 1e7, msg.y / 1e7, msg.z, getattr(msg, "mission_type", _MISSION),
        )  # fmt: skip

    def encode(self, mav: mavlink.MAVLink, target_system: int, target_component: int) -> MAVLinkMessage:
        """As a MISSION_ITEM_INT from ``mav`` (an :func:`~executive.world.dialect.encoder`)."""
        return mav.mission_item_int_encode(
            target_system, target_component, self.seq, self.frame, self.command, self.current, self.autocontinue,
            self.param1, self.param2, self.param3, self.param4, round(self.x * 1e7), round(self.y * 1e7), self.z, self.mission_type,
        )  # fmt: skip


def waypoint_items(points: Iterable[Sequence[float]]) -> tuple[MissionItem, ...]:
    """NAV_WAYPOINT items numbered from 1 (0 is home), from ``(lat, lon)`` or ``(lat, lon, alt_m)`` points."""
    return tuple(MissionItem.waypoint(seq, *point) for seq, point in enumerate(points, start=1))


def _compared(sent: MissionItem, held: MissionItem) -> Iterator[tuple[str, float, float, float, str]]:
    """(field, sent, held, tolerance, format) for each field a vehicle must keep."""
    yield "command", sent.command, held.command, 0.0, "g"
    yield "frame", _SAME_FRAME.get(sent.frame, sent.frame), _SAME_FRAME.get(held.frame, held.frame), 0.0, "g"
    yield "autocontinue", sent.autocontinue, held.autocontinue, 0.0, "g"
    for name in ("param1", "param2", "param3", "param4"):
        value = getattr(sent, name)
        yield name, value, getattr(held, name), PARAM_RELATIVE_TOLERANCE * max(1.0, abs(value)), ".7g"
    yield "x (latitude)", sent.x, held.x, LATLON_TOLERANCE_DEG, ".7f"
    yield "y (longitude)", sent.y, held.y, LATLON_TOLERANCE_DEG, ".7f"
    yield "z (altitude)", sent.z, held.z, ALT_TOLERANCE_M, ".3f"


def first_mismatch(sent: Sequence[MissionItem], held: Sequence[MissionItem]) -> str | None:
    """How the items read back (``held``) first differ from those sent, beyond storage precision; None if they agree."""
    if len(sent) != len(held):
        return f"the vehicle holds {len(held)} items, {len(sent)} were sent"
    for a, b in zip(sent, held, strict=True):
        for name, want, got, tolerance, fmt in _compared(a, b):
            same = (math.isnan(want) and math.isnan(got)) or abs(want - got) <= tolerance * (1 + 1e-6)
            if not same:
                return f"item {a.seq} {name}: sent {want:{fmt}}, the vehicle holds {got:{fmt}}"
    return None


#: A sub's waypoint at the surface is given this far under it: ArduSub's do_nav_wp (ArduSub/commands_logic.cpp) takes an
#: altitude of 0 for "stay at the current depth", and an altitude above home must not be positive (start_command).
SURFACE_ITEM_DEPTH_M = 0.01


def item_altitude(wp: Waypoint) -> float:
    """A waypoint's altitude in its mission item (relative to home): a sub's depth leg at minus its depth (the surface just
    under it, :data:`SURFACE_ITEM_DEPTH_M`), else ``alt_m``."""
    if wp.depth_m is None and wp.control_mode != "depth":
        return wp.alt_m
    return -max(wp.depth_m or 0.0, SURFACE_ITEM_DEPTH_M)


def route_items(waypoints: Sequence[Waypoint]) -> tuple[MissionItem, ...]:
    """The mission items 1..n a route is uploaded as: a NAV_WAYPOINT per waypoint, a NAV_LOITER_UNLIM per sample point;
    a sub's at its depth (:func:`item_altitude`).

    A sample point is a stop that lasts as long as the sample: ArduRover drives to a NAV_LOITER_UNLIM and stops
    there (ModeAuto::do_nav_wp with always_stop_at_destination, so the waypoint before it is driven through toward it,
    and a boat loiters once there), and never completes it (verify_loiter_unlimited returns false: no
    MISSION_ITEM_REACHED), so the vehicle stays until the executive moves the mission on (Rover/mode_auto.cpp). A
    NAV_WAYPOINT's hold time (p1) would drive on after a fixed time whether the sample is done or not; NAV_DELAY
    likewise, and it has no location to stop at.
    """
    return tuple(
        (MissionItem.stop if wp.sample else MissionItem.waypoint)(seq, wp.lat, wp.lon, item_altitude(wp)) for seq, wp in enumerate(waypoints, start=1)
    )


def route_not_on_autopilot(waypoints: Sequence[Waypoint], held: Sequence[MissionItem] | None) -> str | None:
    """Why the autopilot's mission (``held``, ``/vehicle/mission_items``) is not ``waypoints``; None when it is."""
    if held is None:
        return "the autopilot's mission is not known yet"
    mismatch = first_mismatch(route_items(waypoints), held)
    return None if mismatch is None else f"the autopilot's mission differs ({mismatch})"


def horizon_span(count: int, leg: int, horizon: int) -> tuple[int, int]:
    """drive: auto: how many of a ``count``-waypoint route the autopilot must hold with leg ``leg`` under way, and the most it may:
    up to the current leg's waypoint, and ``horizon`` waypoints beyond it (the route's end sooner)."""
    return min(count, leg + 1), min(count, leg + 1 + horizon)


def horizon_not_on_autopilot(waypoints: Sequence[Waypoint], leg: int, horizon: int, held: Sequence[MissionItem] | None) -> str | None:
    """Why the autopilot's mission (``held``) is not the route's horizon: the route's first waypoints, through the current leg's
    at least and ``horizon`` beyond it at most; None when it is."""
    if held is None:
        return "the autopilot's mission is not known yet"
    least, most = horizon_span(len(waypoints), leg, horizon)
    if not least <= len(held) <= most:
        return f"the vehicle holds {len(held)} items, {least}-{most} are the horizon of leg {leg + 1}"
    mismatch = first_mismatch(route_items(waypoints[: len(held)]), held)
    return None if mismatch is None else f"the autopilot's mission differs ({mismatch})"


class _Step(Enum):
    IDLE = "idle"
    SEND_COUNT = "count sent, waiting for the first request"
    SEND_ITEMS = "answering item requests"
    REQUEST_LIST = "list requested, waiting for the count"
    REQUEST_ITEMS = "requesting items"
    CLEAR = "clear sent"
    SET_CURRENT = "set-current sent"


_UPLOADING = (_Step.SEND_COUNT, _Step.SEND_ITEMS)
_DOWNLOADING = (_Step.REQUEST_LIST, _Step.REQUEST_ITEMS)


class MissionTransfer:
    """Moves the mission to and from the autopilot over the MAVLink mission protocol, one transfer at a time.

    Drive it like the :class:`~executive.io.mavlink.commander.Commander`: the reader hands it the
    MISSION_* messages (``on_*``), the runtime calls :meth:`flush` after each drain or tick.
    """

    def __init__(
        self,
        link: Link,
        clock: Clock,
        *,
        system_id: int = 1,
        component_id: int = EXECUTIVE_COMPONENT,
        item_timeout_s: float = 1.5,  # longer than ArduPilot's own 1 s re-request: its re-request usually comes first
        retries: int = 5,
        verify: bool = True,
    ) -> None:
        self._link = link
        self._clock = clock
        self._system_id = system_id
        self._component_id = component_id
        self._mav = encoder(system_id, component_id)
        self._timeout_s = item_timeout_s
        self._retries = retries
        self.verify = verify
        self._bb = blackboard.writer("mission transfer", MISSION_KEYS)
        self.target_system = 1
        self.target_component = 1
        self._tickets = itertools.count(1)
        self._status: MissionTransferStatus | None = None
        self._step = _Step.IDLE
        self._outbox: list[MAVLinkMessage] = []
        self._last: MAVLinkMessage | None = None  # what a timeout resends
        self._awaiting = ""  # the reply we wait for, to say what never came
        self._deadline = math.inf
        self._timeouts = 0  # in a row, without a word from the vehicle
        #: Item 0 is home (ArduPilot); PX4 flies item 0 as the first item (its mission has no home slot). The autopilot port sets it.
        self.home_slot = True
        self._type = _MISSION  # the MAV_MISSION_TYPE of the transfer in progress (or the last one)
        self._upload: tuple[MissionItem, ...] = ()  # home first, with a home slot
        self._verify_upload = verify
        self._final_item_sent = False
        self._partial_end: int | None = None  # an append's partial write under way: its item; None: an upload
        self._last_item_seq = 0
        self._count = 0
        self._received: list[MissionItem] = []
        self._wanted_current = 0
        self.home: MissionItem | None = None
        self.items: tuple[MissionItem, ...] | None = None
        self._reached: MissionItemReached | None = None  # latched: the highest item reached since the mission changed

    # -- requests (from behaviours; never block) ---------------------------------------------
    def upload(
        self, items: Iterable[MissionItem], home: Sequence[float] | None = None, *, verify: bool | None = None, mission_type: int = _MISSION
    ) -> int:
        """Replace the vehicle's mission with ``items`` (renumbered from 1) after a home item 0 at ``home`` (lat, lon[, alt]).

        ArduPilot reports its own home as item 0 whatever is uploaded there, so ``home`` may stay
        None (a placeholder). With ``verify`` (default: the instance's), the mission is read back
        and compared item by item before the upload counts as DONE. ``mission_type`` FENCE or RALLY
        replaces the fence or the rally points instead, numbered from 0 (no home item). Returns the ticket.
        """
        items = tuple(replace(item, mission_type=mission_type) for item in items)
        if self.home_slot and mission_type == _MISSION:
            lat, lon, alt = (*home, 0.0)[:3] if home else (0.0, 0.0, 0.0)
            home_item = MissionItem(0, _M.MAV_FRAME_GLOBAL, _M.MAV_CMD_NAV_WAYPOINT, 0, 1, 0.0, 0.0, 0.0, 0.0, lat, lon, alt)
            self._upload = (home_item, *(replace(item, seq=seq) for seq, item in enumerate(items, start=1)))
        else:  # no home slot: the items from 0 (``home`` is the autopilot's own business)
            self._upload = tuple(replace(item, seq=seq) for seq, item in enumerate(items))
        self._verify_upload = self.verify if verify is None else verify
        # an empty list is its count alone: ArduPilot answers a MISSION_COUNT of 0 with MISSION_ACK ACCEPTED at once
        # (GCS_MAVLink/MissionItemProtocol.cpp handle_mission_count: "if (packet.count == 0) ... send_mission_ack")
        self._final_item_sent = not self._upload
        self._partial_end = None
        ticket = self._start(TransferOperation.UPLOAD, len(self._upload), mission_type)
        self._step = _Step.SEND_COUNT
        count = self._mav.mission_count_encode(self.target_system, self.target_component, len(self._upload), mission_type)
        self._send(count, "MISSION_REQUEST for item 0")
        return ticket

    def append(self, items: Sequence[MissionItem]) -> int:
        """Add ``items`` after the mission the vehicle holds (as last read back), leaving the rest as it is; returns the ticket.

        A partial write (MISSION_WRITE_PARTIAL_LIST from the end to the end) per item, one after the
        other: ArduPilot takes one whose indices are at most its item count, and an item whose seq is
        that count is appended (MissionItemProtocol::handle_mission_write_partial_list and
        handle_mission_item, libraries/GCS_MAVLink/MissionItemProtocol.cpp), so a mission running in
        AUTO goes on with more items and nothing else rewritten. The partial writes follow each other at
        once (their acks), so that ArduRover, which restarts its current waypoint at each write,
        restarts it in one burst. Read back whole before it counts, as an upload.
        """
        if self.items is None:
            raise RuntimeError("append needs the vehicle's mission read back first")
        if not items:
            raise ValueError("nothing to append")
        first = 1 if self.home_slot else 0  # the flight plan's (``_first`` is the last transfer's type's)
        home = (self.home or MissionItem.waypoint(0, 0.0, 0.0),) if self.home_slot else ()
        held = tuple(replace(held, seq=seq) for seq, held in enumerate(self.items, start=first))
        seq = first + len(held)
        self._upload = (*home, *held, *(replace(item, seq=n) for n, item in enumerate(items, start=seq)))
        self._verify_upload = True
        ticket = self._start(TransferOperation.UPLOAD, len(self._upload))
        self._write_partial(seq)
        return ticket

    def _write_partial(self, seq: int) -> None:
        """Start the partial write of item ``seq`` of the upload (an append: ``seq`` is the vehicle's count)."""
        self._final_item_sent = False
        self._partial_end = seq
        self._step = _Step.SEND_COUNT
        partial = self._mav.mission_write_partial_list_encode(self.target_system, self.target_component, seq, seq, _MISSION)
        self._send(partial, f"MISSION_REQUEST for item {seq}")

    def download(self, mission_type: int = _MISSION) -> int:
        """Read the vehicle's mission into ``/vehicle/mission_home`` and ``/vehicle/mission_items`` (its fence or rally points into
        ``/vehicle/fence_items``, ``/vehicle/rally_items``); returns the ticket."""
        ticket = self._start(TransferOperation.DOWNLOAD, 0, mission_type)
        self._request_list()
        return ticket

    def clear(self) -> int:
        """Delete the vehicle's mission (ArduPilot refuses while it runs one armed); returns the ticket."""
        ticket = self._start(TransferOperation.CLEAR, 0)
        self._step = _Step.CLEAR
        self._send(self._mav.mission_clear_all_encode(self.target_system, self.target_component, _MISSION), "MISSION_ACK to MISSION_CLEAR_ALL")
        return ticket

    def set_current(self, seq: int) -> int:
        """Make item ``seq`` the one the mission goes to next; returns the ticket.

        MISSION_SET_CURRENT has no ack: a MISSION_CURRENT carrying ``seq`` confirms it, and
        ArduPilot ignores a seq it does not hold (the transfer then fails after its retries).
        """
        ticket = self._start(TransferOperation.SET_CURRENT, 1)
        self._step = _Step.SET_CURRENT
        self._wanted_current = seq
        self._send(self._mav.mission_set_current_encode(self.target_system, self.target_component, seq), f"MISSION_CURRENT with seq {seq}")
        return ticket

    @property
    def status(self) -> MissionTransferStatus | None:
        """The latest transfer's status (also on ``/link/mission_transfer``)."""
        return self._status

    @property
    def idle(self) -> bool:
        """No transfer in progress."""
        return self._step is _Step.IDLE

    # -- IO side (the reader and the runtime) -------------------------------------------------
    def flush(self) -> int:
        """Send what is due: new messages, and the last one again when its reply is late. Returns messages sent."""
        now = self._clock.now()
        if self._step is not _Step.IDLE and not self._outbox and now >= self._deadline and self._status is not None:
            if self._timeouts >= self._retries:
                self._fail(f"no {self._awaiting} after {self._retries} retries", now)
            elif self._last is not None:
                self._timeouts += 1
                self._outbox.append(self._last)
                self._publish(now, retries=self._status.retries + 1)
        sent = len(self._outbox)
        for msg in self._outbox:
            self._link.send(msg)
        self._outbox.clear()
        if sent and self._step is not _Step.IDLE:
            self._deadline = now + self._timeout_s
        return sent

    def on_request(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_REQUEST_INT or MISSION_REQUEST: the vehicle asks for an item of the upload."""
        if self._step not in _UPLOADING or not self._for_us(msg) or self._status is None:
            return
        seq = msg.seq
        if seq >= len(self._upload):
            log.warning("the vehicle asked for item %d of a %d-item upload", seq, len(self._upload))
            return
        self._step = _Step.SEND_ITEMS
        self._timeouts = 0
        if not any(m.get_type() == "MISSION_ITEM_INT" and m.seq == seq for m in self._outbox):
            last = seq == (len(self._upload) - 1 if self._partial_end is None else self._partial_end)
            self._final_item_sent = self._final_item_sent or last
            self._last_item_seq = seq
            item = self._upload[seq].encode(self._mav, self.target_system, self.target_component)
            self._send(item, "MISSION_ACK" if last else f"MISSION_REQUEST for item {seq + 1}")
        if seq > self._status.progress:
            self._publish(now, progress=seq)

    def on_ack(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_ACK: the end of an upload or a clear, or the vehicle's refusal."""
        if self._step is _Step.IDLE or not self._for_us(msg):
            return
        result, name = msg.type, mission_result_name(msg.type)
        if self._step in _UPLOADING:
            if result == _M.MAV_MISSION_ACCEPTED:
                if self._final_item_sent:  # else a stale ack (of an earlier clear, say)
                    self._written(now)
            elif result == _M.MAV_MISSION_INVALID_SEQUENCE:
                pass  # a resent or reordered item arrived after the vehicle moved on; it re-requests what it lacks
            elif result == _M.MAV_MISSION_ERROR and self._final_item_sent and self._verify_upload:
                # ArduPilot answers an item with ERROR once it stopped receiving: its ACCEPTED may have been lost
                self._written(now)
            elif result == _M.MAV_MISSION_ERROR and self._final_item_sent:
                self._fail(f"the vehicle answered the last item with {name}: its MISSION_ACK may have been lost; download to check", now, result)
            else:
                where = f" at item {self._last_item_seq}" if self._step is _Step.SEND_ITEMS else ""
                self._fail(f"the vehicle refused the upload{where}: {name}", now, result)
        elif self._step in _DOWNLOADING:
            # ERROR and INVALID_SEQUENCE may answer an upload's duplicate items late; a request out of
            # range gets ERROR too, but with a MISSION_COUNT, which on_count checks
            if result not in (_M.MAV_MISSION_ACCEPTED, _M.MAV_MISSION_ERROR, _M.MAV_MISSION_INVALID_SEQUENCE):
                what = "the read-back" if self._status is not None and self._status.verifying else "the download"
                self._fail(f"the vehicle refused {what}: {name}", now, result)
        elif self._step is _Step.CLEAR:
            if result == _M.MAV_MISSION_ACCEPTED:
                self._hold(self.home, ())
                self._finish(now, result)
            else:
                self._fail(f"the vehicle refused to clear its mission: {name}", now, result)

    def on_count(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_COUNT: how many items (home included) a download will bring."""
        if self._step not in _DOWNLOADING or not self._for_us(msg):
            return
        if self._step is _Step.REQUEST_ITEMS:
            if msg.count != self._count:  # ArduPilot's answer to a request beyond its mission
                self._fail(f"the mission changed during the download: {msg.count} items, not {self._count}", now)
            return  # else the answer to a resent MISSION_REQUEST_LIST
        self._timeouts = 0
        self._count = msg.count
        self._received = []
        self._publish(now, total=msg.count, progress=0)
        if msg.count == 0:
            self._downloaded(now)
        else:
            self._step = _Step.REQUEST_ITEMS
            self._request_item(0)

    def on_item(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_ITEM_INT: the item a download asked for (others are duplicates, dropped)."""
        if self._step is not _Step.REQUEST_ITEMS or not self._for_us(msg) or msg.seq != len(self._received):
            return
        self._timeouts = 0
        self._received.append(MissionItem.from_message(msg))
        self._publish(now, progress=len(self._received))
        if len(self._received) < self._count:
            self._request_item(len(self._received))
            return
        # the spec's closing ack: the vehicle sends nothing back, so it is sent once, without retries
        self._outbox.append(self._mav.mission_ack_encode(self.target_system, self.target_component, _M.MAV_MISSION_ACCEPTED, self._type))
        self._downloaded(now)

    def on_current(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_CURRENT (streamed, and the reply to MISSION_SET_CURRENT)."""
        # total, mission_state and mission_mode are MAVLink 2 extensions: 0 from firmware that predates them
        current = MissionCurrent(msg.seq, getattr(msg, "total", 0), getattr(msg, "mission_state", 0), bool(getattr(msg, "mission_mode", 0)), now)
        self._bb.set("/vehicle/mission_current", current)
        if self._step is _Step.SET_CURRENT and msg.seq == self._wanted_current:
            self._finish(now, None)

    def on_reached(self, msg: MAVLinkMessage, now: float) -> None:
        """MISSION_ITEM_REACHED."""
        before = self._reached
        self._reached = MissionItemReached(msg.seq, now, max(msg.seq, before.highest if before else -1))
        self._bb.set("/vehicle/mission_reached", self._reached)

    # -- internals ---------------------------------------------------------------------------
    def _for_us(self, msg: MAVLinkMessage) -> bool:
        """Addressed to us (or to everyone) and about the mission type of the transfer in progress."""
        return (
            getattr(msg, "target_system", 0) in (0, self._system_id)
            and getattr(msg, "target_component", 0) in (0, self._component_id)
            and getattr(msg, "mission_type", _MISSION) == self._type
        )

    def _start(self, operation: TransferOperation, total: int, mission_type: int = _MISSION) -> int:
        now = self._clock.now()
        if self._step is not _Step.IDLE:
            self._fail(f"superseded by a {operation.lower().replace('_', '-')} request", now)
        self._type = mission_type
        # a download's closing MISSION_ACK still goes: PX4 stays busy with the list it sent until it comes (mavlink_mission.cpp)
        self._outbox[:] = [msg for msg in self._outbox if msg.get_type() == "MISSION_ACK"]
        self._timeouts = 0
        self._deadline = math.inf
        ticket = next(self._tickets)
        self._status = MissionTransferStatus(ticket, operation, TransferState.IN_PROGRESS, 0, total, "", None, 0, False, now, self._type)
        self._bb.set("/link/mission_transfer", self._status)
        return ticket

    def _send(self, msg: MAVLinkMessage, awaiting: str) -> None:
        self._outbox.append(msg)
        self._last = msg
        self._awaiting = awaiting

    def _request_list(self) -> None:
        self._step = _Step.REQUEST_LIST
        self._send(self._mav.mission_request_list_encode(self.target_system, self.target_component, self._type), "MISSION_COUNT")

    def _request_item(self, seq: int) -> None:
        self._send(self._mav.mission_request_int_encode(self.target_system, self.target_component, seq, self._type), f"MISSION_ITEM_INT {seq}")

    def _written(self, now: float) -> None:
        """The vehicle took the last item sent: the next partial write of an append, or the upload is done."""
        if self._partial_end is not None and self._partial_end + 1 < len(self._upload):
            self._write_partial(self._partial_end + 1)
            return
        self._uploaded(now)

    def _uploaded(self, now: float) -> None:
        if not self._verify_upload:
            self._hold(self.home if self._home_slot else None, self._upload[self._first :])
            self._finish(now, _M.MAV_MISSION_ACCEPTED)
            return
        self._publish(now, verifying=True, progress=0)
        self._request_list()

    def _downloaded(self, now: float) -> None:
        if self._home_slot:
            home, items = (self._received[0] if self._received else None), tuple(self._received[1:])
        else:
            home, items = None, tuple(self._received)
        self._hold(home, items)
        if self._status is not None and self._status.verifying:
            mismatch = first_mismatch(self._upload[self._first :], items)
            if mismatch is not None:
                self._fail(f"read-back mismatch: {mismatch}", now)
                return
        self._finish(now, None)

    @property
    def _home_slot(self) -> bool:
        """The transfer in progress has a home item 0: the flight plan on a firmware with a home slot (never the fence or rally points)."""
        return self.home_slot and self._type == _MISSION

    @property
    def _first(self) -> int:
        """The seq of the first mission item: 1 after a home slot, else 0."""
        return 1 if self._home_slot else 0

    def _hold(self, home: MissionItem | None, items: tuple[MissionItem, ...]) -> None:
        """What the vehicle holds, as far as we know; another mission's reports of items reached say nothing about this one
        (the same mission with items appended is this one)."""
        if self._type != _MISSION:
            self._bb.set(_HELD_KEY[self._type], items)
            return
        if self.items is None or first_mismatch(self.items, items[: len(self.items)]) is not None:
            self._reached = None
            self._bb.set("/vehicle/mission_reached", None)
        self.home, self.items = home, items
        self._bb.set("/vehicle/mission_home", home)
        self._bb.set("/vehicle/mission_items", items)

    def _finish(self, now: float, result: int | None) -> None:
        self._step = _Step.IDLE
        self._deadline = math.inf
        if self._status is not None:
            self._publish(now, state=TransferState.DONE, progress=self._status.total, result=result, verifying=False)

    def _fail(self, reason: str, now: float, result: int | None = None) -> None:
        self._step = _Step.IDLE
        self._deadline = math.inf
        if self._status is not None:
            log.warning("%s %s failed: %s", MISSION_TYPE_NAMES.get(self._type, "mission"), self._status.operation.lower(), reason)
            self._publish(now, state=TransferState.FAILED, reason=reason, result=result, verifying=False)

    def _publish(self, now: float, **changes: Any) -> None:
        if self._status is None:
            return
        self._status = replace(self._status, time=now, **changes)
        self._bb.set("/link/mission_transfer", self._status)
