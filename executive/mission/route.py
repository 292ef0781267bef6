"""Route operations: pure functions from one route to the next (the tracked UGV's ``mission_manip``).

A :class:`Route` is the waypoints, the index of the one being driven (``current``: the waypoint the
vehicle heads for, ``len(waypoints)`` once the route is finished) and the mission's home. Every
operation returns a new route and leaves its argument alone; one that cannot apply raises
:class:`RouteError` (a ValueError) saying why, for the operator. The mission state keeps the result
(``MissionState.set_route``); the route keeper writes it to the autopilot.

The operations, by the thesis's names:

- SET_HOME: :func:`set_home` (home is not a waypoint: the other operations leave it alone);
- ADD_WP: :func:`add` (after index n), :func:`add_at_end`, :func:`add_after_current`;
- REMOVE_WP: :func:`remove` (index n), :func:`remove_current`, :func:`remove_last`;
- CLEAR_MISSION: :func:`clear`; BACKWARDS_MISSION: :func:`backwards`;
- OFFSET_MISSION: :func:`offset` (every waypoint, or one, a distance toward a compass bearing);
- SCALE_ROTATE_MISSION: :func:`scale_rotate`; MIRROR_MISSION: :func:`mirror` (about the centre of
  the route's latitude/longitude bounding box, :func:`centre`, or a centre given).

Each keeps ``current`` on the same waypoint where it still exists. Indices are 0-based here;
:func:`apply` takes an operator's request, whose waypoint numbers are 1-based as the status line and
the autopilot's mission (item 0 is home) count them.

Geometry is on the WGS84 ellipsoid (geographiclib), never flat-earth: an offset follows the rhumb
line (a constant compass bearing, so an offset back toward the opposite bearing restores the route
to the nanometre); scaling, rotating and mirroring work in geodesic polar coordinates about the
centre (the azimuthal equidistant projection: each waypoint's geodesic distance and bearing from
the centre), so distances to the centre are exact and distances between waypoints are kept (or
scaled) to about 1e-7 over 5 km.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from pydantic import ValidationError

from executive.mission.model import Home, Waypoint
from executive.world import geo

#: A waypoint may not end up farther than this from the centre, or be offset farther (a route edit is for a site, not a continent).
MAX_REACH_M = 1_000_000.0


class RouteError(ValueError):
    """A route operation that cannot apply to this route; ``str()`` says why."""


@dataclass(frozen=True, slots=True)
class Route:
    """Waypoints in driving order, the index of the one the vehicle heads for, and the mission's home (not a waypoint)."""

    waypoints: tuple[Waypoint, ...] = ()
    current: int = 0
    home: Home | None = None

    def __post_init__(self) -> None:
        if not 0 <= self.current <= len(self.waypoints):
            raise ValueError(f"current waypoint {self.current} outside a route of {len(self.waypoints)}")

    def __len__(self) -> int:
        return len(self.waypoints)

    @property
    def finished(self) -> bool:
        """Every waypoint is behind the vehicle (or there is none)."""
        return self.current >= len(self.waypoints)


# -- home ------------------------------------------------------------------------------------------


def set_home(route: Route, lat: float, lon: float) -> Route:
    """Home at ``lat``, ``lon`` (SET_HOME); the waypoints stay. The home's heading (where a simulated vehicle faces) is kept."""
    heading = route.home.heading_deg if route.home is not None else 0.0
    try:
        home = Home(lat=float(lat), lon=float(lon), heading_deg=heading)
    except ValidationError as exc:
        raise RouteError(f"no home at {lat}, {lon}: {_why(exc)}") from None
    return replace(route, home=home)


# -- adding and removing ---------------------------------------------------------------------------


def new_waypoint(lat: float, lon: float, alt_m: float = 0.0) -> Waypoint:
    """A waypoint to add; RouteError when the position is not one."""
    try:
        return Waypoint(lat=float(lat), lon=float(lon), alt_m=float(alt_m))
    except ValidationError as exc:
        raise RouteError(f"no waypoint at {lat}, {lon}: {_why(exc)}") from None


def add(route: Route, waypoint: Waypoint, after: int | None = None) -> Route:
    """``waypoint`` after the waypoint at index ``after`` (ADD_WP): -1 puts it first, None last.

    Inserted behind the vehicle (before the waypoint it heads for), the vehicle keeps heading for
    the same waypoint; inserted in the leg being driven (right before that waypoint) or anywhere
    ahead, it is driven: a finished route gets a leg to drive again.
    """
    n = len(route)
    after = n - 1 if after is None else after
    if not -1 <= after < n:
        raise RouteError(f"no waypoint {after + 1} to add after: the route has {n} (0 adds before the first)")
    at = after + 1
    current = route.current + 1 if at < route.current else route.current
    return replace(route, waypoints=(*route.waypoints[:at], waypoint, *route.waypoints[at:]), current=current)


