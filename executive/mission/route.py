"""Route operations: pure functions from one route to the next (the tracked UGV's ``mission_manip``).

A :class:`Route` is the waypoints and the leg being driven: ``current`` is the index of the waypoint
the vehicle heads for, ``len(waypoints)`` once the route is finished. Every operation returns a new
route and leaves its argument alone; one that cannot apply raises :class:`RouteError` saying why,
for the operator. The mission state keeps the result (``MissionState.set_route``); something else
writes it to the autopilot.

The operations the RC switches use: :func:`add_at_end`, :func:`remove_current` (and :func:`remove`
by index), :func:`clear`. Each keeps ``current`` on the same waypoint where it still exists.
"""

from __future__ import annotations

from dataclasses import dataclass

from executive.mission.model import Waypoint


class RouteError(ValueError):
    """A route operation that cannot apply to this route; ``str()`` says why."""


@dataclass(frozen=True, slots=True)
class Route:
    """Waypoints in driving order and the index of the one the vehicle heads for."""

    waypoints: tuple[Waypoint, ...] = ()
    current: int = 0

    def __post_init__(self) -> None:
        if not 0 <= self.current <= len(self.waypoints):
            raise ValueError(f"current waypoint {self.current} outside a route of {len(self.waypoints)}")

    def __len__(self) -> int:
        return len(self.waypoints)

    @property
    def finished(self) -> bool:
        """Every waypoint is behind the vehicle (or there is none)."""
        return self.current >= len(self.waypoints)


def add_at_end(route: Route, waypoint: Waypoint) -> Route:
    """``waypoint`` after the last one (ADD_WP, use_last); a finished route gets a leg to drive again."""
    return Route((*route.waypoints, waypoint), route.current)


def remove(route: Route, index: int) -> Route:
    """Without the waypoint at ``index`` (REMOVE_WP, seq); the vehicle keeps heading for the same one, or the next."""
    n = len(route)
    if not 0 <= index < n:
        raise RouteError(f"no waypoint {index + 1} to remove: the route has {n}")
    current = route.current - 1 if index < route.current else route.current
    return Route(route.waypoints[:index] + route.waypoints[index + 1 :], min(current, n - 1))


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


def clear(route: Route) -> Route:
    """No waypoints (CLEAR_MISSION); home stays the autopilot's."""
    return Route()
