"""PX4's side of the mission protocol in the simulated autopilot: the items it takes, MISSION_REQUEST_INT, no home slot."""

from __future__ import annotations

import math
from typing import ClassVar

from executive.sim.mission_store import AutopilotMissionState, MissionStore, StoredCommand
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
    _no_current = False  # an upload ended and the navigator has not answered with its item yet

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

    def _received(self) -> None:
        """An upload flagging no item current keeps the navigator's item, constrained to the new count (mission_base.cpp
        updateMavlinkMission: current_seq < 0), in AUTO.MISSION too: it flies on to the same item (real SIH, tests/data/px4).
        Until the navigator answers, MISSION_CURRENT says item 65535: the upload's -1 as a uint16 (mavlink_mission.cpp
        update_active_mission, send_mission_current)."""
        if self.current_seq is not None and self.current_seq >= self.count:
            self.current_seq = max(self.count - 1, 0)
        self._no_current = True

    def set_current(self, seq: int) -> bool:
        """A finished mission stays COMPLETE with the item set until AUTO.MISSION runs it again (mission_result.finished,
        cleared by mission_base.cpp set_mission_result on activation; real SIH: MISSION_CURRENT (4, COMPLETE) after
        MISSION_SET_CURRENT 4, tests/data/px4/README.md)."""
        complete = self.state is AutopilotMissionState.COMPLETE
        if not super().set_current(seq):
            return False
        if complete:
            self.state = AutopilotMissionState.COMPLETE
        return True

    def start_or_resume(self) -> None:
        """AUTO.MISSION goes on at the current item, a finished mission's too (MissionBase::on_activation; the restart at
        item 0 of checkMissionRestart, after a disarm at the last item, is not modelled)."""
        if not self.present:
            return
        if self.current_seq is None or self.current_seq >= self.count:
            self.current_seq = self.first_item
        self.state = AutopilotMissionState.RUNNING

    def feasible(self, required: int, landed: bool) -> bool:
        """MIS_TKO_LAND_REQ ``required``'s rule (navigator/MissionFeasibility/FeasibilityChecker.cpp checkTakeoffLandAvailable): a
        mission without the take-off or landing it asks for is invalid, and AUTO.MISSION refused (real SIH standard_vtol, its
        default 2: two waypoints TEMPORARILY_REJECTED, tests/data/px4/README.md)."""
        commands = {c.command for c in self.commands}
        takeoff = bool(commands & {_M.MAV_CMD_NAV_TAKEOFF, _M.MAV_CMD_NAV_VTOL_TAKEOFF})
        landing = bool(commands & {_M.MAV_CMD_NAV_LAND, _M.MAV_CMD_NAV_VTOL_LAND})
        rule = {1: takeoff, 2: landing, 3: takeoff and landing, 4: takeoff == landing, 5: takeoff == landing if landed else landing}
        return rule.get(required, True)

    def current_message(self, seq: int | None = None) -> MAVLinkMessage:
        if seq is None and self._no_current:
            self._no_current = False
            return super().current_message(0xFFFF)
        return super().current_message(seq)

    def _request(self) -> None:
        self._last_request_at = self._owner.clock.now()
        self._emit(self._mav.mission_request_int_encode(*self._uploader, self._request_i, self.MISSION_TYPE))
