"""The onboard runtime: a fixed-rate loop of link.pump() -> blackboard -> tick -> link.flush().

It owns the process-level safety: a stop request (Ctrl-C, SIGTERM), a failed mission and an
exception inside a behaviour all end with the vehicle commanded into its safe mode.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import py_trees
from py_trees.common import Status

import executive
from executive import registry
from executive.admission.reach import ReachGate, Refusal
from executive.autopilot_link import AutopilotLink
from executive.behaviours.base import FAILURE, INVALID, SUCCESS
from executive.behaviours.failsafe import failsafe_mode
from executive.instruments.backends import open_sampler
from executive.instruments.sampler import InstrumentError, InstrumentSampler, UnavailableSampler
from executive.mission.events import Replaced, Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission, SamplingOptions
from executive.mission.port import MissionPort
from executive.mission.reload import REPLACED
from executive.mission.resume import ResumePoint
from executive.operator import Operator
from executive.operator.progress import Progress
from executive.operator.status import StatusSource
from executive.runtime.pacing import TickPacer
from executive.runtime.services import PacedService, RunObserver, Service
from executive.tree import select as mission_tree
from executive.tree.crash_site import CrashSite
from executive.tree.ticking import BehaviourTree
from executive.world import blackboard
from executive.world.clock import Clock, TickClock

log = logging.getLogger("executive.runtime")  # the name the log and the journal show, kept since 0.1
#: The mission statuses in which its tree ticks, and those a person's abort or delete leaves it in: read every tick, and
#: an Enum class's members are slow to read from it in Python 3.11 (executive.behaviours.base.RUNNING says why).
_TREE_TICKS = (MissionStatus.RUNNING, MissionStatus.PAUSED)
_ENDED_BY_A_PERSON = (MissionStatus.ABORTED, MissionStatus.IDLE)


class BehaviourCrashed(RuntimeError):
    """A behaviour raised during a tick; ``path`` names it from the root."""

    def __init__(self, path: str, error: BaseException) -> None:
        where = registry.user_frame(error)  # a plugin's behaviour: the user's file and line
        super().__init__(f"{path}: {f'{where}: ' if where else ''}{type(error).__name__}: {error}")
        self.path = path
        self.error = error


@dataclass(frozen=True)
class RunOutcome:
    """How a run ended: ``mission`` names the mission that ran (None: none did), ``samples`` how many it recorded.

    ``safe``: what making the vehicle safe at its end came to (None: it was not made safe, as after a COMPLETED mission).
    """

    status: MissionStatus
    reason: str
    ticks: int
    mission: str | None = None
    samples: int = 0
    safe: str | None = None
    #: A user's code (a plugin's tree or behaviour) failed before anything was commanded: bad input (exit 2), not a failed mission.
    users_code: bool = False


def behaviour_path(node: py_trees.behaviour.Behaviour) -> str:
    """``Mission/Route or hold/Guarded route/EKF ok?``"""
    names = []
    current: py_trees.behaviour.Behaviour | None = node
    while current is not None:
        names.append(current.name)
        current = current.parent
    return "/".join(reversed(names))


def explain_failure(root: py_trees.behaviour.Behaviour) -> str:
    """The reason for a failed tree: the shallowest failed node that says why."""
    best: tuple[int, str] | None = None
    for node in root.iterate():
        if node.status == FAILURE and node.feedback_message:
            depth = behaviour_path(node).count("/")
            if best is None or depth <= best[0]:
                best = (depth, f"{node.name}: {node.feedback_message}")
    return best[1] if best else "the mission tree failed"


class Runtime:
    """One executive attached to one vehicle: IO, the mission lifecycle, and the tree of the running mission.

    The tree is built when a mission starts (from READY, or again after it ended), so an operator
    can upload another mission and start it without restarting the executive; a mission replaced
    while PAUSED (hot reload) gets its tree at once, first ticked when the operator resumes (until
    then the vehicle is left as the pause left it). ``serve`` keeps
    the executive up between missions, waiting for operator requests, instead of returning when
    the mission ends. Each tick pumps the autopilot link, drains the other readers, ticks the tree,
    services the writers (:mod:`executive.runtime.services`) and flushes the link; what they are is decided
    by :func:`executive.runtime.assembly.build_runtime`.
    """

    def __init__(
        self,
        mission: Mission,
        clock: Clock,
        link: AutopilotLink,
        mission_state: MissionState,
        *,
        operator: Operator | None = None,
        status: StatusSource | None = None,
        readers: Sequence[Service] = (),
        writers: Sequence[Service] = (),
        paced: Sequence[PacedService] = (),
        observers: Sequence[RunObserver] = (),
        closers: Sequence[Callable[[], object]] = (),
        reporters: Sequence[Service] = (),
        simulated_vehicle: bool = True,
        rate_hz: float = 10.0,
        safe_timeout_s: float | None = None,
        root: py_trees.behaviour.Behaviour | None = None,
        progress: Progress | None = None,
        reach: ReachGate | None = None,
    ) -> None:
        """Built by :func:`executive.runtime.assembly.build_runtime`; ``root`` replaces the tree the first mission selects (for tests and tools).

        ``reporters`` are serviced while the vehicle is made safe too (the ground station: its commands, the steps' reports).
        ``reach``: the distance rule's gate (it tells the tree watch what it holds the tree back for).
        """
        self.mission = mission
        self.clock = clock
        self.period_s = 1.0 / rate_hz
        #: The autopilot: pumped before the tree ticks, flushed after; it connects and makes the vehicle safe.
        self.link = link
        #: This runtime's blackboard (the one current as it is built): installed whenever it ticks or builds a tree.
        self.board = blackboard.current()
        self.mission_state = mission_state
        # the first stage: the tree (and the journal's run) exist before any other subscriber hears of the start
        self.mission_state.events.subscribe(Transition, self._on_transition, Stage.TREE)
        self.mission_state.events.subscribe(Replaced, self._on_replace, Stage.TREE)
        self.mission_state.replace_checks.append(self._check_tree)
        #: A person's requests (``ctl``, the live view, a ground station) and the status snapshot they are answered with.
        self.operator, self.status = operator, status
        #: Drained after the link is pumped, before the tree ticks, in order.
        self.readers: list[Service] = list(readers)
        #: Serviced after the tree ticks, in order (after the running mission's own: its sampler), before the link is flushed.
        self.writers: list[Service] = list(writers)
        #: Serviced between ticks too, until each is due.
        self.paced: list[PacedService] = list(paced)
        self.observers: list[RunObserver] = list(observers)
        self._closers = list(closers)
        self._reporters = list(reporters)
        self._resume: ResumePoint | None = None
        #: The vehicle is the built-in simulator: a simulated instrument may take the samples.
        self.simulated_vehicle = simulated_vehicle
        self.sampler: InstrumentSampler | None = None
        self._run_writers: list[Service] = []
        self._next_root = root
        self._built: tuple[Mission, py_trees.behaviour.Behaviour] | None = None  # a replacement's tree, built when it was checked
        self.tree: py_trees.trees.BehaviourTree | None = None
        self._crash_site: CrashSite | None = None  # with the tree
        #: A mission replaced while PAUSED: its tree waits for the resume (nothing commanded meanwhile).
        self._tree_waits_for_resume = False
        #: The distance rule, judged before a mission's tree first ticks, whatever the tree (a user's may leave it out).
        self.reach = reach or ReachGate(self.clock)
        self._refused: str | None = None  # the distance rule (or a user's code) refused the starting mission: it ends, nothing commanded
        self._refused_users_code = False
        self.mission_state.upload(self.mission)
        self.progress = progress
        #: The bound on making the vehicle safe; None: as long as the firmware's chain of reactions takes (see :meth:`make_safe`).
        self.safe_timeout_s = safe_timeout_s
        #: What the last make-safe came to (``the vehicle made safe: HOLD (confirmed)``); None until one is done.
        self.safe_report: str | None = None
        self.ticks = 0
        #: The loop's schedule: late and skipped ticks, and a warning (and its listeners) when it misses its rate.
        self.pacer = TickPacer(self.clock, self.period_s)
        #: What the tree reads: the clock, latched at the start of each tick.
        self.tree_clock = TickClock(self.clock)
        self._stop_reason: str | None = None
        #: How the last mission that ran ended (None: none has): what ``run`` returns when stopped between missions.
        self.last_outcome: RunOutcome | None = None
        self._running: Mission | None = None  # the mission whose tree was installed last (a deleted one keeps its name here)

    # -- phases ------------------------------------------------------------------------------
    def tick(self) -> Status:
        """One tick: pump the autopilot link, drain the other readers (the operator's too), tick the tree, flush the link.

        Returns the tree's status (INVALID when no mission is active).
        """
        self.board.install()
        self.link.pump()
        for reader in self.readers:
            reader.service()
        status = INVALID
        running = self.mission_state.status in _TREE_TICKS
        if self.tree is not None and running and not self._tree_waits_for_resume and self._refused is None:
            verdict = self.reach.judge(self.mission_state)
            if isinstance(verdict, Refusal):
                self._refused = verdict.reason
            elif verdict is None:  # else held back until the vehicle's position is known: the tree does not tick, nothing is commanded
                status = self._tick_tree(self.tree)
        for writer in self._run_writers:
            writer.service()
        for writer in self.writers:
            writer.service()
        self.link.flush()
        self.ticks += 1
        return status

    def _tick_tree(self, tree: py_trees.trees.BehaviourTree) -> Status:
        try:
            self.tree_clock.latch()
            tree.tick()
        except Exception as exc:
            node = self._node_that_raised(exc)
            raise BehaviourCrashed(behaviour_path(node) if node else "(tree)", exc) from exc
        for observer in self.observers:
            observer.ticked(self.ticks, self.clock.now())
        return tree.root.status

    def _node_that_raised(self, error: BaseException) -> py_trees.behaviour.Behaviour | None:
        """The tree's node ``error`` came out of (None: from no node's own code)."""
        return self._crash_site.node_of(error) if self._crash_site is not None else None

    def request_stop(self, reason: str) -> None:
        """Ask the loop to stop at the next tick (safe from a signal handler)."""
        self._stop_reason = reason

    def run(self, *, start: bool = True, serve: bool = False, resume: ResumePoint | None = None) -> RunOutcome:
        """Tick at the fixed rate: start the mission (or wait for the operator to), until it ends or, with ``serve``, until stopped.

        ``resume`` (from the journal of a run that never ended) continues at its first unfinished
        leg with the samples it had taken: none is taken twice.
        """
        if start:
            self._resume = resume
            if resume is not None and self.link.watch.commanded is None:
                self.link.watch.commanded = "a resumed run"  # the run it continues commanded the vehicle: it is made safe if stopped
            if resume is None:
                self.mission_state.start()
            else:
                legs = len(resume.route.waypoints) if resume.route is not None else self.mission_state.legs.leg_count
                self.mission_state.start(reason=resume.started_text(legs))
                if resume.route is not None:  # the operator had edited it: that is the route being driven
                    route = resume.route
                    reason = "the route as last edited, from the journal"
                    self.mission_state.set_route(route.waypoints, reason, leg_index=route.current, home=route.home)
                self.mission_state.continue_from(resume.leg_index, resume.samples)
        self.pacer.restart()
        try:
            while True:
                if self._stop_reason is not None:
                    if self.mission_state.status in _TREE_TICKS:
                        return self._end(self._abort(f"stopped: {self._stop_reason}"))  # the journal records it ABORTED
                    self.make_safe()
                    # between missions: the last one that ran, with its own outcome (not the one loaded since, never started)
                    ended = self.last_outcome or RunOutcome(self.mission_state.status, self.mission_state.reason, self.ticks)
                    return replace(ended, safe=self.safe_report)
                self.pacer.tick_started()
                ended = self._tick_once()
                if ended is not None and not serve:
                    return ended
                self._wait_until(self.pacer.next_due())
        finally:
            if self.pacer.late or self.pacer.skipped:
                log.warning("the loop ran behind its %g Hz: %s", 1.0 / self.period_s, self.pacer.summary())
            if self.progress:
                self.progress.update(force=True)
                self.progress.close()

    def _wait_until(self, t: float) -> None:
        """Sleep until the next tick, servicing the paced services (the base's 50 Hz motion commands) meanwhile."""
        if not self.paced:
            self.clock.sleep_until(t)
            return
        while self.clock.now() < t:
            for paced in self.paced:
                paced.pace()
            self.clock.sleep_until(min(t, *(paced.next_due for paced in self.paced)))

    def close(self) -> None:
        """Release what the services hold (the control socket) and the instrument, and the board (the next runtime may take it)."""
        self._close_sampler()
        for close in self._closers:
            close()
        self.board.runtime = None

    def _close_sampler(self) -> None:
        if self.sampler is not None:
            self.sampler.close()
            self.sampler = None

    def make_safe(self) -> bool:
        """Stop the tree and the paced services; command the safe mode (or the ending failsafe's mode) until the vehicle is seen in it.

        True once it is; what it came to is :attr:`safe_report`. The rules (bounded, never against a
        person) are :meth:`executive.autopilot_link.AutopilotLink.make_safe`'s; ``safe_timeout_s`` bounds it.
        """
        mode = None
        if self.tree is not None:
            mode = failsafe_mode(self.tree.root)  # an RTL or a surfacing the mission's failsafe asked for is not undone
            self.tree.interrupt()
            try:
                self.tree.root.stop(INVALID)  # stop what is running: a sample in progress is cancelled, not left open
            except Exception as exc:  # a behaviour's terminate() that raises: the vehicle is made safe all the same
                node = self._node_that_raised(exc)
                log.error("stopping the tree: %s", BehaviourCrashed(behaviour_path(node) if node else "(tree)", exc), exc_info=exc)
        for paced in self.paced:  # the base stops at once; the autopilot is told below
            paced.stop()
        made = self.link.make_safe(mode, announce=self.mission_state.announce, timeout_s=self.safe_timeout_s, report=self.report)
        self.safe_report = made.report
        return made.made

    def report(self) -> None:
        """Service the reporters now (the ground station: its commands answered, the mission reported), as the make-safe does."""
        for reporter in self._reporters:
            reporter.service()

    def _refuse(self, why: str) -> RunOutcome:
        """The distance rule refused the starting mission: it ends ABORTED, and as nothing was commanded nothing is undone."""
        users_code, self._refused, self._refused_users_code = self._refused_users_code, None, False
        reason = f"refused before anything was commanded: {why}"
        log.warning("mission %r %s", self.mission_state.mission.name if self.mission_state.mission else "", reason)
        self.mission_state.abort(reason)
        return RunOutcome(MissionStatus.ABORTED, reason, self.ticks, users_code=users_code)

    def _abort(self, reason: str) -> RunOutcome:
        log.warning("mission aborted: %s", reason)
        self.make_safe()
        self.mission_state.abort(reason)
        return RunOutcome(MissionStatus.ABORTED, reason, self.ticks)

    def _tick_once(self) -> RunOutcome | None:
        """Tick, and end the active mission if it is over; returns how it ended, if it did."""
        active = self.tree is not None
        try:
            status = self.tick()
        except BehaviourCrashed as crash:
            ours = registry.user_frame(crash.error) is None  # a user's behaviour is said by its file and line, without our traceback
            log.error("behaviour crashed: %s", crash, exc_info=crash.error if ours else None)
            return self._end(self._abort(f"behaviour crashed: {crash}"))
        if self.progress:
            self.progress.update()
        if self._refused is not None:
            return self._end(self._refuse(self._refused))
        if not active:
            return None
        if self.mission_state.status in _ENDED_BY_A_PERSON:
            self.make_safe()
            return self._end(RunOutcome(self.mission_state.status, self.mission_state.reason, self.ticks))
        if status == SUCCESS and (undone := self.mission_state.sample_log.work_left(self.mission_state.mission)) is not None:
            return self._end(self._abort(f"the tree ended, but {undone}"))  # never report success for work not done
        if status == SUCCESS:
            self.mission_state.complete()  # its reason says how many waypoints were reached
            return self._end(RunOutcome(MissionStatus.COMPLETED, self.mission_state.reason, self.ticks))
        if status == FAILURE:
            return self._end(self._abort(explain_failure(self.tree.root)))  # type: ignore[union-attr]
        return None

    def _end(self, outcome: RunOutcome) -> RunOutcome:
        """The running mission's end: the observers told; the outcome names the mission and its samples, and is kept as the last."""
        self.tree = None
        ran = self._running
        outcome = replace(outcome, mission=ran.name if ran else None, samples=len(self.mission_state.sample_log.taken), safe=self.safe_report)
        self.safe_report = None  # said with this outcome: a later one (a mission completed) is not made safe by it
        self.last_outcome = outcome
        for observer in self.observers:
            observer.end(str(outcome.status), outcome.reason)
        return outcome

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is not MissionStatus.PAUSED:
            self._tree_waits_for_resume = False
        if after is MissionStatus.RUNNING and before is not MissionStatus.PAUSED:
            self._install_tree()

    def _check_tree(self, mission: Mission) -> str | None:
        """Before a replacement: the new mission's tree can be built (kept for :meth:`_on_replace`)."""
        self.board.install()  # its behaviours' blackboard clients are this runtime's
        try:
            self._built = (mission, mission_tree.build(mission))
        except Exception as exc:  # a tree builder's error must refuse the replacement, not take the executive down
            return f"tree: cannot be built: {type(exc).__name__}: {exc}"
        return None

    def _on_replace(self, mission: Mission, reason: str) -> None:
        """Hot reload: the old tree stopped, the run ended as REPLACED, the new mission's tree (and sampler) installed for the resume."""
        if self.tree is not None:
            self.tree.root.stop(INVALID)  # a sample in progress is cancelled, not left open
            for observer in self.observers:
                observer.end(REPLACED, reason)
        self.mission = mission
        self.link.use(mission)
        self._install_tree()
        self._tree_waits_for_resume = True

    def _install_tree(self) -> None:
        """Build the tree (and its sampler) of the mission that is starting, or replacing a paused one."""
        self.board.install()  # its behaviours' blackboard clients are this runtime's
        mission = self._running = self.mission_state.mission
        assert mission is not None
        built, self._built = self._built, None
        prebuilt = built[1] if built is not None and built[0] is mission else None
        try:
            root, self._next_root = self._next_root or prebuilt or mission_tree.build(mission), None
        except registry.PluginError as exc:  # a user's tree that built at the check and raises now
            self._users_code_failed(str(exc))
            return
        self._close_sampler()
        try:
            self.sampler = open_sampler(mission, self.clock, simulator=self.simulated_vehicle)
        except InstrumentError as exc:  # checked before the run and at upload: the instrument has gone since
            log.error("%s", exc)
            self.sampler = UnavailableSampler(self.clock, mission.sampling or SamplingOptions(), str(exc))
        self._run_writers = [self.sampler] if self.sampler is not None else []
        self.tree = BehaviourTree(root)
        self._crash_site = CrashSite(root)  # names the node an exception comes out of, below
        self.reach.close()  # the tree waits for the distance rule
        resumed_from, self._resume = (self._resume.run if self._resume else None), None
        for observer in self.observers:
            observer.begin(mission, root, resumed_from)
        try:
            self.tree.setup(clock=self.tree_clock, autopilot=self.link.autopilot, mission_state=MissionPort(self.mission_state), sampler=self.sampler)
        except Exception as exc:
            node = self._node_that_raised(exc)
            named = f"{type(node).__module__}.{type(node).__qualname__} ({node.name!r})" if node else "(tree)"
            error = registry.PluginError(named, exc, doing="setup()")
            if error.where is None:
                raise  # not a user's code: a bug of ours
            self._users_code_failed(str(error))

    def _users_code_failed(self, why: str) -> None:
        """A user's tree or behaviour failed as the mission starts: it is refused before its tree ticks, nothing commanded (exit 2)."""
        log.error("%s", why)
        self._refused, self._refused_users_code = why, True


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Outcome is RunOutcome (executive.world.state.Outcome is a command's)
    return executive.moved_attribute(__name__, name)
