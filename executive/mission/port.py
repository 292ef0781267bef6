"""The mission as a behaviour sees it: what it may know, and the outcomes it reports; never the mission itself.

A behaviour never writes the mission. It reports what it saw happen (a leg done, a sample taken,
a person's route edit read off the RC switches, something a person must hear) through this port;
the mission's state (:class:`~executive.mission.lifecycle.MissionState`, the one writer of
``/mission``) applies the outcome at once, in the same tick, or refuses it
(:class:`~executive.mission.lifecycle.Refused`, nothing changed). It is handed to the tree as the
``mission_state`` service (``MissionPort(state)``).
"""

from __future__ import annotations

from collections.abc import Sequence

from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission, Waypoint
from executive.mission.route import Route
from executive.mission.status import MissionStatus
from executive.world.state import SampleRecord


class MissionPort:
    """Read the mission's lifecycle, route and samples; report a behaviour's outcomes to them."""

    def __init__(self, state: MissionState) -> None:
        self._state = state

    # -- what a behaviour may know -----------------------------------------------------------
    @property
    def status(self) -> MissionStatus:
        return self._state.status

    @property
    def reason(self) -> str:
        return self._state.reason

    @property
    def hold_while_paused(self) -> bool:
        """While PAUSED the tree holds the vehicle; False when a person paused it by taking the vehicle: hands off."""
        return self._state.hold_while_paused

    @property
    def mission(self) -> Mission | None:
        return self._state.mission

    @property
    def leg_index(self) -> int:
        return self._state.legs.leg_index

    @property
    def leg_count(self) -> int:
        return self._state.legs.leg_count

    @property
    def leg_number(self) -> int:
        return self._state.legs.leg_number

    @property
    def target(self) -> Waypoint | None:
        return self._state.legs.target

    @property
    def next_target(self) -> Waypoint | None:
        return self._state.legs.next_target

    @property
    def route(self) -> Route:
        return self._state.legs.route

    def sampled(self, leg_index: int) -> bool:
        return self._state.sample_log.sampled(leg_index)

    # -- what it reports ---------------------------------------------------------------------
    def leg_done(self) -> None:
        """The current leg is done (reached, or the autopilot reported it): the mission heads for the next waypoint."""
        self._state.advance_leg()

    def sample_taken(self, sample: SampleRecord) -> None:
        """A sample was taken at its leg: the mission keeps it (refused for a leg already sampled)."""
        self._state.record_sample(sample)

    def route_edited(
        self, waypoints: Sequence[Waypoint], reason: str, *, leg_index: int | None = None, vehicle_at: tuple[float, float] | None = None
    ) -> None:
        """A person edited the route (the RC switches): the mission takes it, or refuses it when it breaks the mission's rules."""
        self._state.set_route(waypoints, reason, leg_index=leg_index, vehicle_at=vehicle_at)

    def announce(self, text: str, warning: bool = True) -> None:
        """What a person must hear now (a failsafe's step): told to the ground station as a STATUSTEXT."""
        self._state.announce(text, warning)
