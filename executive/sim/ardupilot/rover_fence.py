"""ArduRover's own fence in the simulated autopilot: the breach check, FENCE_STATUS and FENCE_ACTION.

From the firmware: libraries/AC_Fence/AC_Fence.cpp (parameters, Rover's defaults; ``check``; ``record_breach``
sends FENCE_STATUS at once; the EXTENDED_STATUS stream carries it while the fence is enabled,
GCS_MAVLink/GCS_Fence.cpp send_fence_status), libraries/AC_Fence/AC_PolyFence_loader.cpp ``breached``
(inside every inclusion shape, or any with FENCE_OPTIONS bit 1; outside every exclusion shape), and
Rover/fence.cpp: checked at 10 Hz, armed only, a *new* breach takes FENCE_ACTION once (0 report only; 1 RTL
or Hold; 2 Hold; 3, 4 SmartRTL or RTL or Hold; 5 disarm; 6 Loiter or Hold); the mode may be changed
again afterwards. Not modelled: the fence margin and ArduRover's avoidance (AC_Avoid), which in
GUIDED and AUTO slows the vehicle at the fence rather than letting it through, and the 100 m give-up distance.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import MappingProxyType

from executive.sim.mission_store import StoredCommand
from executive.world import geo
from executive.world.dialect import mavlink

_M = mavlink
#: AC_Fence.cpp's defaults on Rover: off, circle and polygon types, RTL or Hold, a 300 m circle, no options.
FENCE_DEFAULTS = MappingProxyType({"FENCE_ENABLE": 0.0, "FENCE_TYPE": 6.0, "FENCE_ACTION": 1.0, "FENCE_RADIUS": 300.0, "FENCE_OPTIONS": 0.0})
FENCE_TYPE_CIRCLE, FENCE_TYPE_POLYGON = 2, 4
_INCLUSION_UNION = 2
#: Rover/fence.cpp: FENCE_ACTION -> the modes tried in turn (none: report only; "DISARM": AP_Arming::disarm).
FENCE_ACTIONS = MappingProxyType({
    0: (), 1: ("RTL", "HOLD"), 2: ("HOLD",), 3: ("SMART_RTL", "RTL", "HOLD"), 4: ("SMART_RTL", "HOLD"), 5: ("DISARM",), 6: ("LOITER", "HOLD"),
})  # fmt: skip


def _inside_polygon(lat: float, lon: float, corners: Sequence[StoredCommand]) -> bool:
    """Ray casting on latitude/longitude (the shapes are small: AC_PolyFence_loader's Polygon_outside does the same on 1e-7 degrees)."""
    inside = False
    for a, b in zip(corners, [*corners[1:], corners[0]], strict=True):
        if (a.lat > lat) != (b.lat > lat) and lon < (b.lon - a.lon) * (lat - a.lat) / (b.lat - a.lat) + a.lon:
            inside = not inside
    return inside


def polygon_breached(lat: float, lon: float, fence: Sequence[StoredCommand], union: bool) -> bool:
    """AC_PolyFence_loader::breached: outside the inclusion shapes (all of them, or any without ``union``) or inside an exclusion one."""
    inclusions: list[bool] = []  # inside each inclusion shape
    i = 0
    while i < len(fence):
        cmd = fence[i]
        if cmd.command in (_M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION):
            count = int(cmd.params[0])
            inside = _inside_polygon(lat, lon, fence[i : i + count])
            i += count
            if cmd.command == _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION and inside:
                return True
            if cmd.command == _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION:
                inclusions.append(inside)
            continue
        if cmd.command in (_M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, _M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION):
            inside = geo.distance(lat, lon, cmd.lat, cmd.lon) < cmd.params[0]
            if cmd.command == _M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION and inside:
                return True
            if cmd.command == _M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION:
                inclusions.append(inside)
        i += 1
    if not inclusions:
        return False
    return not any(inclusions) if union else not all(inclusions)


def breaches(params: dict[str, float], fence: Sequence[StoredCommand], home: tuple[float, float] | None, lat: float, lon: float) -> int:
    """The fence types breached now (AC_Fence::check): a bitmask of FENCE_TYPE bits (2 circle, 4 polygon); 0 while FENCE_ENABLE is 0."""
    if not params.get("FENCE_ENABLE"):
        return 0
    kinds, found = int(params.get("FENCE_TYPE", 0)), 0
    if kinds & FENCE_TYPE_CIRCLE and home is not None and geo.distance(lat, lon, *home) > params.get("FENCE_RADIUS", 300.0):
        found |= FENCE_TYPE_CIRCLE
    if kinds & FENCE_TYPE_POLYGON and polygon_breached(lat, lon, fence, bool(int(params.get("FENCE_OPTIONS", 0)) & _INCLUSION_UNION)):
        found |= FENCE_TYPE_POLYGON
    return found
