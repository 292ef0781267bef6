"""Local frames: ROS's ENU (x east, y north, z up) and MAVLink's NED (x north, y east, z down).

Positions and velocities convert the same way (swap the horizontal axes, negate the vertical);
a yaw angle is measured from east counter-clockwise in ENU and from north clockwise in NED.
Local offsets are tied to global positions on the WGS84 ellipsoid (geodesics, not flat earth).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from executive.world import geo


class Enu(NamedTuple):
    """A local ENU vector (ROS, REP 103): metres (or m/s) east, north, up."""

    east: float
    north: float
    up: float


class Ned(NamedTuple):
    """A local NED vector (MAVLink LOCAL_NED): metres (or m/s) north, east, down."""

    north: float
    east: float
    down: float


def enu_to_ned(v: Enu) -> Ned:
    """ENU -> NED (positions or velocities)."""
    return Ned(v.north, v.east, -v.up)


def ned_to_enu(v: Ned) -> Enu:
    """NED -> ENU (positions or velocities)."""
    return Enu(v.east, v.north, -v.down)


def _wrap_pi(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def yaw_enu_to_ned(yaw_rad: float) -> float:
    """A heading from east counter-clockwise (ENU) -> from north clockwise (NED), radians in [-pi, pi)."""
    return _wrap_pi(math.pi / 2.0 - yaw_rad)


def yaw_ned_to_enu(yaw_rad: float) -> float:
    """A heading from north clockwise (NED) -> from east counter-clockwise (ENU), radians in [-pi, pi)."""
    return _wrap_pi(math.pi / 2.0 - yaw_rad)  # the same reflection: it is its own inverse


def local_to_global(origin_lat: float, origin_lon: float, north_m: float, east_m: float) -> tuple[float, float]:
    """The latitude and longitude of a point ``north_m``, ``east_m`` from an origin."""
    distance = math.hypot(north_m, east_m)
    if distance == 0.0:
        return origin_lat, origin_lon
    return geo.destination(origin_lat, origin_lon, math.degrees(math.atan2(east_m, north_m)), distance)


def global_to_local(origin_lat: float, origin_lon: float, lat: float, lon: float) -> tuple[float, float]:
    """Metres north and east of an origin to a point."""
    distance, bearing = geo.distance_bearing(origin_lat, origin_lon, lat, lon)
    return distance * math.cos(math.radians(bearing)), distance * math.sin(math.radians(bearing))