def add_at_end(route: Route, waypoint: Waypoint) -> Route:
    """``waypoint`` after the last one (ADD_WP, use_last); a finished route gets a leg to drive again."""
    return add(route, waypoint)


def add_after_current(route: Route, waypoint: Waypoint) -> Route:
    """``waypoint`` right after the current one (ADD_WP, use_current): driven once the current one is reached."""
    index = current_index(route)
    return add(route, waypoint, -1 if index is None else index)


def remove(route: Route, index: int) -> Route:
    """Without the waypoint at ``index`` (REMOVE_WP, seq); the vehicle keeps heading for the same one, or the next."""
    n = len(route)
    if not 0 <= index < n:
        raise RouteError(f"no waypoint {index + 1} to remove: the route has {n}")
    current = route.current - 1 if index < route.current else route.current
    return replace(route, waypoints=route.waypoints[:index] + route.waypoints[index + 1 :], current=min(current, n - 1))


def current_index(route: Route) -> int | None:
    """The waypoint "current" means: the one the vehicle heads for, the last once the route is finished; None if empty."""
    if not route.waypoints:
        return None
    return min(route.current, len(route) - 1)


def remove_current(route: Route) -> Route:
    """Without the current waypoint (REMOVE_WP, use_current): the vehicle heads for the next one."""
    index = current_index(route)
    if index is None:
        raise RouteError("the route is empty: no waypoint to remove")
    return remove(route, index)


def remove_last(route: Route) -> Route:
    """Without the last waypoint (REMOVE_WP, use_last)."""
    if not route.waypoints:
        raise RouteError("the route is empty: no waypoint to remove")
    return remove(route, len(route) - 1)


def clear(route: Route) -> Route:
    """No waypoints (CLEAR_MISSION); home stays."""
    return replace(route, waypoints=(), current=0)


# -- reshaping -------------------------------------------------------------------------------------


def backwards(route: Route) -> Route:
    """The waypoints in reverse order (BACKWARDS_MISSION; home is not a waypoint and stays).

    The vehicle keeps heading for the same waypoint, then drives back the way it came; a finished
    route stays finished (started again, the reversed route is driven from its new first waypoint).
    """
    n = len(route)
    if n == 0:
        raise RouteError("the route is empty: nothing to reverse")
    return replace(route, waypoints=route.waypoints[::-1], current=n - 1 - route.current if route.current < n else n)


def offset(route: Route, distance_m: float, bearing_deg: float, index: int | None = None) -> Route:
    """Every waypoint (or the one at ``index``) moved ``distance_m`` toward the compass bearing ``bearing_deg`` (OFFSET_MISSION).

    Along the rhumb line: the same compass bearing all the way, as GPS drift between days shifts a
    whole route. A negative distance moves the other way.
    """
    _finite(distance_m=distance_m, bearing_deg=bearing_deg)
    if abs(distance_m) > MAX_REACH_M:
        raise RouteError(f"an offset of {distance_m / 1000:g} km is over {MAX_REACH_M / 1000:g} km")
    if not route.waypoints:
        raise RouteError("the route is empty: nothing to offset")
    if index is not None and not 0 <= index < len(route):
        raise RouteError(f"no waypoint {index + 1} to offset: the route has {len(route)}")
    waypoints = list(route.waypoints)
    for i in range(len(route)) if index is None else (index,):
        wp = waypoints[i]
        try:
            waypoints[i] = _at(wp, *geo.rhumb_destination(wp.lat, wp.lon, bearing_deg, distance_m))
        except ValueError as exc:
            raise RouteError(f"waypoint {i + 1}: {exc}") from None
    return replace(route, waypoints=tuple(waypoints))


def centre(route: Route) -> tuple[float, float]:
    """The centre (lat, lon) of the route's latitude/longitude bounding box: what scale_rotate and mirror turn about."""
    if not route.waypoints:
        raise RouteError("the route is empty: it has no centre")
    return geo.bounding_box_centre([(wp.lat, wp.lon) for wp in route.waypoints])


