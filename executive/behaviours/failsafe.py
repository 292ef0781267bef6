"""Failsafes: when a guard of the mission fails, the reaction its policy names, at once, then its recovery.

Every guard stands for a condition of the mission's ``failsafe:`` policy (:data:`CONDITIONS`:
:class:`~executive.behaviours.guards.LinkAlive` failing is ``link_loss``...); a guard standing for
none (a speed or depth limit) holds the vehicle and resumes, within ``limits.recovery_timeout_s``.

:class:`Failsafe` stands behind the guarded work in a reactive selector (``executive.trees.parts.failsafe_guarded``):
the guards are ticked every tick before the work, so the tick in which a condition becomes true on
the blackboard (the readers write it before the tree ticks) is the tick in which the route fails
and the failsafe runs; it asks the autopilot for the reaction there and then, and the runtime
sends it when that tick ends: zero ticks of delay.

A reaction is done only when the autopilot has accepted it (its COMMAND_ACK, on the blackboard)
and the heartbeat shows the vehicle in the mode (or disarmed) asked for. Until then the feedback
says what it waits for (``asking HOLD: refused (FAILED) x2``), and it is asked again every
:data:`~executive.autopilot.asking.ASK_AGAIN_S` of vehicle time. After three failed asks (refused; accepted
but not seen; unanswered while heartbeats arrive), or at once when the firmware's source says the
vehicle cannot enter it in its present state (a position mode without a position estimate), the
next reaction the firmware allows is asked instead (:mod:`executive.autopilot.fallbacks`). Each
such step is a warning and an announcement to the ground station (a STATUSTEXT): see
:mod:`executive.autopilot.asking`.

While it runs, every guard is judged each tick (not only the first that failed), so a condition
that becomes true during another one's reaction gets its own. A person who has the vehicle (a
failing ``wait`` guard that says so: the take-over switch, disarmed), or who drives it in a mode
of a person's (MANUAL, ACRO...: set by the RC, a ground station, or by us at the operator's request),
is never fought: nothing is commanded meanwhile. Each cause, reaction, recovery and abort is logged as a warning (the journal
keeps it as an event).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.autopilot.asking import READS, Asker
from executive.autopilot.fallbacks import DISARM
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.commands import SetMode
from executive.behaviours.energy import EnergyEnough
from executive.behaviours.guards import Armed, BatteryAbove, EkfOk, GpsNotGlitching, Guard, HeadingSane, LinkAlive
from executive.behaviours.position_guards import InsideGeofence
from executive.behaviours.rc_guards import RcAutoMode, RcFresh, RcNotLost, RcNotTakingOver
from executive.behaviours.returning import ReturningDrive, why_not_rtl
from executive.behaviours.zone_guards import OutsideKeepOut
from executive.mission.declaration import reaction_modes, vehicle_profile
from executive.mission.failsafes import JUDGED_AFTER_PERSON, FailsafeCondition, FailsafePolicy
from executive.mission.port import MissionPort
from executive.mission.return_path import DRIVEN_KINDS, ReturnPlanner
from executive.sensing.vtol_flight import flies_as_plane

log = logging.getLogger(__name__)

#: Which failsafe condition a failing guard is.
CONDITIONS: tuple[tuple[type[Guard], str], ...] = (
    (LinkAlive, "link_loss"),
    (EkfOk, "ekf_loss"),
    (Armed, "disarmed"),
    (RcNotTakingOver, "rc_takeover"),
    (RcAutoMode, "rc_takeover"),
    (RcFresh, "rc_loss"),
    (RcNotLost, "rc_loss"),
    (GpsNotGlitching, "gps_glitch"),
    (HeadingSane, "heading_insane"),
    (BatteryAbove, "battery_low"),
    (InsideGeofence, "geofence_breach"),
    (EnergyEnough, "energy"),
    (OutsideKeepOut, "keep_out"),
)
#: A stronger reaction replaces a weaker one in force, never the reverse (a surfacing sub is not stopped by a later hold).
RANK = {"wait": 0, "hold": 1, "loiter": 1, "rtl": 2, "surface": 2, "disarm": 3}
REARM_RETRY_S = 2.0


def condition_of(guard: Guard) -> str | None:
    """The failsafe condition ``guard`` failing is, if any."""
    return next((condition for kind, condition in CONDITIONS if isinstance(guard, kind)), None)


@dataclass(frozen=True)
class _Reaction:
    guard: Guard
    policy: FailsafePolicy

    @property
    def rank(self) -> int:
        return RANK[self.policy.reaction]


class Failsafe(TimedBehaviour):
    """RUNNING while a guard fails and its policy says resume (the reaction commanded), FAILURE on abort or time-out.

    ``policy``: condition -> :class:`~executive.mission.model.FailsafePolicy`; ``fallback`` is the policy
    of a guard that stands for no condition. When every guard holds the branch it stands behind
    failed for another reason: FAILURE, with nothing to add. An abort leaves its feedback empty
    when the guard that caused it says why in the tree already; :attr:`left_in` is the mode it
    left the vehicle in (the runtime then leaves it there).
    """

    reads = (
        "/vehicle/vtol_state", "/vehicle/ground_speed_m_s", "/vehicle/mode_set_by", "/mission/leg_index", "/mission/leg_count",
        "/vehicle/position", "/vehicle/home", *READS,
    )  # fmt: skip
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    #: Where its steps are announced to a person (the ground station's STATUSTEXT); from ``setup(mission_state=...)`` when given.
    mission_state: MissionPort | None = None
    catalogued = False  # made with the mission's policy by failsafe_guarded and checked

    def __init__(
        self,
        guards: Sequence[Guard],
        policy: Mapping[str, FailsafePolicy],
        vehicle: str,
        fallback: FailsafePolicy,
        name: str = "Wait for guards",
        *,
        returns: ReturnPlanner | None = None,
        reach_m: float = 2.0,
        leg_timeout_s: float = 120.0,
        work: py_trees.behaviour.Behaviour | None = None,
    ) -> None:
        super().__init__(name)
        #: The guarded work this failsafe stands behind (None: a guard alone), whose refused mode change is asked again after a recovery.
        self.work = work
        #: The mission's return around its keep-out zones to a rally point or home (None: the firmware's RTL always).
        self.returns = returns
        self.reach_m, self.leg_timeout_s = reach_m, leg_timeout_s
        self.guards = tuple(guards)
        self.policy = dict(policy)
        self.vehicle = vehicle
        self.fallback = fallback
        self._conditions = {g: condition_of(g) for g in self.guards}
        self.left_in: str | None = None
        self._own_disarm = False  # kept across a pause: the vehicle is still ours to re-arm
        # kept across re-entries: after a recovery, until the recovered condition's time limit, a refused mode change is asked again
        self._resume_until: float | None = None
        self._resume_causes = ""
        self._retry_said = False
        self._leg = 0
        self._reset()

    def setup(self, **services: Any) -> None:
        super().setup(**services)
        self.mission_state = services.get("mission_state")

    def _reset(self) -> None:
        self._since: dict[Guard, float] = {}
        self._in_force: _Reaction | None = None
        self._reacting = Asker(self, self.vehicle, announce=self._announce, on_disarm=self._disarming)
        self._rearm_from: float | None = None
        self._rearm_at = float("-inf")
        self._return: ReturningDrive | None = None  # the executive's own return, when the firmware's RTL will not do
        self._return_ends_mission = False
        self._return_reason = ""
        self._deferred_said: set[Guard] = set()
        self._rtl_judged: dict[Guard, str | None] = {}  # per guard: why the firmware's RTL will not do (None: it will)

    def initialise(self) -> None:
        super().initialise()
        self._reset()
        self.left_in = None
        self._leg = self.get("/mission/leg_index")  # the leg to resume (the work may finish it in the tick it resumes)

    def policy_of(self, guard: Guard) -> FailsafePolicy:
        condition = self._conditions.get(guard)
        return self.policy.get(condition, self.fallback) if condition else self.fallback

    def _name(self, guard: Guard) -> str:
        return self._conditions.get(guard) or guard.name

    def terminate(self, new_status: Status) -> None:
        if self.left_in is not None or new_status == FAILURE:
            return  # ended the mission: the reaction must reach the vehicle
        # interrupted: by the guards recovering (the work resumes) or by a pause; a reaction still being retried must not undo either
        self._reacting.cancel()
        if self._return is not None:
            self._return.cancel()
        if self._since and all(g.status == SUCCESS for g in self.guards):
            causes = ", ".join(self._name(g) for g in self._since)
            self._resume_until = max(since + self.policy_of(g).timeout_s for g, since in self._since.items())
            self._resume_causes, self._retry_said = causes, False
            leg = f"{self._leg + 1}/{self.get('/mission/leg_count')}"
            log.warning("failsafe %s: recovered after %.1f s -> resume leg %s", causes, self.elapsed, leg)
            if self.mission_state is not None:
                self.mission_state.announce(f"failsafe {causes} recovered: leg {leg}", warning=False)
        self._since = {}

    def update(self) -> Status:
        now = self.clock.now()
        if self.get("/vehicle/armed"):
            self._own_disarm = False
        failing = {g: why for g in self.guards if (why := g.judge()) is not None}  # debounced: see guards
        if self._own_disarm:  # disarmed by this failsafe, not by a person
            failing = {g: why for g, why in failing.items() if self._conditions.get(g) != "disarmed"}
        person = next((g for g in failing if g.pilot_in_control), None)  # whatever a policy says (the loader refuses any but wait)
        driving = self._person_drives()
        hands_off = person is not None or driving is not None
        deferred = self._defer(failing) if hands_off else {}
        failing = {g: why for g, why in failing.items() if g not in deferred}
        if self._return is not None and self._return_ends_mission:
            return self._returning(now, hands_off)
        for g in [g for g in self._since if g not in failing]:
            del self._since[g]
        new = [g for g in failing if g not in self._since]
        for g in new:
            self._since[g] = now
        if not failing and deferred:
            self.feedback_message = "hands off: " + "; ".join(f"{g.name} {why}" for g, why in deferred.items()) + " (judged when they hand back)"
            return RUNNING
        if not failing:
            return self._rearm(now) if self._own_disarm else self._retry_refused_mode(now) or self._nothing_to_wait_for()
        self._rearm_from = None
        why = "; ".join(f"{g.name} {reason}" for g, reason in failing.items())
        aborting = [_Reaction(g, self.policy_of(g)) for g in failing if self.policy_of(g).recovery == "abort"]
        if aborting:
            cause = max(aborting, key=lambda r: r.rank)
            if not hands_off:
                self._in_force = cause
            self._log(cause, failing[cause.guard], person, "abort the mission", driving)  # the cause first, then each step of its reaction
            mode = None if hands_off else self._react(cause)
            if self._return is not None:  # the executive's own return: the mission ends where it arrives
                self._return_ends_mission, self._return_reason = True, f"{cause.guard.name} {failing[cause.guard]}"
                return self._returning(now, hands_off)
            self.left_in = mode or self._mode_in_force
            self.feedback_message = "" if cause.guard.status == FAILURE else f"{cause.guard.name} {failing[cause.guard]}"
            return FAILURE
        chosen = None if hands_off else self._strongest(failing, new)
        if chosen is not None:
            self._in_force = chosen
        for g in new:
            reaction = _Reaction(g, self.policy_of(g))
            self._log(reaction, failing[g], person, f"resume when it recovers (within {reaction.policy.timeout_s:g} s)", driving)
        if hands_off:
            self._reacting.stand_back()
        else:
            if chosen is not None:
                self._react(chosen)
            self._reacting.follow_up(now)
            if self._return is not None:
                why = f"{self._return.follow(now, self._reacting.done)}; {why}"
        late = [g for g in failing if now - self._since[g] > self.policy_of(g).timeout_s]
        if late:
            limit = self.policy_of(late[0]).timeout_s
            log.warning("failsafe %s: not recovered within %g s -> abort the mission", self._name(late[0]), limit)
            self.left_in = self._mode_in_force
            self.feedback_message = f"not recovered after {limit:g} s: {why}"
            return FAILURE
        waited, limit = max(((now - self._since[g], self.policy_of(g).timeout_s) for g in failing), key=lambda x: x[0] / x[1])
        self.feedback_message = f"{self._state(hands_off)} ({waited:.0f}/{limit:g} s): {why}"
        return RUNNING

    @property
    def returning(self) -> bool:
        """It drives a return of its own that ends the mission where it arrives."""
        return self._return is not None and self._return_ends_mission

    def _defer(self, failing: Mapping[Guard, str]) -> dict[Guard, str]:
        """The failing conditions not judged while a person has the vehicle (:data:`JUDGED_AFTER_PERSON`), each said once."""
        deferred = {g: why for g, why in failing.items() if self._conditions.get(g) in JUDGED_AFTER_PERSON}
        for g, why in deferred.items():
            if g not in self._deferred_said:
                log.warning("failsafe %s: %s -> a person has the vehicle: judged when they hand back", self._name(g), why)
        self._deferred_said = set(deferred)
        return deferred

    def _returning(self, now: float, hands_off: bool) -> Status:
        """The executive's own return that ends the mission: followed until it arrives (then FAILURE, left in the hold)."""
        assert self._return is not None
        if hands_off:  # a person took the vehicle during the return: they have it, the mission ends hands off
            self._return.cancel()
            self._reacting.stand_back()
            log.warning("failsafe %s: a person took the vehicle during the return -> hands off, abort the mission", self._return.cause)
            self.left_in = None
            self.feedback_message = f"{self._return_reason}; a person took the vehicle during the return: hands off"
            return FAILURE
        self._reacting.follow_up(now)
        text = self._return.follow(now, self._reacting.done)
        if self._return.arrived or self._return.failed is not None:
            self.left_in = self._return.hold_mode
            self.feedback_message = f"{self._return_reason}; {text}"
            return FAILURE
        self.feedback_message = text
        return RUNNING

    def _state(self, hands_off: bool) -> str:
        """What the vehicle is left in, or what the reaction still waits for."""
        state = None if hands_off else self._reacting.state()
        return state or "hands off"

    # -- reactions ---------------------------------------------------------------------------

    def _strongest(self, failing: Iterable[Guard], new: list[Guard]) -> _Reaction | None:
        """The strongest reaction among the failing conditions, to command now, unless one as strong is in force (a new one: stronger or equal)."""
        candidates = [_Reaction(g, self.policy_of(g)) for g in failing if self.policy_of(g).reaction != "wait"]
        if not candidates:
            return None
        strongest = max(candidates, key=lambda r: (r.rank, r.guard in new))
        in_force = self._in_force.rank if self._in_force is not None else -1
        if strongest.rank > in_force or (strongest.guard in new and strongest.rank == in_force):
            return strongest
        return None

    def _react(self, reaction: _Reaction) -> str | None:
        """Ask for ``reaction`` (unless it, or a reaction after it, is asked already); the mode it leaves the vehicle in, if any."""
        self._in_force = reaction
        what = reaction.policy.reaction
        if what == "wait":
            return None
        if what == "rtl" and self._return is None and self._drive_return(reaction):
            what = "hold"  # first: stopped where it is; then the return (self._return)
        mode = self._mode_of(what)
        first = DISARM if what == "disarm" else mode
        if self._reacting.covers(first):  # asked already (or refused, and the next one asked)
            return self._mode_in_force
        if what == "disarm":  # the manual mode first: re-armed later, the vehicle does not drive off
            try:
                self._reacting.track(self.autopilot.set_mode(mode), mode)
            except KeyError:
                log.error("failsafe %s: the autopilot has no mode %s", self._name(reaction.guard), mode)
        self._reacting.start(first, self._name(reaction.guard))
        return self._mode_in_force

    def _drive_return(self, reaction: _Reaction) -> bool:
        """Whether this return is the executive's own (the firmware's RTL would not do, :func:`why_not_rtl`); if so it is made."""
        if self.returns is None or self.vehicle not in DRIVEN_KINDS:
            return False
        cause = self._name(reaction.guard)
        why = self._why_not_rtl(reaction)
        if why is None:
            return False
        hold = self._mode_of("hold")
        log.warning("failsafe %s: not the autopilot's RTL (%s) -> %s, then the executive's own return around the keep-out zones", cause, why, hold)
        self._return = ReturningDrive(
            self, self.vehicle, self.returns, cause, hold, reach_m=self.reach_m, leg_timeout_s=self.leg_timeout_s, announce=self._announce
        )
        return True

    def _why_not_rtl(self, reaction: _Reaction) -> str | None:
        """Why the firmware's RTL will not do for ``reaction`` (None: it will), judged once per episode of its guard."""
        if self.returns is None or self.vehicle not in DRIVEN_KINDS:
            return None
        if reaction.guard not in self._rtl_judged:
            home = self.get("/vehicle/home")
            mission_home = self.returns.mission.home
            where = (home.lat, home.lon) if home is not None else ((mission_home.lat, mission_home.lon) if mission_home else None)
            self._rtl_judged[reaction.guard] = why_not_rtl(self.returns, self._name(reaction.guard), self.get("/vehicle/position"), where)
        return self._rtl_judged[reaction.guard]

    @property
    def _mode_in_force(self) -> str | None:
        return self._reacting.mode_in_force

    def _disarming(self) -> None:
        self._own_disarm = True

    def _announce(self, text: str, warning: bool) -> None:
        if self.mission_state is not None:
            self.mission_state.announce(text, warning)

    def _mode_of(self, what: str) -> str:
        """The mode of reaction ``what`` for this vehicle; a VTOL flying as a plane takes the plane's.

        A return (rtl) is the plane's RTL from the moment a transition to fixed-wing flight starts, or when the
        speed says wing-borne before EXTENDED_SYS_STATE does: QRTL entered then hovers the whole way home
        (:mod:`executive.sensing.vtol_flight`). A hold or loiter is the plane's only in FW: mid-transition,
        QLOITER stops it where it is.
        """
        modes = reaction_modes(self.vehicle, what)
        state = self.get("/vehicle/vtol_state")
        if what == "rtl" and self.vehicle == "vtol":
            return modes[1] if flies_as_plane(state, self.get("/vehicle/ground_speed_m_s")) else modes[0]
        return modes[1] if state == "FW" else modes[0]

    def _rearm(self, now: float) -> Status:
        """Every condition cleared, the vehicle disarmed by this failsafe: arm it again (retried), then the work resumes."""
        if self._rearm_from is None:
            self._rearm_from = now
            log.warning("failsafe %s: recovered -> re-arm, then resume", self._name(self._in_force.guard) if self._in_force else "disarm")
        limit = self._in_force.policy.timeout_s if self._in_force else self.fallback.timeout_s
        if now - self._rearm_from > limit:
            log.warning("failsafe: could not re-arm within %g s -> abort the mission", limit)
            self.left_in = self._mode_in_force
            self.feedback_message = f"could not re-arm within {limit:g} s"
            return FAILURE
        if now - self._rearm_at >= REARM_RETRY_S:
            self._rearm_at = now
            self._reacting.track(self.autopilot.arm())
        self.feedback_message = f"re-arming ({now - self._rearm_from:.0f}/{limit:g} s)"
        return RUNNING

    def _retry_refused_mode(self, now: float) -> Status | None:
        """RUNNING when the work, resumed after a recovery, failed on a refused mode change and the recovery's time is not up.

        The firmware's own failsafe may still be latched (ArduRover refuses GUIDED and AUTO for about
        a second after its EKF recovered: ``failsafe.ekf``, Rover/ekf_check.cpp, Rover/mode.cpp): the
        work is ticked again next tick and asks again, until the recovered condition's time limit.
        """
        if self._resume_until is None or now > self._resume_until:
            return None
        refused = self._refused_mode_change()
        if refused is None:
            return None
        if not self._retry_said:
            self._retry_said = True
            log.warning(
                "failsafe %s: recovered, but %s -> asked again until the recovery's time limit (%.0f s more)",
                self._resume_causes, refused, self._resume_until - now,
            )  # fmt: skip
        self.feedback_message = f"resuming after {self._resume_causes}: {refused}; asking again"
        return RUNNING

    def _refused_mode_change(self) -> str | None:
        """Why the guarded work failed on a mode change, if it did."""
        if self.work is None:
            return None
        for node in self.work.iterate():
            if isinstance(node, SetMode) and node.status == FAILURE:
                return f"{node.name}: {node.feedback_message}"
        return None

    def _nothing_to_wait_for(self) -> Status:
        self.feedback_message = ""  # the branch it stands behind failed: that is the reason to report
        return FAILURE

    def _person_drives(self) -> str | None:
        """Why a person drives the vehicle, if one does: a mode in which a person drives (MANUAL, ACRO...) that this failsafe did not ask for.

        Set by the RC, a ground station, or by the executive at the operator's request (handed over):
        no failsafe of ours changes it; RC loss meanwhile is the autopilot's own RC failsafe's job.
        """
        mode = self.get("/vehicle/mode")
        set_by = self.get("/vehicle/mode_set_by")  # None: the boot mode, nobody's choice
        if mode in vehicle_profile(self.vehicle).pilot_modes and set_by not in (None, "autopilot") and mode != self._mode_in_force:
            return f"the vehicle is in {mode}: a person drives it"
        return None

    def _log(self, reaction: _Reaction, reason: str, person: Guard | None, recovery: str, driving: str | None = None) -> None:
        """``failsafe <condition>: <reason> -> <reaction>, <recovery>``: a warning, so an event in the journal."""
        what, condition = reaction.policy.reaction, self._name(reaction.guard)
        short = done = "wait: hands off"  # short: for a STATUSTEXT (50 characters)
        if person is not None:
            done = f"wait: hands off ({person.name.rstrip('?')} fails: a person has the vehicle)"
        elif driving is not None:
            job = "; RC loss is the autopilot's own RC failsafe's job" if condition == "rc_loss" else ""
            done = f"wait: hands off ({driving}{job})"
        elif what != "wait":
            mode = self._mode_of(what)
            short = done = f"disarm in {mode}" if what == "disarm" else f"{what} ({mode})"
            if what == "rtl" and self._return is None and self._why_not_rtl(reaction) is not None:
                hold = self._mode_of("hold")
                done = f"{hold}, then the executive's own return around the keep-out zones"
                short = f"{hold}, then return around zones"
            stronger = self._in_force
            if stronger is not None and stronger.rank > reaction.rank:
                done += f" not commanded: {stronger.policy.reaction} ({self._mode_in_force}) for {self._name(stronger.guard)} in force"
                short = f"{stronger.policy.reaction} kept"
        log.warning("failsafe %s: %s -> %s, %s", condition, reason, done, recovery)
        if self.mission_state is not None:
            self.mission_state.announce(f"failsafe {condition} -> {short}" + (", abort" if recovery == "abort the mission" else ""))


class FailsafeNote(py_trees.behaviour.Behaviour):
    """Logs a failsafe event for a tree that reacts with its own behaviours (the ASV's EKF wait), then SUCCESS.

    With ``guard``, its reason goes in the text: ``failsafe ekf_loss: <reason> -> <text>``.
    """

    node_refs = ("guard",)
    param_docs = {
        "condition": "the failsafe condition journalled (ekf_loss, rc_loss...)",
        "text": "what is done about it",
        "guard": "the name of a guard of the tree whose reason goes in the text",
    }

    def __init__(self, condition: FailsafeCondition, text: str, guard: Guard | None = None, name: str | None = None) -> None:
        super().__init__(name or f"Journal: {condition}")
        self.condition, self.text, self.guard = condition, text, guard

    def update(self) -> Status:
        reason = f"{self.guard.feedback_message} -> " if self.guard is not None else ""
        log.warning("failsafe %s: %s%s", self.condition, reason, self.text)
        return SUCCESS


def failsafe_mode(root: py_trees.behaviour.Behaviour) -> str | None:
    """The mode a failsafe that ended the mission left the vehicle in, if one did."""
    return next((node.left_in for node in root.iterate() if isinstance(node, Failsafe) and node.left_in), None)
