"""The mission in a simulated autopilot: the stored items, the vehicle's side of the mission protocol, the item the mission is on.

What every firmware's store does alike: MISSION_COUNT / MISSION_ITEM_INT uploads driven by the vehicle
(asked again after 1 s without the item, cancelled after 8 s), MISSION_REQUEST_LIST / MISSION_REQUEST_INT
downloads, MISSION_CLEAR_ALL, MISSION_SET_CURRENT (answered by a MISSION_CURRENT echoing the seq), the
mission's state and current item. A firmware's subclass says how it stores an item, how it asks for
one, whether item 0 is home, and what it says on an upload and at the end:
:class:`~executive.sim.ardupilot.mission_store.ArduPilotMissionStore`,
:class:`~executive.sim.px4.mission_store.Px4MissionStore`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import ClassVar, Protocol

from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, encoder, mavlink

_M = mavlink
_MISSION = _M.MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True, slots=True)
class StoredCommand:
    """A mission command as the simulated autopilot stores it."""

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


class AutopilotMissionState(Enum):
    """The simulated autopilot's own mission run (AP_Mission's state, MISSION_CURRENT ``mission_state``).

    Not the executive's mission lifecycle (:class:`executive.mission.lifecycle.MissionState`).
    """

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


class MissionStore(ABC):
    """The mission of a simulated autopilot and its side of the mission protocol (a firmware's subclass stores and asks its way).

    :meth:`handle` takes the MISSION_* messages in :attr:`MESSAGES`; :meth:`update`, called as time
    passes, asks again for a late item and cancels a stalled upload. Replies and STATUSTEXTs go out
    through ``emit`` and ``text``. AUTO steps through the mission with :meth:`start_or_resume`,
    :attr:`current` and :meth:`advance`.
    """

    MESSAGES: ClassVar[frozenset[str]] = frozenset(
        {"MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_REQUEST_LIST", "MISSION_REQUEST_INT", "MISSION_CLEAR_ALL", "MISSION_SET_CURRENT"}
    )
    HOME_SLOT: ClassVar[bool]  # item 0 is home (ArduPilot); the mission proper starts at 1
    MISSION_TYPE: ClassVar[int] = _MISSION  # the MAV_MISSION_TYPE it keeps (fence and rally stores: executive.sim.zone_stores)
    READ_BACK_AUTOCONTINUE: ClassVar[int] = 1  # MISSION_ITEM_INT autocontinue of an item read back
    AUTO_MODE: ClassVar[str]  # the mode that runs the mission (MISSION_CURRENT mission_mode)
    RE_REQUEST_S = 1.0  # MissionItemProtocol: ask again for an item after this long without it
    UPLOAD_TIMEOUT_S = 8.0  # ... and give up on the upload after this long
    MAX_ITEMS = 700  # depends on the board's storage

    def __init__(
        self, owner: MissionOwner, emit: Callable[[MAVLinkMessage], None], text: Callable[[int, str], None], *, max_items: int | None = None
    ) -> None:
        self._owner = owner
        self._emit = emit
        self._text = text
        self._mav = encoder(owner.system_id, owner.component_id)
        self.max_items = self.MAX_ITEMS if max_items is None else max_items  # a store's own class limit by default
        self._commands: list[StoredCommand] = []  # [0] is the home slot, read back as the current home
        self.state = AutopilotMissionState.STOPPED
        self.current_seq: int | None = None  # the item AUTO is on (or starts from); None = from the first
        self.receiving = False  # an upload is under way
        self._request_i = self._request_last = 0
        self._uploader = (0, 0)  # system and component id of whoever uploads
        self._last_item_at = self._last_request_at = 0.0
        self.uploaded_at: float | None = None  # clock time of the last completed upload
        #: Writes to the stored mission so far: items stored (a home slot's item 0 aside), cut or cleared
        #: (AP_Mission::write_cmd_to_storage, truncate and clear move its last change time).
        self.changes = 0
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
        return self.state is AutopilotMissionState.RUNNING

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
        if getattr(msg, "mission_type", _MISSION) != self.MISSION_TYPE:
            self._ack(msg, _M.MAV_MISSION_UNSUPPORTED)  # not this store's (the firmware hands each type to its own store)
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
            self._emit(self._mav.mission_ack_encode(*self._uploader, _M.MAV_MISSION_OPERATION_CANCELLED, self.MISSION_TYPE))
        elif now - self._last_request_at > self.RE_REQUEST_S:
            self._request()

    def _ack(self, msg: MAVLinkMessage, result: int) -> None:
        self._emit(self._mav.mission_ack_encode(msg.get_srcSystem(), msg.get_srcComponent(), result, self.MISSION_TYPE))

    @abstractmethod
    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        """An uploaded item as this firmware stores it, or the MAV_MISSION_RESULT refusing it."""

    @abstractmethod
    def _request(self) -> None:
        """Ask the uploader for item ``_request_i`` (and note when)."""

    def _received(self) -> None:
        """An upload completed (a firmware may say so)."""
        return

    def _completed(self) -> None:
        """The last item is done (a firmware may say so)."""
        return

    def _on_count(self, msg: MAVLinkMessage) -> None:
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if self.receiving and sender != self._uploader:
            self._ack(msg, _M.MAV_MISSION_DENIED)  # one uploader at a time; the same one may start over
            return
        if msg.count > self.max_items:
            self._ack(msg, _M.MAV_MISSION_NO_SPACE)
            self._text(_M.MAV_SEVERITY_WARNING, f"Only {self.max_items} items are supported")
            return
        if msg.count < self.count:
            del self._commands[msg.count :]
            self.changes += 1
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
            self.changes += int(msg.seq != 0 or not self.HOME_SLOT)  # "Update of home location is not a true change"
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

    @property
    def commands(self) -> tuple[StoredCommand, ...]:
        """The items held (home's slot included)."""
        return tuple(self._commands)

    def _on_request_list(self, msg: MAVLinkMessage) -> None:
        if self.receiving:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        self._emit(self._mav.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(), self.count, self.MISSION_TYPE))

    def _on_request_int(self, msg: MAVLinkMessage) -> None:
        if self.receiving:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        if (msg.seq != 0 or not self.HOME_SLOT) and msg.seq >= self.count:  # home can always be read
            self._emit(self._mav.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(), self.count, self.MISSION_TYPE))  # the real size
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        cmd = self.command(msg.seq)
        current = int(msg.seq != 0 and msg.seq == self.current_seq)
        self._emit(
            self._mav.mission_item_int_encode(
                msg.get_srcSystem(), msg.get_srcComponent(), msg.seq, cmd.frame, cmd.command, current, self.READ_BACK_AUTOCONTINUE,
                *cmd.params, cmd.lat_e7, cmd.lon_e7, cmd.alt_cm / 100.0, self.MISSION_TYPE,
            )
        )  # fmt: skip

    def _on_clear_all(self, msg: MAVLinkMessage) -> None:
        if self.receiving or (self.running and self._owner.armed):
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        self._commands.clear()
        self.changes += 1
        self.state, self.current_seq = AutopilotMissionState.STOPPED, None
        self._ack(msg, _M.MAV_MISSION_ACCEPTED)

    def _on_set_current(self, msg: MAVLinkMessage) -> None:
        if self.set_current(msg.seq):
            # ground stations take the echo of their seq as the ack, even 0 (home), which the vehicle never holds
            self._emit(self.current_message(msg.seq))

    def command_set_current(self, seq: float, reset: float) -> int:
        """MAV_CMD_DO_SET_MISSION_CURRENT: param1 the item, param2 1 to reset a completed mission too; a MAV_RESULT."""
        if reset == 1.0 and self.state is AutopilotMissionState.COMPLETE:
            self.state = AutopilotMissionState.STOPPED
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
        if self.state is AutopilotMissionState.COMPLETE:
            self.state = AutopilotMissionState.STOPPED
        return True

    def start_or_resume(self) -> None:
        """AUTO runs the mission from its current item (MIS_RESTART=0); a completed one starts over."""
        if not self.present:
            return
        if self.state is AutopilotMissionState.COMPLETE or self.current_seq is None or self.current_seq >= self.count:
            self.current_seq = self.first_item
        self.state = AutopilotMissionState.RUNNING

    def stop(self) -> None:
        """Leaving AUTO: the mission stops where it is, to resume there."""
        if self.running:
            self.state = AutopilotMissionState.STOPPED

    @property
    def current(self) -> StoredCommand | None:
        """The item being executed, while the mission runs."""
        if not self.running or self.current_seq is None or self.current_seq >= self.count:
            return None
        return self._commands[self.current_seq]

    def advance(self) -> StoredCommand | None:
        """The current item is done: MISSION_ITEM_REACHED, then the next item, or None (and "Mission Complete") after the last."""
        if self.current_seq is None or not self.running:
            return None
        self._emit(self._mav.mission_item_reached_encode(self.current_seq))
        if self.current_seq + 1 < self.count:
            self.current_seq += 1
            return self._commands[self.current_seq]
        self.state = AutopilotMissionState.COMPLETE
        self._completed()
        return None

    def current_message(self, seq: int | None = None) -> MAVLinkMessage:
        """MISSION_CURRENT as the firmware streams it; ``seq`` replaces the item (to echo MISSION_SET_CURRENT)."""
        if not self.present:
            state = _M.MISSION_STATE_NO_MISSION
        else:
            state = {
                AutopilotMissionState.STOPPED: _M.MISSION_STATE_NOT_STARTED,
                AutopilotMissionState.RUNNING: _M.MISSION_STATE_ACTIVE,
                AutopilotMissionState.COMPLETE: _M.MISSION_STATE_COMPLETE,
            }[self.state]
        seq = (self.current_seq or 0) if seq is None else seq
        total = max(self.count - self.first_item, 0)
        return self._mav.mission_current_encode(seq, total, state, int(self._owner.mode == self.AUTO_MODE))
