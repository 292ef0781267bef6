"""The executive's own return: hold, then GUIDED legs to the nearest rally point or home around the keep-out zones.

A failsafe's ``rtl`` reaction asks the firmware's RTL where that goes where the mission means: the
straight line home (ArduRover ``Rover/mode_rtl.cpp`` ModeRTL::_enter: the destination is home,
``rover.home``, driven as one straight AR_WPNav leg; PX4's AUTO.RTL likewise goes straight to home
or its own rally points, ``navigator/rtl.cpp``). It knows nothing of the mission's keep-out zones
nor of its rally points (the autopilot's own copies are uploaded only with ``geofence.autopilot``).
So a rover or a boat on a mission with keep-out zones or rally points returns by
:class:`ReturningDrive` instead, unless the way is the firmware's: to home, on a straight line that
touches no zone, and not for ``keep_out`` itself (a vehicle at a zone's edge is stopped before it is
turned: RTL turns at speed). The way is planned once, when the return starts
(:class:`~executive.mission.return_path.ReturnPlanner`), from where the vehicle stands after the hold.

Steps: the hold (the failsafe's own reaction, asked and verified as any) until the vehicle stands
(or :data:`STOP_WAIT_S`); GUIDED, asked and verified as a reaction; each point of the way sent as a
GUIDED target (re-sent every second: ArduPilot drops a target silently outside GUIDED), the next one
once within the acceptance radius; at the last, the hold again.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.common import Status

from executive.autopilot import Target
from executive.autopilot.asking import Announce, Asker, Host
from executive.behaviours.base import FAILURE, SUCCESS
from executive.mission.declaration import vehicle_profile
from executive.mission.return_path import ReturnPath, ReturnPlanner
from executive.world import geo
from executive.world.state import GlobalPosition, HomePosition

log = logging.getLogger("executive.behaviours.failsafe")  # the journal's event kind: "failsafe"

#: Standing: slower than this (m/s) the vehicle has stopped in its hold, and the way is planned from where it is.
STANDING_M_S = 0.3
#: The hold is waited for at most this long (vehicle seconds) before the way is planned from where the vehicle is.
STOP_WAIT_S = 15.0
#: A GUIDED target is sent again this often (vehicle seconds), as GoTo does.
RESEND_S = 1.0


def _home(host: Host, mission_home: tuple[float, float] | None) -> tuple[float, float] | None:
    home: HomePosition | None = host.get("/vehicle/home")
    return (home.lat, home.lon) if home is not None else mission_home


def why_not_rtl(planner: ReturnPlanner, condition: str, position: GlobalPosition | None, home: tuple[float, float] | None) -> str | None:
    """Why the firmware's RTL will not do for this return (None: it will): its straight line home crosses a zone, a rally point is
    nearer, or the condition is keep_out itself."""
    if not planner.needed or position is None:
        return None
    path = planner.plan(position.lat, position.lon, home)
    if path is None:
        return None
    if condition == "keep_out":
        return "at a keep-out zone: stopped first, then driven around it"
    if path.to != "home":
        return f"{path.to} is nearer than home"
    if not path.straight:
        return "its straight line home crosses a keep-out zone"
    return None


@dataclass
class _Leg:
    index: int
    started: float
    sent_at: float = float("-inf")


class ReturningDrive:
    """One return driven by the executive for ``host`` (a failsafe): :meth:`follow` each tick until :attr:`arrived`."""

    def __init__(
        self,
        host: Host,
        vehicle: str,
        planner: ReturnPlanner,
        cause: str,
        hold_mode: str,
        *,
        reach_m: float,
        leg_timeout_s: float,
        announce: Announce | None = None,
    ) -> None:
        self.host, self.vehicle, self.planner, self.cause = host, vehicle, planner, cause
        self.hold_mode, self.reach_m, self.leg_timeout_s, self.announce = hold_mode, reach_m, leg_timeout_s, announce
        self.mission_home = (planner.mission.home.lat, planner.mission.home.lon) if planner.mission.home else None
        self.path: ReturnPath | None = None
        self.started = host.clock.now()
        self._guided = Asker(host, vehicle, announce=announce, escalate=False)
        self._leg: _Leg | None = None
        self.arrived = False
        self.failed: str | None = None  # no way found, or a leg not reached in time: the vehicle is left in its hold
        self._end = ""

    @property
    def guided_mode(self) -> str:
        return vehicle_profile(self.vehicle).guided_mode

    @property
    def tickets(self) -> list[Any]:
        return self._guided.tickets

    def follow(self, now: float, held: bool) -> str:
        """One tick of the return (``held``: the failsafe's hold is done); what it is doing, for the feedback."""
        position: GlobalPosition | None = self.host.get("/vehicle/position")
        if self.arrived or self.failed is not None:  # held there: the hold asked until the autopilot shows it
            self._guided.follow_up(now)
            return self._end
        if self.path is None:
            standing = position is not None and position.ground_speed_m_s < STANDING_M_S
            if not ((held and standing) or now - self.started > STOP_WAIT_S) or position is None:
                return f"holding before the return ({position.ground_speed_m_s:.1f} m/s)" if position else "holding before the return"
            self.path = self.planner.plan(position.lat, position.lon, _home(self.host, self.mission_home))
            if self.path is None:
                self.failed = self._end = "no way to a rally point or home around the keep-out zones"
                log.warning("failsafe %s: %s -> left in %s", self.cause, self.failed, self.hold_mode)
                return self.failed
            log.warning("failsafe %s: return to %s", self.cause, self.path.describe())
            if self.announce is not None:
                self.announce(f"{self.cause}: return to {self.path.to}"[:50], False)
            self._guided.start(self.guided_mode, self.cause)
            self._leg = _Leg(0, now)
        assert self._leg is not None
        self._guided.follow_up(now)
        point = self.path.points[self._leg.index]
        if position is not None:
            distance = geo.distance(position.lat, position.lon, *point)
            if distance <= self.reach_m:
                if self._leg.index == len(self.path.points) - 1:
                    self.arrived = True
                    log.warning("failsafe %s: returned to %s", self.cause, self.path.to)
                    return self._stop(f"returned to {self.path.describe()}")
                self._leg = _Leg(self._leg.index + 1, now)
                point = self.path.points[self._leg.index]
        if now - self._leg.started > self.leg_timeout_s:
            self.failed = f"leg {self._leg.index + 1}/{len(self.path.points)} of the return to {self.path.to} not reached in {self.leg_timeout_s:g} s"
            log.warning("failsafe %s: %s -> left in %s", self.cause, self.failed, self.hold_mode)
            return self._stop(self.failed)
        if not self._guided.done:
            return f"returning to {self.path.to}: {self._guided.state()}"
        if now - self._leg.sent_at >= RESEND_S:
            self.host.autopilot.go_to(Target(point[0], point[1]))
            self._leg.sent_at = now
        legs = f"leg {self._leg.index + 1}/{len(self.path.points)}"
        far = f", {geo.distance(position.lat, position.lon, *point):.0f} m" if position is not None else ""
        return f"returning to {self.path.to} around the keep-out zones: {legs}{far}"

    def _stop(self, why: str) -> str:
        """Hold the vehicle where the return ended (asked and verified as a reaction); ``why`` is said from now on."""
        self._end = why
        self._guided.start(self.hold_mode, self.cause)
        return why

    def cancel(self) -> None:
        """A person has the vehicle, or the failsafe ended: nothing more is asked."""
        self._guided.cancel()


class NoReturnUnderWay(py_trees.behaviour.Behaviour):
    """FAILURE while ``failsafe`` drives a return that ends the mission, so the guarded work does not resume under it when the
    condition that started the return clears on the way (a vehicle out of the zone is not sent back along its route)."""

    catalogued = False  # made by failsafe_guarded for a mission whose returns are the executive's

    def __init__(self, failsafe: Any, name: str = "No return under way?") -> None:
        super().__init__(name)
        self.failsafe = failsafe

    def update(self) -> Status:
        if self.failsafe.returning:
            self.feedback_message = "returning: the mission ends where the return arrives"
            return FAILURE
        self.feedback_message = ""
        return SUCCESS
