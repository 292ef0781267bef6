"""PX4's side of the mission protocol in the simulated autopilot: the items it takes, MISSION_REQUEST_INT, no home slot."""

from __future__ import annotations

import math
from typing import ClassVar

from executive.sim.mission_store import MissionStore, StoredCommand
from executive.world.dialect import MAVLinkMessage, mavlink

_M = mavlink

#: Mission items the simulated PX4 takes (others: MAV_MISSION_UNSUPPORTED), those with a position, and their frames.
PX4_LOCATION_COMMANDS = frozenset({
    _M.MAV_CMD_NAV_WAYPOINT, _M.MAV_CMD_NAV_LOITER_UNLIM, _M.MAV_CMD_NAV_LOITER_TIME, _M.MAV_CMD_NAV_TAKEOFF,
    _M.MAV_CMD_NAV_LAND, _M.MAV_CMD_NAV_VTOL_TAKEOFF, _M.MAV_CMD_NAV_VTOL_LAND,
})  # fmt: skip
PX4_MISSION_COMMANDS = PX4_LOCATION_COMMANDS | {
    _M.MAV_CMD_NAV_RETURN_TO_LAUNCH, _M.MAV_CMD_DO_VTOL_TRANSITION, _M.MAV_CMD_DO_CHANGE_SPEED, _M.MAV_CMD_DO_JUMP,
}  # fmt: skip
PX4_MISSION_FRAMES = frozenset({
    _M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
})  # fmt: skip


class Px4MissionStore(MissionStore):
    """PX4's side of the mission protocol: MISSION_REQUEST_INT, no home slot, no STATUSTEXT on upload or completion.

    It stores the VTOL items ArduPilot's store lacks (take-off, landing, transitions) with their
    parameters as sent (NaN included: PX4 keeps a NaN yaw as "unchanged").
    """

    HOME_SLOT: ClassVar[bool] = False
    AUTO_MODE: ClassVar[str] = "AUTO.MISSION"

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        if msg.command not in PX4_MISSION_COMMANDS:
            return _M.MAV_MISSION_UNSUPPORTED
        if msg.command not in PX4_LOCATION_COMMANDS:
            return StoredCommand(msg.command, (msg.param1, msg.param2, msg.param3, msg.param4), 0, 0, 0, _M.MAV_FRAME_MISSION)
        if msg.frame not in PX4_MISSION_FRAMES:
            return _M.MAV_MISSION_UNSUPPORTED_FRAME
        if abs(msg.x) > 90 * 10**7 or abs(msg.y) > 180 * 10**7 or not math.isfinite(msg.z):
            return _M.MAV_MISSION_INVALID
        frame = _M.MAV_FRAME_GLOBAL if msg.frame in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT) else _M.MAV_FRAME_GLOBAL_RELATIVE_ALT
        return StoredCommand(msg.command, (msg.param1, msg.param2, msg.param3, msg.param4), msg.x, msg.y, round(msg.z * 100), frame)

    def _request(self) -> None:
        self._last_request_at = self._owner.clock.now()
        self._emit(self._mav.mission_request_int_encode(*self._uploader, self._request_i, self.MISSION_TYPE))
