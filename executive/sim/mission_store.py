"""ArduPilot's mission in the simulated autopilot: the stored items, the vehicle's side of the mission protocol, the item AUTO is on.

It follows the firmware (GCS_MAVLink/MissionItemProtocol*.cpp, AP_Mission) where it differs from the spec:

- item 0 is home: reading item 0 always gives the vehicle's current home, whatever was uploaded there;
- the vehicle drives an upload with MISSION_REQUEST (ArduPilot kept the non-INT request; ground
  stations answer with MISSION_ITEM_INT); an item other than the one requested gets MISSION_ACK
  INVALID_SEQUENCE and changes nothing; the vehicle asks again after 1 s without the item and
  cancels the upload (OPERATION_CANCELLED) after 8 s;
- MISSION_COUNT cuts the mission to the new count at once and items replace the old ones as they
  arrive, so a failed upload leaves a mixed mission;
- items are kept as ArduPilot keeps them: latitude and longitude in 1e-7 degree, altitude in whole
  centimetres, a NAV_WAYPOINT's hold time in whole seconds and none of its other parameters, and
  frames read back in their non-INT form;
- MISSION_SET_CURRENT has no ack: a MISSION_CURRENT echoing the seq confirms it, an item the vehicle
  does not hold is ignored.

Only the flight plan is stored (no fence, no rally points), and MISSION_ITEM / MISSION_REQUEST
from a ground station (the float forms) are not handled.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import ClassVar, Protocol

from executive.clock import Clock
from executive.io.mavlink.dialect import MAVLinkMessage, encoder, mavlink

_M = mavlink
_MISSION = _M.MAV_MISSION_TYPE_MISSION
LOCATION_ALT_MAX_M = 83_000  # what a Location's altitude in cm can hold

#: Commands stored with a location (as AP_Mission::stored_in_location); AUTO drives to NAV_WAYPOINTs.
LOCATION_COMMANDS = frozenset({_M.MAV_CMD_NAV_WAYPOINT, _M.MAV_CMD_NAV_LOITER_UNLIM, _M.MAV_CMD_NAV_LOITER_TIME, _M.MAV_CMD_DO_SET_HOME})
#: Commands the store accepts (others get MAV_MISSION_UNSUPPORTED); AUTO passes over all but NAV_WAYPOINT.
KNOWN_COMMANDS = LOCATION_COMMANDS | {_M.MAV_CMD_NAV_RETURN_TO_LAUNCH, _M.MAV_CMD_DO_CHANGE_SPEED, _M.MAV_CMD_DO_JUMP, _M.MAV_CMD_CONDITION_DELAY}

# the frame an item is read back in, per uploaded frame
_READ_BACK_FRAME = {
    _M.MAV_FRAME_MISSION: _M.MAV_FRAME_GLOBAL,
    _M.MAV_FRAME_GLOBAL: _M.MAV_FRAME_GLOBAL,
    _M.MAV_FRAME_GLOBAL_INT: _M.MAV_FRAME_GLOBAL,
    _M.MAV_FRAME_GLOBAL_RELATIVE_ALT: _M.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: _M.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    _M.MAV_FRAME_GLOBAL_TERRAIN_ALT: _M.MAV_FRAME_GLOBAL_TERRAIN_ALT,
    _M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: _M.MAV_FRAME_GLOBAL_TERRAIN_ALT,
}
_INVALID_PARAM = (_M.MAV_MISSION_INVALID_PARAM1, _M.MAV_MISSION_INVALID_PARAM2, _M.MAV_MISSION_INVALID_PARAM3, _M.MAV_MISSION_INVALID_PARAM4)


@dataclass(frozen=True, slots=True)
class StoredCommand:
    """A mission command as ArduPilot stores it."""

    command: int
    params: tuple[float, float, float, float]
    lat_e7: int
    lon_e7: int
    alt_cm: int
    frame: int  # the frame it is read back in

    @property
    def lat(self) -> float:
        return self.lat_e7 * 1e-7

    @property
    def lon(self) -> float:
        return self.lon_e7 * 1e-7


def to_stored(msg: MAVLinkMessage) -> StoredCommand | int:
    """A MISSION_ITEM_INT as ArduPilot would store it, or the MAV_MISSION_RESULT refusing it."""
    params = (msg.param1, msg.param2, msg.param3, msg.param4)
    for i, value in enumerate(params):
        if math.isnan(value) and not (i == 3 and msg.command == _M.MAV_CMD_NAV_WAYPOINT):  # a waypoint's yaw may be NaN
            return _INVALID_PARAM[i]
    if msg.command not in KNOWN_COMMANDS:
        return _M.MAV_MISSION_UNSUPPORTED
    if msg.command == _M.MAV_CMD_NAV_WAYPOINT:
        params = (float(max(0, min(int(msg.param1), 0xFFFF))), 0.0, 0.0, 0.0)  # only the hold time, in a uint16 of seconds
    if msg.command not in LOCATION_COMMANDS:
        return StoredCommand(msg.command, params, 0, 0, 0, _M.MAV_FRAME_GLOBAL)
    if abs(msg.x) > 90 * 10**7:
        return _M.MAV_MISSION_INVALID_PARAM5_X
    if abs(msg.y) > 180 * 10**7:
        return _M.MAV_MISSION_INVALID_PARAM6_Y
    if math.isnan(msg.z) or abs(msg.z) >= LOCATION_ALT_MAX_M:
        return _M.MAV_MISSION_INVALID_PARAM7
    if msg.frame not in _READ_BACK_FRAME:
        return _M.MAV_MISSION_UNSUPPORTED_FRAME
    return StoredCommand(msg.command, params, msg.x, msg.y, int(msg.z * 100), _READ_BACK_FRAME[msg.frame])


class MissionState(Enum):
    """AP_Mission's state."""

    STOPPED = "stopped"
    RUNNING = "running"
    COMPLETE = "complete"


