"""The route the mission drives and how far along it the vehicle is: the one writer of the leg keys of ``/mission``.

The current leg lives here, not in the tree: a guard that fails and recovers resumes the same leg.
The lifecycle (:class:`~executive.mission.lifecycle.MissionState`) decides when the route may
change or a leg end, and who hears of it; this holds the mission's waypoints and the leg.
"""

from __future__ import annotations

from executive.mission.model import Mission, Waypoint
from executive.mission.route import Route
from executive.world import blackboard


class RouteProgress:
    """The loaded mission (its waypoints and home) and the index of the waypoint the vehicle heads for."""

    def __init__(self) -> None:
        self._bb = blackboard.writer("route progress", ["/mission/leg_index", "/mission/leg_count", "/mission/target", "/mission/next_target"])
        self.mission: Mission | None = None
        self.leg_index = 0
        #: A leg is being driven (the mission RUNNING or PAUSED): only then is there a target. The lifecycle says so.
        self.active = False

    def load(self, mission: Mission | None, leg_index: int = 0) -> None:
        self.mission, self.leg_index = mission, leg_index

    @property
    def leg_count(self) -> int:
        return len(self.mission.waypoints) if self.mission else 0

    @property
    def leg_number(self) -> int:
        """The leg as a person counts it, as the status shows it (``leg 2/2``): from 1, the last one once past it (a VTOL landing)."""
        return min(self.leg_index + 1, self.leg_count)

    @property
    def route(self) -> Route:
        """The mission's waypoints and the current leg (the input of a route operation)."""
        waypoints = tuple(self.mission.waypoints) if self.mission else ()
        return Route(waypoints, min(self.leg_index, len(waypoints)), self.mission.home if self.mission else None)

    @property
    def target(self) -> Waypoint | None:
        """The waypoint of the current leg, while a leg is :attr:`active`."""
        if self.mission is None or not self.active or self.leg_index >= self.leg_count:
            return None
        return self.mission.waypoints[self.leg_index]

    @property
    def next_target(self) -> Waypoint | None:
        """The waypoint after the current leg's, if there is one (the leg may be driven through toward it)."""
        if self.target is None or self.leg_index + 1 >= self.leg_count:
            return None
        assert self.mission is not None
        return self.mission.waypoints[self.leg_index + 1]

    def advance(self) -> None:
        """The current leg is done: head for the next waypoint (the last index once past the end)."""
        self.leg_index = min(self.leg_index + 1, self.leg_count)

    def publish(self) -> None:
        self._bb.set("/mission/leg_index", self.leg_index)
        self._bb.set("/mission/leg_count", self.leg_count)
        self._bb.set("/mission/target", self.target)
        self._bb.set("/mission/next_target", self.next_target)
