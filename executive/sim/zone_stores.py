"""The fence and the rally points in a simulated autopilot: their side of the mission protocol (MAV_MISSION_TYPE_FENCE, _RALLY).

Each is a :class:`~executive.sim.mission_store.MissionStore` of its own mission type, numbered from 0
(no home slot), read back with autocontinue 0, as the firmware keeps it:

- ArduPilot's fence (GCS_MAVLink/MissionItemProtocol_Fence.cpp, AC_Fence/AC_PolyFence_loader.cpp): the
  items are taken whole at the end of the upload: AC_PolyFence_loader::validate_fence refuses (MISSION_ACK
  ERROR, "Fence validation failed") a polygon of fewer than 3 corners or whose items disagree on the count,
  a circle inside a polygon's run or of radius <= 0, two return points, and the old fence is kept; a
  polygon's count over 255 is INVALID_PARAM1 at its item. It reads an item back with frame 0, z 0 and only
  param1 (the count, or a circle's float radius). At most :data:`ARDUPILOT_FENCE_ITEMS` items.
- ArduPilot's rally points (GCS_MAVLink/MissionItemProtocol_Rally.cpp, AP_Rally): MAV_CMD_NAV_RALLY_POINT
  only, an altitude in whole metres (int16, truncated), read back in its frame (MAV_FRAME_GLOBAL or
  _RELATIVE_ALT); at most :data:`ARDUPILOT_RALLY_POINTS`.
- PX4's (src/modules/mavlink/mavlink_mission.cpp, upstream a70a558393): a polygon vertex with a count
  under 3 is MISSION_ACK ERROR at its item ("Fence: too few vertices"); items keep their altitude and are
  read back in the INT frames (fence MAV_FRAME_GLOBAL_INT, rally points _RELATIVE_ALT_INT: measured on
  PX4 SIH, tests/data/zones); at most 64 fence items and 32 rally points (src/modules/dataman/dataman.h).
"""

from __future__ import annotations

import math
from typing import ClassVar

from executive.sim.ardupilot.mission_store import ArduPilotMissionStore
from executive.sim.mission_store import StoredCommand
from executive.sim.px4.mission_store import Px4MissionStore
from executive.world.dialect import MAVLinkMessage, mavlink

_M = mavlink
_POLYGONS = frozenset({_M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION})
_CIRCLES = frozenset({_M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, _M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION})
FENCE_COMMANDS = _POLYGONS | _CIRCLES | {_M.MAV_CMD_NAV_FENCE_RETURN_POINT}
_GLOBAL_FRAMES = frozenset({
    _M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    _M.MAV_FRAME_GLOBAL_TERRAIN_ALT, _M.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
})  # fmt: skip
#: SITL's storage (StorageManager.cpp, 18 areas): 160 + 256 + 256 fence bytes / 8 (AC_PolyFence_loader::max_items).
ARDUPILOT_FENCE_ITEMS = 84
#: ... and 150 + 300 + 300 rally bytes / 15 (RallyLocation).
ARDUPILOT_RALLY_POINTS = 50


def validate_fence(commands: tuple[StoredCommand, ...]) -> str | None:
    """Why ArduPilot would refuse this fence (AC_PolyFence_loader::validate_fence), as its STATUSTEXT says; None if it takes it."""
    left, run_type, run_count, return_points = 0, 0, 0, 0
    for cmd in commands:
        if cmd.command in _POLYGONS:
            count = int(cmd.params[0])
            if count < 3:
                return f"Invalid vertex count ({count})"
            if left == 0:
                left, run_type, run_count = count, cmd.command, count
            elif cmd.command != run_type:
                return f"Received incorrect vertex type (want={run_type} got={cmd.command})"
            elif count != run_count:
                return f"Unexpected vertex count want={run_count} got={count}"
            left -= 1
        elif left:
            return f"Received incorrect type (want={run_type} got={cmd.command})"
        elif cmd.command in _CIRCLES and cmd.params[0] <= 0:
            return "Non-positive circle radius"
        elif cmd.command == _M.MAV_CMD_NAV_FENCE_RETURN_POINT:
            return_points += 1
            if return_points > 1:
                return "Multiple return points"
    return None


