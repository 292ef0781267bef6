"""The distance rule, checked by the runtime before any tree runs: every waypoint within ``limits.max_goal_distance_m`` of the vehicle.

The seed systems refuse a goal too far from where the vehicle is (the ASV's 5 km, the AUV's 1 km,
``limits.max_goal_distance_m``). ``executive validate`` checks it against the mission's ``home:``
(:func:`executive.mission.model.cross_field_errors`) and an upload against the vehicle's position
when the EKF vouches for it (:meth:`executive.mission.lifecycle.MissionState.upload`). A tree
cannot be trusted to check it at start: a user's tree may leave it out. So the runtime holds back
a starting mission's tree until the vehicle's position is known and every waypoint still to drive
is within the limit of it: nothing is armed, no mode set, nothing sent before. A mission out of
reach is refused (it ends ABORTED with the waypoints and their distances) with nothing commanded,
so nothing is undone either; a position that never comes within ``limits.ekf_wait_s`` refuses it too.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

from executive.mission.lifecycle import MissionState, out_of_reach
from executive.mission.zones import first_leg_problems
from executive.tree.waiting import Waiting
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import EkfStatus, GlobalPosition

log = logging.getLogger("executive.reach")  # the name the log and the journal show, kept since 0.1

#: The name the distance rule goes by in the status (``waiting: Within reach (3 s): ...``) and in the refusal.
NAME = "Within reach"


@dataclass(frozen=True)
class Refusal:
    """A starting mission refused by the distance rule; ``reason`` names the waypoints and their distances (or the missing position)."""

    reason: str


class ReachGate:
    """Before a starting mission's tree first ticks: the vehicle's position, then every waypoint still to drive within reach of it.

    :meth:`close` when a tree is installed (a mission starting, or replacing a paused one);
    :meth:`judge` each tick until it opens (None: open, the tree may tick; ``WAIT``: not yet, the
    tree must not tick; a :class:`Refusal`: the mission must end, nothing commanded).

    What it waits for goes to ``show`` (the tree watch, the one writer of ``/mission/waiting``): a
    :class:`~executive.tree.waiting.Waiting` while it holds the tree back, None once it opens.
    """

    WAIT = "wait"

    def __init__(self, clock: Clock, show: Callable[[Waiting | None], object] = lambda waiting: None) -> None:
        self._clock = clock
        self._bb = blackboard.reader("reach gate", ["/vehicle/position", "/vehicle/ekf"])
        self._show = show
        self._closed_at: float | None = None

    @property
    def open(self) -> bool:
        """The tree may tick: the rule has passed for this mission (or no mission was started)."""
        return self._closed_at is None

    def close(self) -> None:
        """A mission's tree was installed: hold it back until :meth:`judge` has checked the rule."""
        self._closed_at = self._clock.now()

    def judge(self, state: MissionState) -> Refusal | str | None:
        """None once the rule passes (the gate opens); ``WAIT`` while the position is unknown; a :class:`Refusal` otherwise."""
        if self._closed_at is None:
            return None
        mission = state.mission
        assert mission is not None
        limits = mission.limits
        ahead = state.legs.leg_index  # the waypoints already reached are goals no more (a run resumed after a crash)
        if ahead >= len(mission.waypoints):
            return self._pass()
        position: GlobalPosition | None = self._bb.get("/vehicle/position")
        ekf: EkfStatus | None = self._bb.get("/vehicle/ekf")
        far = [] if position is None else out_of_reach(mission, position.lat, position.lon, first=ahead)
        crossing = [] if position is None else first_leg_problems(mission, position.lat, position.lon, first=ahead)
        # ArduPilot sends GLOBAL_POSITION_INT whether or not it has a position (GCS_Common.cpp send_global_position_int: "we
        # send stale data"); before a fix ArduPlane's DCM dead-reckons from 0, 0 on its airspeed (AP_AHRS_DCM.cpp
        # drift_correction): seen on real ArduPlane SITL, 14960 km from its waypoints. A refusal needs a position the EKF
        # vouches for; one it disowns that puts the route out of reach is waited out (the tree's EKF guard holds every move).
        disowned = ekf is not None and not ekf.position_ok()
        if position is None or (far and disowned):
            waited = self._clock.now() - self._closed_at
            rule = f"every waypoint must be within {limits.max_goal_distance_m:g} m of the vehicle (limits.max_goal_distance_m)"
            if waited > limits.ekf_wait_s:
                return Refusal(f"{NAME}: no position (that the EKF vouches for) within {limits.ekf_wait_s:g} s (limits.ekf_wait_s): {rule}")
            why = "no position yet"
            if position is not None and ekf is not None:
                why += f": EKF has no position estimate (flags {int(ekf.flags):#x})"
            self._show(Waiting(NAME, NAME, f"{why}: {rule}", self._closed_at))  # no tree ticks yet: the gate says what the mission waits for
            return self.WAIT
        if far or crossing:  # the leg from where the vehicle is to its first waypoint, against the keep-out zones (executive.mission.zones)
            return Refusal(f"{NAME}: " + "; ".join(far + crossing))
        return self._pass()

    def _pass(self) -> None:
        self._closed_at = None
        self._show(None)