def scale_rotate(route: Route, scale: float, angle_deg: float, about: tuple[float, float] | None = None) -> Route:
    """Every waypoint's distance from the centre times ``scale``, its bearing from there plus ``angle_deg`` (SCALE_ROTATE_MISSION).

    Positive angles turn clockwise, as compass bearings go. The centre is ``about`` (lat, lon), by
    default the route's :func:`centre`. The default centre of the result may differ from the one used
    (a bounding box turned is another box): to undo an edit exactly, give the same centre back.
    """
    _finite(scale=scale, angle_deg=angle_deg)
    if scale <= 0.0:
        raise RouteError(f"scale {scale:g}: must be greater than 0")
    return _polar(route, about, lambda s, azi: (s * scale, azi + angle_deg), "scale or rotate")


def mirror(route: Route, bearing_deg: float, about: tuple[float, float] | None = None) -> Route:
    """Every waypoint reflected across the axis through the centre with the compass bearing ``bearing_deg`` (MIRROR_MISSION).

    The centre is ``about`` (lat, lon), by default the route's :func:`centre`; as for
    :func:`scale_rotate`, give the same centre back to undo it exactly.
    """
    _finite(bearing_deg=bearing_deg)
    return _polar(route, about, lambda s, azi: (s, 2.0 * bearing_deg - azi), "mirror")


def _polar(route: Route, about: tuple[float, float] | None, transform: Callable[[float, float], tuple[float, float]], what: str) -> Route:
    """Each waypoint's geodesic (distance, bearing) from the centre through ``transform``, and back to a position."""
    if not route.waypoints:
        raise RouteError(f"the route is empty: nothing to {what}")
    lat0, lon0 = centre(route) if about is None else _checked_point(about, "centre")
    waypoints = []
    for i, wp in enumerate(route.waypoints):
        distance, bearing = transform(*geo.distance_bearing(lat0, lon0, wp.lat, wp.lon))
        if distance > MAX_REACH_M:
            raise RouteError(f"waypoint {i + 1} would be {distance / 1000:.0f} km from the centre: over {MAX_REACH_M / 1000:g} km")
        waypoints.append(_at(wp, *geo.destination(lat0, lon0, bearing, distance)))
    return replace(route, waypoints=tuple(waypoints))


# -- an operator's request -------------------------------------------------------------------------

#: The operations :func:`apply` knows, and the thesis's names for them.
OPERATIONS = ("set_home", "add", "remove", "clear", "backwards", "offset", "scale_rotate", "mirror")
ALIASES = {
    "add_wp": "add", "remove_wp": "remove", "clear_mission": "clear", "backwards_mission": "backwards",
    "offset_mission": "offset", "scale_rotate_mission": "scale_rotate", "mirror_mission": "mirror",
}  # fmt: skip
_ARGUMENTS = {
    "set_home": ("lat", "lon"),
    "add": ("after", "lat", "lon", "alt_m"),
    "remove": ("waypoint",),
    "clear": (),
    "backwards": (),
    "offset": ("distance_m", "bearing_deg", "waypoint"),
    "scale_rotate": ("scale", "angle_deg", "centre"),
    "mirror": ("bearing_deg", "centre"),
}


def operation_name(name: object) -> str:
    """``"SCALE_ROTATE_MISSION"``, ``"scale-rotate"`` -> ``"scale_rotate"``; RouteError for an unknown one."""
    key = str(name).strip().lower().replace("-", "_")
    key = ALIASES.get(key, key)
    if key not in OPERATIONS:
        raise RouteError(f"unknown route operation {name!r} (known: {', '.join(OPERATIONS)})")
    return key