class ArduPilotFenceStore(ArduPilotMissionStore):
    """ArduPilot's fence (see the module)."""

    HOME_SLOT: ClassVar[bool] = False
    MISSION_TYPE: ClassVar[int] = _M.MAV_MISSION_TYPE_FENCE
    READ_BACK_AUTOCONTINUE: ClassVar[int] = 0
    MAX_ITEMS = ARDUPILOT_FENCE_ITEMS

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._kept: list[StoredCommand] = []  # the fence before an upload: kept if the new one is refused

    def _on_count(self, msg: MAVLinkMessage) -> None:
        if not self.receiving:
            self._kept = list(self._commands)
        super()._on_count(msg)

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        """As MissionItemProtocol_Fence::convert_MISSION_ITEM_INT_to_AC_PolyFenceItem."""
        if msg.frame not in _GLOBAL_FRAMES:
            return _M.MAV_MISSION_UNSUPPORTED_FRAME
        if msg.command not in FENCE_COMMANDS:
            return _M.MAV_MISSION_UNSUPPORTED
        if msg.command in _POLYGONS and msg.param1 > 255:
            return _M.MAV_MISSION_INVALID_PARAM1
        param1 = float(int(msg.param1)) if msg.command in _POLYGONS else (msg.param1 if msg.command in _CIRCLES else 0.0)
        return StoredCommand(msg.command, (param1, 0.0, 0.0, 0.0), msg.x, msg.y, 0, _M.MAV_FRAME_GLOBAL)

    def _upload_complete(self, msg: MAVLinkMessage) -> None:
        why = validate_fence(self.commands)
        if why is None:
            super()._upload_complete(msg)
            return
        self.receiving = False
        self._commands[:] = self._kept
        self._text(_M.MAV_SEVERITY_WARNING, why)
        self._text(_M.MAV_SEVERITY_WARNING, "Fence validation failed")
        self._ack(msg, _M.MAV_MISSION_ERROR)

    def _received(self) -> None:
        return  # MissionItemProtocol_Fence::complete says nothing on success


class ArduPilotRallyStore(ArduPilotMissionStore):
    """ArduPilot's rally points (see the module)."""

    HOME_SLOT: ClassVar[bool] = False
    MISSION_TYPE: ClassVar[int] = _M.MAV_MISSION_TYPE_RALLY
    READ_BACK_AUTOCONTINUE: ClassVar[int] = 0
    MAX_ITEMS = ARDUPILOT_RALLY_POINTS

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        """As MissionItemProtocol_Rally::convert_MISSION_ITEM_INT_to_RallyLocation."""
        if msg.command != _M.MAV_CMD_NAV_RALLY_POINT:
            return _M.MAV_MISSION_UNSUPPORTED
        if abs(msg.x) > 90 * 10**7:
            return _M.MAV_MISSION_INVALID_PARAM5_X
        if abs(msg.y) > 180 * 10**7:
            return _M.MAV_MISSION_INVALID_PARAM6_Y
        if not -32768 <= msg.z <= 32767:
            return _M.MAV_MISSION_INVALID_PARAM7
        frames = {_M.MAV_FRAME_GLOBAL: _M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT: _M.MAV_FRAME_GLOBAL}
        frames |= dict.fromkeys((_M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT), _M.MAV_FRAME_GLOBAL_RELATIVE_ALT)
        if msg.frame not in frames:
            return _M.MAV_MISSION_UNSUPPORTED_FRAME
        return StoredCommand(msg.command, (0.0, 0.0, 0.0, 0.0), msg.x, msg.y, int(msg.z) * 100, frames[msg.frame])

    def _received(self) -> None:
        return


class Px4FenceStore(Px4MissionStore):
    """PX4's fence (see the module)."""

    MISSION_TYPE: ClassVar[int] = _M.MAV_MISSION_TYPE_FENCE
    READ_BACK_AUTOCONTINUE: ClassVar[int] = 0
    MAX_ITEMS = 64

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        if msg.command not in FENCE_COMMANDS or msg.frame not in _GLOBAL_FRAMES or not math.isfinite(msg.z):
            return _M.MAV_MISSION_ERROR
        if msg.command in _POLYGONS and msg.param1 < 3:
            self._text(_M.MAV_SEVERITY_CRITICAL, "Fence: too few vertices")
            return _M.MAV_MISSION_ERROR
        # read back in MAV_FRAME_GLOBAL_INT whatever it was sent in (measured on PX4 SIH, tests/data/zones)
        return StoredCommand(msg.command, (msg.param1, 0.0, 0.0, 0.0), msg.x, msg.y, round(msg.z * 100), _M.MAV_FRAME_GLOBAL_INT)


class Px4RallyStore(Px4MissionStore):
    """PX4's rally (safe) points (see the module)."""

    MISSION_TYPE: ClassVar[int] = _M.MAV_MISSION_TYPE_RALLY
    READ_BACK_AUTOCONTINUE: ClassVar[int] = 0
    MAX_ITEMS = 32

    def _to_stored(self, msg: MAVLinkMessage) -> StoredCommand | int:
        if msg.command != _M.MAV_CMD_NAV_RALLY_POINT or msg.frame not in _GLOBAL_FRAMES or not math.isfinite(msg.z):
            return _M.MAV_MISSION_ERROR
        relative = msg.frame in (_M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        frame = _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT if relative else _M.MAV_FRAME_GLOBAL_INT  # as PX4 SIH read them back
        return StoredCommand(msg.command, (0.0, 0.0, 0.0, 0.0), msg.x, msg.y, round(msg.z * 100), frame)
