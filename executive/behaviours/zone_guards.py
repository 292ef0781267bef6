"""The keep-out zones at run time: the vehicle inside one, or heading into one before it could stop (failsafe ``keep_out``).

The route was checked against the zones before it was driven (:mod:`executive.mission.zones`), so a
vehicle meets a zone only off its route: a person drove it, a current or the wind set it, a
take-over ended there. :class:`OutsideKeepOut` fails when the vehicle is inside a zone, or when the
straight line ahead of it at its velocity, as long as it needs to stop, enters one. That horizon is
the distance covered while the hold is asked and taken (:data:`REACT_S`) plus the distance the
vehicle coasts to a stop in it (:data:`COAST_M_S2`): ``v * 1 s + v^2 / 1 m/s^2``, 6 m (4 s) at 2 m/s, 30 m
(7 s) at 5 m/s. A shorter look would let the vehicle coast in; a longer one would stop it for zones it
was turning away from.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from executive.behaviours.guards import Guard
from executive.behaviours.position_guards import POSITION_RULE
from executive.mission.model import Mission
from executive.mission.zones import Plane, Zones
from executive.world.state import GlobalPosition

if TYPE_CHECKING:
    import shapely

#: From the tick the guard fails to the vehicle braking: the hold asked that tick, its ack and the firmware's mode change within a
#: round trip, and a position report 0.2 s old (GLOBAL_POSITION_INT at 5 Hz). One second covers them with a heartbeat to spare.
REACT_S = 1.0
#: How fast a held vehicle slows, m/s^2. ArduRover's HOLD does not brake: it sets the throttle and the steering to zero and the
#: vehicle coasts (Rover/mode_hold.cpp ModeHold::update), slowed by its own drag; a rover stops within a few metres, a boat
#: glides further. 0.5 m/s^2 is a light hull's coast-down (the lock-step simulated rover, cut at 1.4 m/s, stood ~2.4 m on).
COAST_M_S2 = 0.5


def stopping_m(speed_m_s: float) -> float:
    """How far ahead a vehicle at ``speed_m_s`` still goes before it stands: reaction, then coasting in its hold."""
    return speed_m_s * REACT_S + speed_m_s**2 / (2.0 * COAST_M_S2)


class OutsideKeepOut(Guard):
    """The vehicle is outside every keep-out zone and will stay out if it is held now: not inside one, and the line it covers
    before it can stop (:func:`stopping_m` at its ground speed, along its velocity) enters none.

    Debounce: fails at once (a zone ahead is met within seconds); passes after 2 s clear.
    """

    reads = ("/vehicle/position",)
    resume_after_s = 2.0
    unknown_or_stale = POSITION_RULE
    catalogued = False  # made with the mission's zones by failsafe_guards

    def __init__(self, mission: Mission, name: str = "Outside keep-out zones?") -> None:
        super().__init__(name)
        self.mission = mission
        self._zones: Zones | None = None  # made at the first position: the plane centred there

    def awaits(self) -> str | None:
        return "a position (GLOBAL_POSITION_INT)" if self.get("/vehicle/position") is None else None

    def check(self) -> str | None:
        import shapely

        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        if self._zones is None:
            self._zones = Zones(self.mission, Plane((position.lat, position.lon)))
        zones = self._zones
        here = zones.plane.xy([position.lat], [position.lon])[0]
        speed = position.ground_speed_m_s
        ahead = stopping_m(speed)
        point = shapely.points(here)
        for area in zones.keep_out:
            if shapely.intersects(point, area.shape):
                return f"inside {area.label}"
        if speed < 0.05:
            return None
        end = here + ahead * np.array([position.ve_m_s, position.vn_m_s]) / speed
        path: shapely.Geometry = shapely.linestrings([here, end])
        for area in zones.keep_out:
            if shapely.intersects(path, area.shape):
                gap = float(shapely.distance(point, area.shape))
                return f"heading into {area.label}: {gap:.1f} m ahead at {speed:.1f} m/s (stops in {ahead:.1f} m)"
        return None


def outside_keep_out(mission: Mission, name: str = "Outside keep-out zones?") -> OutsideKeepOut | None:
    """The :class:`OutsideKeepOut` guard for a mission with keep-out zones; None without any."""
    if mission.geofence is None or not mission.geofence.keep_out:
        return None
    return OutsideKeepOut(mission, name)
