"""The mission lifecycle: the one place the mission changes, apart from what is told of it.

The mission's state is three small objects, each the one writer of its keys of ``/mission``: the
lifecycle here (``/mission/state``, ``/mission/reason``), the route and the leg the vehicle is on
(:class:`~executive.mission.legs.RouteProgress`) and the samples taken
(:class:`~executive.mission.samples.SampleLog`); :class:`MissionState` alone changes them, on a
request (the operator's, the runtime's) or an outcome a behaviour reports through its port
(:class:`~executive.mission.port.MissionPort`, over this: a behaviour never writes the mission). What happens
is told as events on one stream (:class:`~executive.mission.events.MissionEvents`), whose
subscribers hear it in the order of their declared stage, not of who subscribed first.

States and requests follow the AUV mission manager: upload (IDLE/READY/COMPLETED -> READY, refused
while RUNNING or PAUSED; while PAUSED a mission is *replaced* instead, see below), start (READY ->
RUNNING; COMPLETED -> RUNNING from the first waypoint),
pause (RUNNING -> PAUSED), resume (PAUSED -> RUNNING), delete (READY/PAUSED/COMPLETED -> IDLE; a
running mission is paused first). We add ABORTED, where a failed or interrupted mission ends; it
behaves like COMPLETED. A refused request raises :class:`Refused` and changes nothing.

The route and the current leg are kept by :class:`~executive.mission.legs.RouteProgress` (``state.legs``),
not by the tree: a guard that fails and recovers resumes the same leg.

The samples taken are kept by :class:`~executive.mission.samples.SampleLog` (``state.sample_log``):
:meth:`MissionState.record_sample` is the one way a sample is kept, and ``state.sample_log.sampled(leg)``
tells whether a leg's sample is already taken, so that a Sample action re-entered (a guard recovered,
the mission resumed) never takes it twice. Samples belong to a run: ``upload`` and ``start`` begin
with none. A restarted executive (after a crash) must not take a sample twice either: whoever
restores its progress (the journal) hands the samples it recorded to
:meth:`MissionState.restore_samples` after ``start`` and before the first tick.

Readers read the route, the leg and the samples there (or on the blackboard); the lifecycle's own
``leg_index``, ``target``, ``samples``... of 0.1 warn (:class:`executive.MovedMember`) for one release.

The route itself may change while the mission is loaded (an operator records or edits it):
:meth:`MissionState.set_route` keeps the new route here, so a guard failure or a pause does not lose
it, and tells the stream (:class:`~executive.mission.events.RouteChanged`). The operations that make new routes are in
:mod:`executive.mission.route`. The route carries the mission's home (``Mission.home``, not a
waypoint): SET_HOME changes it through ``set_route(..., home=...)``, and the route keeper (a
subscriber) takes it to the autopilot. An edit that would break the mission's rules (a waypoint
outside the geofence, no waypoint left for a tree that needs one) is refused.

While PAUSED the whole mission may be replaced (hot reload: :meth:`MissionState.replace`, planned
by :mod:`executive.mission.reload`): the state stays PAUSED, at the leg and with the samples the
plan gives. The replace checks are asked first (the runtime builds the new tree there: a tree that
cannot be built refuses the replacement, nothing changed); then the stream tells
(:class:`~executive.mission.events.Replaced`: the runtime swaps the tree, the journal continues the
run on the new mission, the route keeper takes the new route to the autopilot).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Sequence

import executive
from executive.mission.errors import format_path
from executive.mission.events import Announcement, MissionEvents, Replaced, RouteChanged, SampleTaken, Transition
from executive.mission.legs import RouteProgress
from executive.mission.model import Home, Mission, Waypoint
from executive.mission.rules import cross_field_errors
from executive.mission.samples import SampleLog
from executive.mission.status import MissionStatus
from executive.mission.zones import first_leg_problems
from executive.world import blackboard
from executive.world.geo import distance
from executive.world.state import SampleRecord

log = logging.getLogger(__name__)


_S = MissionStatus
#: request -> (states it is allowed from, state it leads to)
TRANSITIONS: dict[str, tuple[frozenset[MissionStatus], MissionStatus]] = {
    "upload": (frozenset({_S.IDLE, _S.READY, _S.COMPLETED, _S.ABORTED}), _S.READY),
    "start": (frozenset({_S.READY, _S.COMPLETED, _S.ABORTED}), _S.RUNNING),
    "pause": (frozenset({_S.RUNNING}), _S.PAUSED),
    "resume": (frozenset({_S.PAUSED}), _S.RUNNING),
    "delete": (frozenset({_S.READY, _S.RUNNING, _S.PAUSED, _S.COMPLETED, _S.ABORTED}), _S.IDLE),
    "complete": (frozenset({_S.RUNNING}), _S.COMPLETED),
    "abort": (frozenset({_S.RUNNING, _S.PAUSED}), _S.ABORTED),
}

#: Asked before a replacement: why this mission cannot replace the paused one (None: it can).
ReplaceCheck = Callable[[Mission], "str | None"]
#: States in which the route may be changed.
ROUTE_EDITABLE = frozenset({MissionStatus.READY, MissionStatus.RUNNING, MissionStatus.PAUSED})


def out_of_reach(mission: Mission, lat: float, lon: float, *, first: int = 0) -> list[str]:
    """The waypoints (from index ``first`` on) farther than ``limits.max_goal_distance_m`` from (lat, lon), each with its distance."""
    limit = mission.limits.max_goal_distance_m
    found = []
    for i, wp in enumerate(mission.waypoints[first:], start=first):
        d = distance(lat, lon, wp.lat, wp.lon)
        if d > limit:
            named = f" ({wp.name})" if wp.name else ""
            found.append(f"waypoints[{i}]{named}: {d:.0f} m from the vehicle, over limits.max_goal_distance_m ({limit:g} m)")
    return found


class Refused(Exception):
    """A lifecycle request that is not allowed in the current state; ``str()`` says why."""


class MissionState:
    """The loaded mission's lifecycle; it alone changes the mission, its route and leg (:attr:`legs`), and its samples (:attr:`sample_log`)."""

    def __init__(self) -> None:
        self._bb = blackboard.writer("mission lifecycle", ["/mission/state", "/mission/reason"])
        self.status = MissionStatus.IDLE
        self.reason = ""
        #: The route and the leg the vehicle is on.
        self.legs = RouteProgress()
        #: The samples taken in this run.
        self.sample_log = SampleLog()
        #: What happens to the mission, told to its subscribers stage by stage.
        self.events = MissionEvents()
        #: Asked before a replacement: why this mission cannot replace the paused one (None: it can); all are asked.
        self.replace_checks: list[ReplaceCheck] = []
        #: Asked before a resume: each says why the mission may not resume yet (a replacing mission's zones not on the autopilot), or None.
        self.resume_checks: list[Callable[[], str | None]] = []
        #: While PAUSED, the tree holds the vehicle in its safe mode; False when a person paused it by taking the vehicle: hands off.
        self.hold_while_paused = True

    def announce(self, text: str, warning: bool = True) -> None:
        """Tell the stream (the ground station) what a person must hear now; short: a STATUSTEXT holds 50 characters."""
        self.events.tell(Announcement(text, warning))

    # -- requests ----------------------------------------------------------------------------
    def upload(self, mission: Mission, vehicle_at: tuple[float, float] | None = None) -> None:
        """Load a mission READY; refused (nothing changes) when it breaks a limit or, with the vehicle's position, a waypoint is out of reach.

        The rules between fields are checked again (a mission built in code never went through the
        loader), and every waypoint must be within ``limits.max_goal_distance_m`` of ``vehicle_at``
        (the AUV's 1 km rule: the Zeno vehicle refuses such a mission at upload). Without a position
        the trees check it when the mission starts.
        """
        self._check("upload")
        problems = [f"{format_path(path)}: {why}" for path, why in cross_field_errors(mission)]
        if vehicle_at is not None:
            problems += out_of_reach(mission, *vehicle_at) + first_leg_problems(mission, *vehicle_at)
        if problems:
            raise Refused(f"mission {mission.name!r} refused: " + "; ".join(problems))
        self.legs.load(mission)
        self.sample_log.clear()
        self._transition("upload", f"mission {mission.name!r} loaded, {len(mission.waypoints)} waypoints")

    def replace(
        self, mission: Mission, leg_index: int, samples: Iterable[SampleRecord], reason: str, vehicle_at: tuple[float, float] | None = None
    ) -> None:
        """While PAUSED: make ``mission`` the mission, heading for ``leg_index``, with ``samples`` already taken; it stays PAUSED.

        Refused (nothing changes) in another state, for a leg outside the new route, when the
        mission breaks a rule or, with the vehicle's position, a waypoint is out of reach (as
        :meth:`upload`), or when a replace check says why not. The stream is told after.
        """
        if self.status is not MissionStatus.PAUSED:
            raise Refused(f"cannot replace the mission while {self.status} (only while PAUSED)")
        if not 0 <= leg_index < len(mission.waypoints):
            raise Refused(f"leg {leg_index + 1} is outside a route of {len(mission.waypoints)} waypoints")
        problems = [f"{format_path(path)}: {why}" for path, why in cross_field_errors(mission)]
        if vehicle_at is not None:
            problems += out_of_reach(mission, *vehicle_at) + first_leg_problems(mission, *vehicle_at)
        problems += [why for check in self.replace_checks if (why := check(mission)) is not None]
        if problems:
            raise Refused(f"mission {mission.name!r} refused: " + "; ".join(problems))
        self.legs.load(mission, leg_index)
        self.sample_log.clear()
        self.sample_log.restore(samples)
        self.reason = reason
        self._bb.set("/mission/reason", reason)
        self._publish()
        log.info("%s", reason)
        self.events.tell(Replaced(mission, reason))

    def start(self, vehicle_at: tuple[float, float] | None = None, reason: str = "started from the first waypoint") -> None:
        """READY (or ended) -> RUNNING from the first waypoint; refused (nothing changes) when a waypoint is out of reach of ``vehicle_at``.

        Without a position the runtime checks the distances before the tree first ticks (:mod:`executive.admission.reach`).
        ``reason``: what the transition says (a run resumed from the journal says where it resumes).
        """
        self._check("start")
        assert self.mission is not None
        far = out_of_reach(self.mission, *vehicle_at) if vehicle_at is not None else []
        if far:
            raise Refused(f"mission {self.mission.name!r} refused: " + "; ".join(far))
        self.legs.load(self.mission)
        self.sample_log.clear()
        self._transition("start", reason)

    def pause(self, reason: str = "pause requested", *, hold: bool = True) -> None:
        """RUNNING -> PAUSED; ``hold=False``: a person has the vehicle (a mode change we did not ask for), nothing is commanded meanwhile."""
        self._check("pause")
        self.hold_while_paused = hold
        self._transition("pause", reason)

    def resume(self, reason: str = "") -> None:
        self._check("resume")
        problems = [why for check in self.resume_checks if (why := check()) is not None]
        if problems:
            raise Refused("cannot resume: " + "; ".join(problems))
        self.hold_while_paused = True
        self._transition("resume", f"resumed at leg {self.legs.leg_number}" + (f": {reason}" if reason else ""))

    def delete(self) -> None:
        self._check("delete")
        if self.status is MissionStatus.RUNNING:
            self._transition("pause", "paused before delete")
        self.legs.load(None)
        self.sample_log.clear()
        self._transition("delete", "mission deleted")

    def complete(self) -> None:
        """RUNNING -> COMPLETED, said as what was done: every waypoint reached, or how many were (a user's tree may succeed short of them)."""
        self._check("complete")
        reached = min(self.legs.leg_index, self.legs.leg_count)
        said = (
            "every waypoint reached"
            if reached >= self.legs.leg_count
            else f"the tree succeeded; {reached} of {self.legs.leg_count} waypoints reached"
        )
        self._transition("complete", said)

    def abort(self, reason: str) -> None:
        self._check("abort")
        self._transition("abort", reason)

    def explain(self, reason: str) -> None:
        """Say why the mission stays as it is (a replacing mission's zones refused: it stays PAUSED) as its reason; no transition."""
        self.reason = reason
        self._bb.set("/mission/reason", reason)

    # -- the loaded mission; its route and leg are read at self.legs, its samples at self.sample_log ---------------------
    @property
    def mission(self) -> Mission | None:
        """The mission loaded (None while IDLE), as its route now is (an operator's edits in it)."""
        return self.legs.mission

    #: Read at ``legs`` and ``sample_log`` since 0.2 (issue 41); the old names warn, for one release.
    leg_index = executive.MovedMember("legs.leg_index")
    leg_count = executive.MovedMember("legs.leg_count")
    leg_number = executive.MovedMember("legs.leg_number")
    target = executive.MovedMember("legs.target")
    next_target = executive.MovedMember("legs.next_target")
    route = executive.MovedMember("legs.route")
    samples = executive.MovedMember("sample_log.taken")
    sampled = executive.MovedMember("sample_log.sampled")
    work_left = executive.MovedMember("sample_log.work_left(mission)", lambda state: lambda: state.sample_log.work_left(state.mission))

    def continue_from(self, leg_index: int, samples: Iterable[SampleRecord] = ()) -> None:
        """After a restart (crash, kill -9, power cut): carry on the running mission at ``leg_index`` with the samples already taken.

        Called right after :meth:`start` and before the first tick, by whoever restores progress
        (the journal); the stream is not told about the samples: the journal recorded them.
        """
        if self.status is not MissionStatus.RUNNING:
            raise Refused(f"cannot continue a mission while {self.status}")
        if not 0 <= leg_index <= self.legs.leg_count:
            raise Refused(f"leg {leg_index + 1} is outside a route of {self.legs.leg_count} waypoints")
        self.legs.leg_index = leg_index
        self.restore_samples(samples)
        self.reason = f"continued at leg {leg_index + 1} after a restart"
        log.info("mission continues at leg %d/%d with %d sample(s) already taken", leg_index + 1, self.legs.leg_count, len(self.sample_log.taken))
        self._publish()

    def advance_leg(self) -> None:
        """The current leg is done: head for the next waypoint."""
        if self.status is not MissionStatus.RUNNING:
            raise Refused(f"cannot advance a leg while {self.status}")
        self.legs.advance()
        log.info("leg %d/%d done", self.legs.leg_index, self.legs.leg_count)
        self._publish()

    def route_refusal(self) -> str | None:
        """Why the route cannot be changed now; None when it can."""
        if self.mission is None:
            return "cannot change the route: no mission loaded"
        if self.status not in ROUTE_EDITABLE:
            return f"cannot change the route while {self.status} (allowed while {', '.join(sorted(ROUTE_EDITABLE))})"
        return None

    def set_route(
        self,
        waypoints: Sequence[Waypoint],
        reason: str,
        *,
        leg_index: int | None = None,
        home: Home | None = None,
        vehicle_at: tuple[float, float] | None = None,
    ) -> None:
        """Replace the mission's waypoints (an operator's edit), and its home if given: publish the new route and tell the stream.

        Allowed while READY, RUNNING or PAUSED. ``leg_index`` (the waypoint the vehicle heads for)
        defaults to the current one, kept inside the new route. Samples keep the legs they were
        taken at. Refused (nothing changes) without a mission, in other states, with a leg index
        outside the route, or when the edited mission breaks the mission file's rules; with the vehicle's position
        (``vehicle_at``) while RUNNING or PAUSED, also when the leg from there to the waypoint it heads for enters a zone.
        """
        refusal = self.route_refusal()
        if refusal is not None:
            raise Refused(refusal)
        assert self.mission is not None
        leg = min(self.legs.leg_index, len(waypoints)) if leg_index is None else leg_index
        if not 0 <= leg <= len(waypoints):
            raise Refused(f"leg {leg + 1} is outside a route of {len(waypoints)} waypoints")
        edited = self.mission.model_copy(update={"waypoints": list(waypoints), "home": self.mission.home if home is None else home})
        problems = [f"{format_path(path)}: {why}" for path, why in cross_field_errors(edited)]
        if vehicle_at is not None and self.status in (MissionStatus.RUNNING, MissionStatus.PAUSED):
            problems += first_leg_problems(edited, *vehicle_at, first=leg)  # the leg it is on is from where it is, not from a waypoint
        if problems:
            raise Refused("the edited mission breaks its rules: " + "; ".join(problems))
        self.legs.load(edited, leg)
        self._publish()
        log.info("route changed: %s (%d waypoints, heading for %d)", reason, len(waypoints), leg + 1)
        self.events.tell(RouteChanged(self.legs.route, reason))

    # -- samples (kept by self.sample_log) ---------------------------------------------------------
    def record_sample(self, sample: SampleRecord) -> None:
        """Keep a finished sample: publish ``/mission/samples`` and tell the stream.

        Refused (nothing changes) without a mission, for a leg the mission does not have, or for a
        leg already sampled.
        """
        if self.mission is None:
            raise Refused("cannot record a sample: no mission loaded")
        if not 0 <= sample.leg_index < self.legs.leg_count:
            raise Refused(f"cannot record a sample of leg {sample.leg_index + 1}: the mission has {self.legs.leg_count}")
        if self.sample_log.sampled(sample.leg_index):
            raise Refused(f"leg {sample.leg_index + 1} is already sampled")
        self.sample_log.keep(sample)
        self._publish()
        if sample.partial:
            log.warning("partial sample of leg %d recorded: %d reads, none of %s", sample.leg_index + 1, len(sample.reads), ", ".join(sample.missing))
        else:
            log.info("sample of leg %d recorded: %d reads", sample.leg_index + 1, len(sample.reads))
        self.events.tell(SampleTaken(sample))

    def restore_samples(self, samples: Iterable[SampleRecord]) -> None:
        """Put back the samples a previous process recorded (the stream is not told: its journal already knows)."""
        self.sample_log.restore(samples)
        self._publish()

    # -- internals ---------------------------------------------------------------------------
    def _check(self, request: str) -> None:
        allowed, _ = TRANSITIONS[request]
        if self.status not in allowed:
            raise Refused(f"cannot {request} while {self.status} (allowed from {', '.join(sorted(allowed))})")
        if request in ("start", "resume") and self.mission is None:
            raise Refused(f"cannot {request}: no mission loaded")

    def _transition(self, request: str, reason: str) -> None:
        before, (_, after) = self.status, TRANSITIONS[request]
        self.status = after
        self.reason = reason
        self._bb.set("/mission/reason", reason)
        self._publish()
        log.info("mission %s -> %s: %s", before, after, reason)
        self.events.tell(Transition(before, after, reason))

    def _publish(self) -> None:
        self._bb.set("/mission/state", str(self.status))
        self.legs.active = self.status in (MissionStatus.RUNNING, MissionStatus.PAUSED)
        self.legs.publish()
        self.sample_log.publish()