def apply(route: Route, operation: object, args: Mapping[str, Any], here: Callable[[], tuple[float, float]]) -> tuple[Route, str]:
    """An operator's request on ``route``: the new route and what was done, in words.

    ``args`` by operation (waypoint numbers are 1-based; a position defaults to the vehicle's, from ``here()``):

    - ``set_home``: ``lat``, ``lon``;
    - ``add``: ``after`` (``"end"``, the default, ``"current"``, or a number: 0 adds before the first), ``lat``, ``lon``, ``alt_m``;
    - ``remove``: ``waypoint`` (``"last"``, ``"current"`` or a number);
    - ``clear``, ``backwards``: nothing;
    - ``offset``: ``distance_m``, ``bearing_deg``, ``waypoint`` (a number; default every waypoint);
    - ``scale_rotate``: ``scale``, ``angle_deg``, ``centre`` ([lat, lon]; default the bounding box's);
    - ``mirror``: ``bearing_deg`` (of the axis), ``centre``.

    ``here`` may raise RouteError (no position). Unknown or missing arguments are refused.
    """
    op = operation_name(operation)
    unknown = sorted(set(args) - set(_ARGUMENTS[op]))
    if unknown:
        raise RouteError(f"{op} takes {', '.join(_ARGUMENTS[op]) or 'no arguments'}, not {', '.join(unknown)}")
    n = len(route)
    if op == "set_home":
        lat, lon, where = _position(args, here)
        new = set_home(route, lat, lon)
        return new, f"home set to {lat:.7f}, {lon:.7f}{where}"
    if op == "add":
        lat, lon, where = _position(args, here)
        waypoint = new_waypoint(lat, lon, _number(args, "alt_m", 0.0))
        after = args.get("after", "end")
        if after == "end":
            new = add_at_end(route, waypoint)
        elif after == "current":
            new = add_after_current(route, waypoint)
        else:
            new = add(route, waypoint, _waypoint_number(after, "after", allow_zero=True) - 1)
        number = next(i for i, wp in enumerate(new.waypoints) if wp is waypoint) + 1
        return new, f"waypoint {number}/{n + 1} added at {lat:.7f}, {lon:.7f}{where}"
    if op == "remove":
        which = args.get("waypoint")
        if which == "last":
            index = n - 1
        elif which == "current":
            index = current_index(route)
        else:
            index = _waypoint_number(which, "waypoint") - 1
        if index is None or index < 0:
            raise RouteError("the route is empty: no waypoint to remove")
        return remove(route, index), f"waypoint {index + 1}/{n} removed"
    if op == "clear":
        return clear(route), f"route cleared ({n} waypoints removed)"
    if op == "backwards":
        new = backwards(route)
        return new, f"route reversed ({n} waypoints)"
    if op == "offset":
        distance, bearing = _number(args, "distance_m"), _number(args, "bearing_deg")
        which = args.get("waypoint")
        index = None if which is None else _waypoint_number(which, "waypoint") - 1
        what = f"{n} waypoints" if index is None else f"waypoint {index + 1}"
        return offset(route, distance, bearing, index), f"{what} offset {distance:g} m toward {bearing % 360:05.1f}°"
    about = _centre_arg(args.get("centre"), route)
    at = f"{about[0]:.7f}, {about[1]:.7f}"
    if op == "scale_rotate":
        scale, angle = _number(args, "scale"), _number(args, "angle_deg")
        return scale_rotate(route, scale, angle, about), f"{n} waypoints scaled by {scale:g} and rotated {angle:g}° about {at}"
    bearing = _number(args, "bearing_deg")
    return mirror(route, bearing, about), f"{n} waypoints mirrored across the {bearing % 180:05.1f}° axis through {at}"


# -- internals -------------------------------------------------------------------------------------


def _at(waypoint: Waypoint, lat: float, lon: float) -> Waypoint:
    """The same waypoint (speed, depth, name...) at another position."""
    return waypoint.model_copy(update={"lat": lat, "lon": lon})


def _why(exc: ValidationError) -> str:
    error = exc.errors()[0]
    return f"{'.'.join(str(p) for p in error['loc'])}: {error['msg']}"


def _finite(**values: float) -> None:
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise RouteError(f"{name} must be a finite number, not {value!r}")


def _number(args: Mapping[str, Any], name: str, default: float | None = None) -> float:
    value = args.get(name, default)
    if value is None:
        raise RouteError(f"{name} is needed")
    _finite(**{name: value})
    return float(value)


def _waypoint_number(value: object, name: str, allow_zero: bool = False) -> int:
    if isinstance(value, str) and value.strip().lstrip("+").isdigit():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or value < (0 if allow_zero else 1):
        words = '"last", "current"' if name == "waypoint" else '"end", "current"'
        raise RouteError(f"{name} must be {words} or a waypoint number from {0 if allow_zero else 1}, not {value!r}")
    return value


def _position(args: Mapping[str, Any], here: Callable[[], tuple[float, float]]) -> tuple[float, float, str]:
    """(lat, lon, words) from ``lat`` and ``lon`` if given (both), else the vehicle's position."""
    if "lat" in args or "lon" in args:
        return _number(args, "lat"), _number(args, "lon"), ""
    lat, lon = here()
    return lat, lon, " (the vehicle's position)"


def _checked_point(point: object, name: str) -> tuple[float, float]:
    if not isinstance(point, list | tuple) or len(point) != 2:
        raise RouteError(f"{name} must be [lat, lon], not {point!r}")
    lat, lon = point
    _finite(**{f"{name} latitude": lat, f"{name} longitude": lon})
    if not -90.0 <= lat <= 90.0:
        raise RouteError(f"{name} latitude {lat:g} is outside [-90, 90]")
    return float(lat), float(lon)


def _centre_arg(value: object, route: Route) -> tuple[float, float]:
    return centre(route) if value is None else _checked_point(value, "centre")