class MissionOwner(Protocol):
    """What the store needs from its autopilot."""

    clock: Clock
    system_id: int
    component_id: int
    home: tuple[float, float] | None
    armed: bool
    mode: str


class MissionStore:
    """The mission of a simulated ArduPilot and its side of the mission protocol.

    :meth:`handle` takes the MISSION_* messages in :attr:`MESSAGES`; :meth:`update`, called as time
    passes, asks again for a late item and cancels a stalled upload. Replies and STATUSTEXTs go out
    through ``emit`` and ``text``. AUTO steps through the mission with :meth:`start_or_resume`,
    :attr:`current` and :meth:`advance`.
    """

    MESSAGES: ClassVar[frozenset[str]] = frozenset(
        {"MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_REQUEST_LIST", "MISSION_REQUEST_INT", "MISSION_CLEAR_ALL", "MISSION_SET_CURRENT"}
    )
    HOME_SLOT: ClassVar[bool] = True  # item 0 is home (ArduPilot); the mission proper starts at 1
    AUTO_MODE: ClassVar[str] = "AUTO"  # the mode that runs the mission (MISSION_CURRENT mission_mode)
    RE_REQUEST_S = 1.0  # MissionItemProtocol: ask again for an item after this long without it
    UPLOAD_TIMEOUT_S = 8.0  # ... and give up on the upload after this long
    MAX_ITEMS = 700  # depends on the board's storage

    def __init__(
        self, owner: MissionOwner, emit: Callable[[MAVLinkMessage], None], text: Callable[[int, str], None], *, max_items: int = MAX_ITEMS
    ) -> None:
        self._owner = owner
        self._emit = emit
        self._text = text
        self._mav = encoder(owner.system_id, owner.component_id)
        self.max_items = max_items
        self._commands: list[StoredCommand] = []  # [0] is the home slot, read back as the current home
        self.state = MissionState.STOPPED
        self.current_seq: int | None = None  # the item AUTO is on (or starts from); None = from the first
        self.receiving = False  # an upload is under way
        self._request_i = self._request_last = 0
        self._uploader = (0, 0)  # system and component id of whoever uploads
        self._last_item_at = self._last_request_at = 0.0
        self.uploaded_at: float | None = None  # clock time of the last completed upload
        self._handlers: dict[str, Callable[[MAVLinkMessage], None]] = {
            "MISSION_COUNT": self._on_count,
            "MISSION_ITEM_INT": self._on_item,
            "MISSION_REQUEST_LIST": self._on_request_list,
            "MISSION_REQUEST_INT": self._on_request_int,
            "MISSION_CLEAR_ALL": self._on_clear_all,
            "MISSION_SET_CURRENT": self._on_set_current,
        }

    @property
    def count(self) -> int:
        """Items held, home included (what MISSION_COUNT says)."""
        return len(self._commands)

    @property
    def first_item(self) -> int:
        """The seq of the mission's first item: 1 after a home slot, else 0."""
        return 1 if self.HOME_SLOT else 0

    @property
    def present(self) -> bool:
        """There is a mission: something after home."""
        return self.count > self.first_item

    @property
    def running(self) -> bool:
        return self.state is MissionState.RUNNING

    def command(self, seq: int) -> StoredCommand:
        """Item ``seq`` as it would be read back (item 0: the current home)."""
        if seq == 0 and self.HOME_SLOT:
            lat, lon = self._owner.home or (0.0, 0.0)
            return StoredCommand(_M.MAV_CMD_NAV_WAYPOINT, (0.0, 0.0, 0.0, 0.0), round(lat * 1e7), round(lon * 1e7), 0, _M.MAV_FRAME_GLOBAL)
        return self._commands[seq]

    # -- the protocol ----------------------------------------------------------------------------

    def handle(self, msg: MAVLinkMessage) -> None:
        """React to one MISSION_* message (see :attr:`MESSAGES`); replies go out through ``emit``."""
        handler = self._handlers.get(msg.get_type())
        if handler is None:
            return
        if getattr(msg, "mission_type", _MISSION) != _MISSION:
            self._ack(msg, _M.MAV_MISSION_UNSUPPORTED)  # no fence or rally points in the sim
            return
        handler(msg)

    def update(self) -> None:
        """Time passed: ask again for a late item, or cancel an upload that stalled."""
        if not self.receiving:
            return
        now = self._owner.clock.now()
        if now - self._last_item_at > self.UPLOAD_TIMEOUT_S:
            self.receiving = False
            self._text(_M.MAV_SEVERITY_WARNING, "Mission upload timeout")
            self._emit(self._mav.mission_ack_encode(*self._uploader, _M.MAV_MISSION_OPERATION_CANCELLED, _MISSION))
        elif now - self._last_request_at > self.RE_REQUEST_S:
            self._request()

    def _ack(self, msg: MAVLinkMessage, result: int) -> None:
        self._emit(self._mav.mission_ack_encode(msg.get_srcSystem(), msg.get_srcComponent(), result, _MISSION))

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        """An uploaded item as this firmware stores it, or the MAV_MISSION_RESULT refusing it."""
        return to_stored(msg)

    def _request(self) -> None:
        self._last_request_at = self._owner.clock.now()
        self._emit(self._mav.mission_request_encode(*self._uploader, self._request_i, _MISSION))

    def _received(self) -> None:
        """An upload completed (ArduPilot says so in a STATUSTEXT)."""
        self._text(_M.MAV_SEVERITY_INFO, "Flight plan received")

    def _on_count(self, msg: MAVLinkMessage) -> None:
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if self.receiving and sender != self._uploader:
            self._ack(msg, _M.MAV_MISSION_DENIED)  # one uploader at a time; the same one may start over
            return
        if msg.count > self.max_items:
            self._ack(msg, _M.MAV_MISSION_NO_SPACE)
            self._text(_M.MAV_SEVERITY_WARNING, f"Only {self.max_items} items are supported")
            return
        del self._commands[msg.count :]
        self._uploader = sender
        if msg.count == 0:
            self._upload_complete(msg)
            return
        self.receiving = True
        self._request_i, self._request_last = 0, msg.count - 1
        self._last_item_at = self._owner.clock.now()
        self._request()

    def _on_item(self, msg: MAVLinkMessage) -> None:
        if not self.receiving:
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        if msg.seq != self._request_i:
            self._ack(msg, _M.MAV_MISSION_INVALID_SEQUENCE)
            return
        if (msg.get_srcSystem(), msg.get_srcComponent()) != self._uploader:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        stored = self._to_stored(msg)
        if isinstance(stored, StoredCommand) and msg.seq <= self.count:
            self._commands[msg.seq : msg.seq + 1] = [stored]
        else:
            self._ack(msg, stored if isinstance(stored, int) else _M.MAV_MISSION_ERROR)
            self.receiving = False
            return
        self._last_item_at = self._owner.clock.now()
        self._request_i += 1
        if self._request_i > self._request_last:
            self._upload_complete(msg)
        else:
            self._request()

    def _upload_complete(self, msg: MAVLinkMessage) -> None:
        self.receiving = False
        self.uploaded_at = self._owner.clock.now()
        self._received()
        self._ack(msg, _M.MAV_MISSION_ACCEPTED)

    def _on_request_list(self, msg: MAVLinkMessage) -> None:
        if self.receiving:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        self._emit(self._mav.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(), self.count, _MISSION))

    def _on_request_int(self, msg: MAVLinkMessage) -> None:
        if self.receiving:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        if (msg.seq != 0 or not self.HOME_SLOT) and msg.seq >= self.count:  # home can always be read
            self._emit(self._mav.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(), self.count, _MISSION))  # the real size
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        cmd = self.command(msg.seq)
        current = int(msg.seq != 0 and msg.seq == self.current_seq)
        self._emit(
            self._mav.mission_item_int_encode(
                msg.get_srcSystem(), msg.get_srcComponent(), msg.seq, cmd.frame, cmd.command, current, 1,
                *cmd.params, cmd.lat_e7, cmd.lon_e7, cmd.alt_cm / 100.0, _MISSION,
            )
        )  # fmt: skip

    def _on_clear_all(self, msg: MAVLinkMessage) -> None:
        if self.receiving or (self.running and self._owner.armed):
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        self._commands.clear()
        self.state, self.current_seq = MissionState.STOPPED, None
        self._ack(msg, _M.MAV_MISSION_ACCEPTED)

    def _on_set_current(self, msg: MAVLinkMessage) -> None:
        if self.set_current(msg.seq):
            # ground stations take the echo of their seq as the ack, even 0 (home), which the vehicle never holds
            self._emit(self.current_message(msg.seq))

    def command_set_current(self, seq: float, reset: float) -> int:
        """MAV_CMD_DO_SET_MISSION_CURRENT: param1 the item, param2 1 to reset a completed mission too; a MAV_RESULT."""
        if reset == 1.0 and self.state is MissionState.COMPLETE:
            self.state = MissionState.STOPPED
        if not self.set_current(int(seq)):
            return _M.MAV_RESULT_FAILED
        self._emit(self.current_message())
        return _M.MAV_RESULT_ACCEPTED

    # -- execution (AUTO) ------------------------------------------------------------------------

    def set_current(self, seq: int) -> bool:
        """Make item ``seq`` the one to execute next (0 means the first); False, changing nothing, if there is no such item."""
        if not self.present or seq >= self.count:
            return False
        self.current_seq = max(seq, self.first_item)
        if self.state is MissionState.COMPLETE:
            self.state = MissionState.STOPPED
        return True

    def start_or_resume(self) -> None:
        """AUTO runs the mission from its current item (MIS_RESTART=0); a completed one starts over."""
        if not self.present:
            return
        if self.state is MissionState.COMPLETE or self.current_seq is None or self.current_seq >= self.count:
            self.current_seq = self.first_item
        self.state = MissionState.RUNNING

    def stop(self) -> None:
        """Leaving AUTO: the mission stops where it is, to resume there."""
        if self.running:
            self.state = MissionState.STOPPED

    @property
    def current(self) -> StoredCommand | None:
        """The item being executed, while the mission runs."""
        if not self.running or self.current_seq is None or self.current_seq >= self.count:
            return None
        return self._commands[self.current_seq]

    def next_nav_after(self, seq: int) -> StoredCommand | None:
        """The navigation command after item ``seq`` (AP_Mission::get_next_nav_cmd), if it has a location; None at the end.

        A DO_JUMP on the way ends the look-ahead here (the vehicle then stops at ``seq``: the jump is not followed).
        """
        for cmd in self._commands[seq + 1 :]:
            if cmd.command == _M.MAV_CMD_DO_JUMP:
                return None
            if cmd.command < _M.MAV_CMD_NAV_LAST:
                return cmd if cmd.command in LOCATION_COMMANDS else None
        return None

    def advance(self) -> StoredCommand | None:
        """The current item is done: MISSION_ITEM_REACHED, then the next item, or None (and "Mission Complete") after the last."""
        if self.current_seq is None or not self.running:
            return None
        self._emit(self._mav.mission_item_reached_encode(self.current_seq))
        if self.current_seq + 1 < self.count:
            self.current_seq += 1
            return self._commands[self.current_seq]
        self.state = MissionState.COMPLETE
        self._completed()
        return None

    def _completed(self) -> None:
        """The last item is done (ArduPilot says so in a STATUSTEXT)."""
        self._text(_M.MAV_SEVERITY_NOTICE, "Mission Complete")

    def current_message(self, seq: int | None = None) -> MAVLinkMessage:
        """MISSION_CURRENT as ArduPilot streams it; ``seq`` replaces the item (to echo MISSION_SET_CURRENT)."""
        if not self.present:
            state = _M.MISSION_STATE_NO_MISSION
        else:
            state = {
                MissionState.STOPPED: _M.MISSION_STATE_NOT_STARTED,
                MissionState.RUNNING: _M.MISSION_STATE_ACTIVE,
                MissionState.COMPLETE: _M.MISSION_STATE_COMPLETE,
            }[self.state]
        seq = (self.current_seq or 0) if seq is None else seq
        total = max(self.count - self.first_item, 0)
        return self._mav.mission_current_encode(seq, total, state, int(self._owner.mode == self.AUTO_MODE))
