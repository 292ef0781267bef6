"""A mission replaced while paused: its zones and rally points on the autopilot, read back, before it may resume.

The pre-flight's :class:`~executive.behaviours.zones.ZonesOnAutopilot` puts a starting mission's
fence and rally points on the autopilot. A mission replaced while PAUSED (``ctl upload``, hot
reload) is not started: without this the autopilot would go on enforcing the old mission's fence,
and its own RTL and fence action would use the old rally points, the vehicle protected against the
wrong world when the executive is gone. So, at the replacement, the same behaviour is ticked here
(as the route keeper takes the new route to the autopilot at once) with the new mission's fence and
rally points - or empty ones where the new mission has none and the old one had put some there -
sent and read back, and with ``enforce`` the fence parameters set as for a new mission.

Until that is done the mission cannot resume (a resume check: ``ctl resume`` answers why); a
refusal by the autopilot keeps it PAUSED with the reason (nothing of the new mission runs) until
another mission is uploaded in its place.
"""

from __future__ import annotations

import logging

from py_trees.common import Status

from executive.autopilot.port import AutopilotPort
from executive.behaviours.zones import ZonesOnAutopilot, puts_zones_on_autopilot
from executive.mission.events import Replaced, Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.mission.port import MissionPort
from executive.world.clock import Clock

log = logging.getLogger(__name__)


class ReplacedZones:
    """Puts a replacing mission's zones and rally points on the autopilot while it is paused; call :meth:`service` every tick."""

    def __init__(self, mission_state: MissionState, autopilot: AutopilotPort, clock: Clock) -> None:
        self._mission_state = mission_state
        self._autopilot = autopilot
        self._clock = clock
        #: Whether the executive may have put a fence, rally points on the autopilot (a started mission's pre-flight, a replacement):
        #: what a replacing mission without them clears. Only ever widened, but to exactly a replacement's once it is read back.
        self._put = (False, False)
        self._zones: ZonesOnAutopilot | None = None
        self._zones_put = (False, False)
        mission_state.events.subscribe(Transition, self._on_transition, Stage.ZONES)
        mission_state.events.subscribe(Replaced, self._on_replace, Stage.ZONES)
        mission_state.resume_checks.append(self.why_not_resume)

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is not MissionStatus.PAUSED:  # resumed (done here by then), or another mission: its pre-flight takes over
            self._stop()
        mission = self._mission_state.mission
        if after is MissionStatus.RUNNING and before is not MissionStatus.PAUSED and mission is not None:
            self._put = _either(self._put, _puts(mission))

    def _on_replace(self, mission: Mission, reason: str) -> None:
        self._stop()
        sends = puts_zones_on_autopilot(mission)
        geofence = mission.geofence if sends and mission.geofence is not None and mission.geofence.autopilot != "off" else None
        rally = mission.rally_points if sends else []
        clear_fence, clear_rally = self._put[0] and not _has_fence(mission), self._put[1] and not rally
        if not (sends or clear_fence or clear_rally):
            return
        zones = ZonesOnAutopilot(geofence, rally, clear_fence=clear_fence, clear_rally=clear_rally, name="Zones of the replacing mission")
        zones.setup(clock=self._clock, autopilot=self._autopilot, mission_state=MissionPort(self._mission_state))
        self._zones, self._zones_put = zones, _puts(mission)
        self._put = _either(self._put, self._zones_put)  # a refusal part-way may leave the fence new and the rally points old
        self.service()

    def service(self) -> None:
        """Tick the upload until it succeeds or fails (said once)."""
        zones = self._zones
        if zones is None or zones.status in (Status.SUCCESS, Status.FAILURE):
            return
        zones.tick_once()
        if zones.status is Status.FAILURE:
            log.error("the replacing mission cannot resume: its zones are not on the autopilot: %s", zones.feedback_message)
            state = self._mission_state
            state.explain(f"{state.reason}; cannot resume: {self.why_not_resume()}")  # what ctl status says
            state.announce("zones refused: mission stays paused")
        elif zones.status is Status.SUCCESS:
            self._put = self._zones_put  # (the behaviour logs what is held)

    def why_not_resume(self) -> str | None:
        """None when the replacing mission's zones are on the autopilot (or there was nothing to send); else why it may not resume."""
        zones = self._zones
        if zones is None or zones.status is Status.SUCCESS:
            return None
        if zones.status is Status.FAILURE:
            return f"the new mission's zones are not on the autopilot: {zones.feedback_message}; upload a mission it takes"
        return f"the new mission's zones are not yet on the autopilot ({zones.feedback_message or 'starting'}): resume once they are read back"

    def _stop(self) -> None:
        if self._zones is not None and self._zones.status is Status.RUNNING:
            self._zones.stop(Status.INVALID)
        self._zones = None


def _puts(mission: Mission) -> tuple[bool, bool]:
    """(a fence, rally points): what the mission puts on the autopilot."""
    return _has_fence(mission), puts_zones_on_autopilot(mission) and bool(mission.rally_points)


def _either(a: tuple[bool, bool], b: tuple[bool, bool]) -> tuple[bool, bool]:
    return a[0] or b[0], a[1] or b[1]


def _has_fence(mission: Mission) -> bool:
    geofence = mission.geofence
    shapes = geofence is not None and (geofence.polygon is not None or bool(geofence.inclusion) or bool(geofence.keep_out))
    return shapes and geofence is not None and geofence.autopilot != "off"


__all__ = ["ReplacedZones"]
