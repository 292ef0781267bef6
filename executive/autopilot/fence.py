"""The mission's zones and rally points as the autopilot's fence and rally items (MAVLink mission types FENCE and RALLY).

The fence, in the order ``geofence:`` lists its shapes (``polygon``, ``inclusion``, ``keep_out``):
a polygon is one MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION / _EXCLUSION item per corner, each with
the corner count in param1 (a last corner repeating the first is dropped); a circle one
MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION / _EXCLUSION with its radius in param1. Rally points are
MAV_CMD_NAV_RALLY_POINT above home. Each item is sent as the firmware reads it back, so the read-back
compares item by item:

- ArduPilot reads a fence item back with frame 0 (MAV_FRAME_GLOBAL), z 0 and only param1
  (GCS_MAVLink/MissionItemProtocol_Fence.cpp get_item_as_mission_item; AC_PolyFence_loader.cpp stores
  the type, corner count, latitude/longitude and a circle's float radius);
- ArduPilot keeps a rally point's altitude as whole metres in an int16 (AP_Rally/AP_Rally.h RallyLocation,
  GCS_MAVLink/MissionItemProtocol_Rally.cpp convert_MISSION_ITEM_INT_to_RallyLocation), so it is sent rounded;
- PX4 keeps each item's frame and altitude as sent (src/modules/mavlink/mavlink_mission.cpp, upstream a70a558393).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from executive.io.mavlink.mission_protocol import MissionItem
from executive.mission.model import GeofenceConfig, RallyPoint, Vertex, Zone
from executive.world.dialect import mavlink

_M = mavlink
_FENCE, _RALLY = _M.MAV_MISSION_TYPE_FENCE, _M.MAV_MISSION_TYPE_RALLY
_POLYGON = {True: _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, False: _M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION}
_CIRCLE = {True: _M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, False: _M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION}


@dataclass(frozen=True, slots=True)
class ZoneItems:
    """Items for one mission type and, for each item, the mission's shape or rally point it comes from (``geofence.keep_out[1] 'pier'``)."""

    items: tuple[MissionItem, ...]
    sources: tuple[str, ...]

    def source_of(self, seq: int) -> str:
        """The mission's shape or point item ``seq`` belongs to."""
        return self.sources[seq] if 0 <= seq < len(self.sources) else f"item {seq}"

    def shapes(self) -> list[str]:
        """Each source once, in order."""
        return list(dict.fromkeys(self.sources))


def _label(field: str, index: int | None, name: str | None) -> str:
    where = field if index is None else f"{field}[{index}]"
    return f"{where} '{name}'" if name else where


def _corners(vertices: Sequence[Vertex]) -> list[Vertex]:
    """The corners of a polygon; a last one repeating the first closes it and is not a corner."""
    corners = list(vertices)
    if len(corners) > 3 and (corners[0].lat, corners[0].lon) == (corners[-1].lat, corners[-1].lon):
        corners.pop()
    return corners


def _shape_items(zone_polygon: Sequence[Vertex] | None, zone: Zone | None, inclusion: bool) -> list[MissionItem]:
    if zone_polygon is not None:
        corners = _corners(zone_polygon)
        command = _POLYGON[inclusion]
        return [MissionItem(0, _M.MAV_FRAME_GLOBAL, command, 0, 0, float(len(corners)), 0.0, 0.0, 0.0, v.lat, v.lon, 0.0, _FENCE) for v in corners]
    assert zone is not None and zone.circle is not None
    c = zone.circle
    return [MissionItem(0, _M.MAV_FRAME_GLOBAL, _CIRCLE[inclusion], 0, 0, c.radius_m, 0.0, 0.0, 0.0, c.lat, c.lon, 0.0, _FENCE)]


def fence_items(geofence: GeofenceConfig | None) -> ZoneItems:
    """The fence items of ``geofence:``: ``polygon`` and ``inclusion`` zones as inclusion shapes, ``keep_out`` as exclusion ones."""
    items: list[MissionItem] = []
    sources: list[str] = []

    def add(shape: list[MissionItem], source: str) -> None:
        items.extend(shape)
        sources.extend([source] * len(shape))

    if geofence is not None:
        if geofence.polygon is not None:
            add(_shape_items(geofence.polygon, None, True), "geofence.polygon")
        for field, zones, inclusion in (("geofence.inclusion", geofence.inclusion, True), ("geofence.keep_out", geofence.keep_out, False)):
            for i, zone in enumerate(zones):
                add(_shape_items(zone.polygon, zone, inclusion), _label(field, i, zone.name))
    numbered = tuple(replace(item, seq=seq) for seq, item in enumerate(items))
    return ZoneItems(numbered, tuple(sources))


def rally_items(points: Sequence[RallyPoint]) -> ZoneItems:
    """The rally points above home, their altitude in whole metres (ArduPilot's int16 metres)."""
    frame, command = _M.MAV_FRAME_GLOBAL_RELATIVE_ALT, _M.MAV_CMD_NAV_RALLY_POINT
    items = tuple(
        MissionItem(seq, frame, command, 0, 0, 0.0, 0.0, 0.0, 0.0, p.lat, p.lon, float(round(p.alt_m)), _RALLY) for seq, p in enumerate(points)
    )
    return ZoneItems(items, tuple(_label("rally_points", i, p.name) for i, p in enumerate(points)))


def inclusion_shapes(geofence: GeofenceConfig | None) -> list[str]:
    """The mission's inclusion shapes (``polygon`` and each ``inclusion`` zone), named."""
    if geofence is None:
        return []
    zones = [_label("geofence.inclusion", i, z.name) for i, z in enumerate(geofence.inclusion)]
    return ["geofence.polygon", *zones] if geofence.polygon is not None else zones
