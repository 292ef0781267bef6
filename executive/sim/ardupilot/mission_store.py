"""ArduPilot's mission in the simulated autopilot: how it stores items and asks for them, home at item 0, AUTO's look-ahead.

It follows the firmware (GCS_MAVLink/MissionItemProtocol*.cpp, AP_Mission) where it differs from the spec:

- item 0 is home: reading item 0 always gives the vehicle's current home, whatever was uploaded there;
- the vehicle drives an upload with MISSION_REQUEST (ArduPilot kept the non-INT request; ground
  stations answer with MISSION_ITEM_INT); an item other than the one requested gets MISSION_ACK
  INVALID_SEQUENCE and changes nothing; the vehicle asks again after 1 s without the item and
  cancels the upload (OPERATION_CANCELLED) after 8 s;
- MISSION_COUNT cuts the mission to the new count at once and items replace the old ones as they
  arrive, so a failed upload leaves a mixed mission;
- items are kept as ArduPilot keeps them: latitude and longitude in 1e-7 degree, altitude in whole
  centimetres, a NAV_WAYPOINT's hold time in whole seconds and none of its other parameters, a
  NAV_LOITER_UNLIM's radius (param3) alone, and frames read back in their non-INT form;
- MISSION_WRITE_PARTIAL_LIST rewrites items from start_index to end_index, each at most the item
  count (else MISSION_ACK ERROR and "Flight plan update rejected"), refused (DENIED) during an
  upload; an item whose seq is the count is appended, so a partial write from the end to the end
  adds one item to a mission that may be running (MissionItemProtocol::handle_mission_write_partial_list,
  handle_mission_item);
- MISSION_SET_CURRENT has no ack: a MISSION_CURRENT echoing the seq confirms it, an item the vehicle
  does not hold is ignored.

Only the flight plan is stored (no fence, no rally points), and MISSION_ITEM / MISSION_REQUEST
from a ground station (the float forms) are not handled.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar

from executive.sim.mission_store import MissionOwner, MissionStore, StoredCommand
from executive.world.dialect import MAVLinkMessage, mavlink

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


def to_stored(msg: MAVLinkMessage) -> StoredCommand | int:
    """A MISSION_ITEM_INT as ArduPilot would store it, or the MAV_MISSION_RESULT refusing it."""
    params = (msg.param1, msg.param2, msg.param3, msg.param4)
    for i, value in enumerate(params):
        if math.isnan(value) and not (i == 3 and msg.command in (_M.MAV_CMD_NAV_WAYPOINT, _M.MAV_CMD_NAV_LOITER_UNLIM)):  # the yaw may be NaN
            return _INVALID_PARAM[i]
    if msg.command not in KNOWN_COMMANDS:
        return _M.MAV_MISSION_UNSUPPORTED
    if msg.command == _M.MAV_CMD_NAV_WAYPOINT:
        params = (float(max(0, min(int(msg.param1), 0xFFFF))), 0.0, 0.0, 0.0)  # only the hold time, in a uint16 of seconds
    elif msg.command == _M.MAV_CMD_NAV_LOITER_UNLIM:  # only the radius, a uint16 of metres, its sign the direction (AP_Mission.cpp)
        params = (0.0, 0.0, math.copysign(float(min(int(abs(msg.param3)), 0xFFFF)), msg.param3), 0.0)
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


class ArduPilotMissionStore(MissionStore):
    """ArduPilot's mission and its side of the mission protocol (see the module's docstring)."""

    HOME_SLOT: ClassVar[bool] = True
    AUTO_MODE: ClassVar[str] = "AUTO"
    MESSAGES: ClassVar[frozenset[str]] = MissionStore.MESSAGES | {"MISSION_WRITE_PARTIAL_LIST"}

    def __init__(
        self,
        owner: MissionOwner,
        emit: Callable[[MAVLinkMessage], None],
        text: Callable[[int, str], None],
        *,
        max_items: int | None = None,
    ) -> None:
        super().__init__(owner, emit, text, max_items=max_items)
        self._handlers["MISSION_WRITE_PARTIAL_LIST"] = self._on_write_partial_list

    def _on_write_partial_list(self, msg: MAVLinkMessage) -> None:
        """Items start_index..end_index rewritten (one at the count appended), as the firmware does (see the module)."""
        if self.receiving:
            self._ack(msg, _M.MAV_MISSION_DENIED)
            return
        if msg.start_index > self.count or msg.end_index > self.count or msg.end_index < msg.start_index or msg.start_index < 0:
            self._text(_M.MAV_SEVERITY_WARNING, "Flight plan update rejected")
            self._ack(msg, _M.MAV_MISSION_ERROR)
            return
        self._uploader = (msg.get_srcSystem(), msg.get_srcComponent())
        self.receiving = True
        self._request_i, self._request_last = msg.start_index, msg.end_index
        self._last_item_at = self._owner.clock.now()
        self._request()

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        """As AP_Mission stores it (:func:`to_stored`)."""
        return to_stored(msg)

    def _request(self) -> None:
        self._last_request_at = self._owner.clock.now()
        self._emit(self._mav.mission_request_encode(*self._uploader, self._request_i, self.MISSION_TYPE))

    def _received(self) -> None:
        """An upload completed (ArduPilot says so in a STATUSTEXT)."""
        self._text(_M.MAV_SEVERITY_INFO, "Flight plan received")

    def _completed(self) -> None:
        """The last item is done (ArduPilot says so in a STATUSTEXT)."""
        self._text(_M.MAV_SEVERITY_NOTICE, "Mission Complete")

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
