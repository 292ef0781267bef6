"""Flow control for missions: waiting with a limit, waiting out failed guards, and looping over legs."""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from typing import Any

import py_trees
from py_trees.common import Access, Status

from executive.autopilot import AutopilotPort, Request
from executive.autopilot.asking import READS, Announce, Asker
from executive.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.guards import Guard
from executive.mission.lifecycle import MissionStatus
from executive.mission.port import MissionPort
from executive.world.clock import Clock

log = logging.getLogger(__name__)


class ClockedDecorator(py_trees.decorators.Decorator):
    """A decorator that times its child on the injected clock (``setup(clock=...)``), as every behaviour here."""

    catalogued = False
    clock: Clock | None = None

    def setup(self, **services: object) -> None:
        clock = services.get("clock")
        if clock is None:
            raise RuntimeError(f"{self.name}: setup() needs clock")
        self.clock = clock  # type: ignore[assignment]


class WaitUntil(ClockedDecorator):
    """RUNNING until the child succeeds (then SUCCESS); FAILURE if it has not within ``limit_s``.

    A failed child is ticked again ``retry_s`` later (a condition: every tick; an action such as
    arming: not so often that the autopilot is flooded). A ``hint`` (what a person does to end the
    wait: ``to arm it: executive ctl arm ...``) is logged when the wait starts, unless the child
    succeeds at once, and said again on giving up.
    """

    def __init__(self, child: py_trees.behaviour.Behaviour, limit_s: float, name: str | None = None, retry_s: float = 0.0, hint: str = "") -> None:
        super().__init__(name=name or f"Wait until {child.name}", child=child)
        self.limit_s = limit_s
        self.retry_s = retry_s
        self.hint = hint

    def initialise(self) -> None:
        assert self.clock is not None
        self.started = self.clock.now()
        self._failed_at = float("-inf")
        self._hinted = not self.hint

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        assert self.clock is not None
        if self.status != RUNNING:
            self.initialise()
        if self.clock.now() - self._failed_at >= self.retry_s:
            yield from self.decorated.tick()
            if self.decorated.status == FAILURE:
                self._failed_at = self.clock.now()
        new_status = self.update()
        if new_status != RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def update(self) -> Status:
        assert self.clock is not None
        if self.decorated.status == SUCCESS:
            self.feedback_message = ""
            return SUCCESS
        waited = self.clock.now() - self.started
        if waited > self.limit_s:
            hint = f" ({self.hint})" if self.hint else ""
            self.feedback_message = f"gave up after {self.limit_s:g} s: {self.decorated.feedback_message}{hint}"
            return FAILURE
        if not self._hinted:
            self._hinted = True
            log.info("%s (up to %g s): %s", self.name, self.limit_s, self.hint)
        self.feedback_message = f"waiting ({waited:.0f}/{self.limit_s:g} s): {self.decorated.feedback_message}"
        return RUNNING


class Timeout(ClockedDecorator):
    """The child's status, but FAILURE (the child stopped) once it has been RUNNING ``timeout_s`` of vehicle time.

    py_trees' own Timeout reads the wall clock; this one the injected clock, as every behaviour here.
    """

    def __init__(self, child: py_trees.behaviour.Behaviour, timeout_s: float, name: str | None = None) -> None:
        super().__init__(name=name or f"{child.name} (within {timeout_s:g} s)", child=child)
        self.timeout_s = timeout_s

    def initialise(self) -> None:
        assert self.clock is not None
        self.started = self.clock.now()

    def update(self) -> Status:
        assert self.clock is not None
        status = self.decorated.status
        if status == RUNNING and self.clock.now() - self.started > self.timeout_s:
            self.decorated.stop(INVALID)
            self.feedback_message = f"timed out after {self.timeout_s:g} s: {self.decorated.feedback_message}"
            return FAILURE
        self.feedback_message = self.decorated.feedback_message
        return status


def hold_mode_for(vtol_state: str | None, hold_mode: str | None, fixed_wing_hold_mode: str | None) -> str | None:
    """The mode to hold in: ``fixed_wing_hold_mode`` (if any) for a VTOL flying as a plane, which cannot hover, else ``hold_mode``."""
    return fixed_wing_hold_mode if fixed_wing_hold_mode and vtol_state == "FW" else hold_mode


class WaitForGuards(TimedBehaviour):
    """RUNNING while one of ``guards`` fails this tick (waiting for it to recover), up to ``limit_s``.

    Put it after the guarded branch in a reactive selector. When every guard holds, the branch
    itself failed, and so does this: there is nothing to wait for. On entry it asks for
    ``hold_mode`` unless a failing guard says a person has the vehicle; a VTOL in fixed-wing
    flight (``/vehicle/vtol_state`` FW) is held in ``fixed_wing_hold_mode`` instead, when given.
    The hold is asked again until the autopilot accepts it and the heartbeat shows it
    (:class:`~executive.autopilot.asking.Asker`, without its next reactions: the mission's
    ``Failsafe`` has those); the feedback says what it waits for (``asking HOLD: refused (FAILED) x2``).
    """

    reads = ("/vehicle/vtol_state", *READS)
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    catalogued = False  # the failsafe (Failsafe, failsafe_guarded) does this with the mission's policy

    def __init__(
        self,
        guards: Sequence[Guard],
        limit_s: float,
        hold_mode: str | None = None,
        name: str = "Wait for guards",
        fixed_wing_hold_mode: str | None = None,
    ) -> None:
        super().__init__(name)
        self.guards = tuple(guards)
        self.limit_s = limit_s
        self.hold_mode = hold_mode
        self.fixed_wing_hold_mode = fixed_wing_hold_mode
        self._announce: Announce | None = None
        self._reacting = Asker(self, None, escalate=False)

    def setup(self, **services: Any) -> None:
        super().setup(**services)
        mission_state: MissionPort | None = services.get("mission_state")
        self._announce = mission_state.announce if mission_state is not None else None

    def initialise(self) -> None:
        super().initialise()
        self._reacting = Asker(self, None, escalate=False, announce=self._announce)

    def terminate(self, new_status: Status) -> None:
        # The guards recovered (or the mission ended): a hold still being retried must not reach the vehicle now.
        self._reacting.cancel()

    def update(self) -> Status:
        failing = [g for g in self.guards if g.status == FAILURE]
        if not failing:
            self.feedback_message = ""  # the branch it stands behind failed: that is the reason to report
            return FAILURE
        why = "; ".join(f"{g.name} {g.feedback_message}" for g in failing)
        if self.elapsed > self.limit_s:
            self.feedback_message = f"not recovered after {self.limit_s:g} s: {why}"
            return FAILURE
        mode = hold_mode_for(self.get("/vehicle/vtol_state"), self.hold_mode, self.fixed_wing_hold_mode)
        if any(g.pilot_in_control for g in failing):
            self._reacting.stand_back()
            state = "hands off"
        else:
            if mode and self._reacting.asking is None:  # at once, or when the person who had the vehicle lets go
                self._reacting.start(mode, failing[0].name.rstrip("?"))
            self._reacting.follow_up(self.clock.now())
            state = self._reacting.state() or "waiting"
        self.feedback_message = f"{state} ({self.elapsed:.0f}/{self.limit_s:g} s): {why}"
        return RUNNING


class ForEachLeg(py_trees.decorators.Decorator):
    """Run the child once per remaining leg of the mission; SUCCESS when no leg is left.

    The leg index lives in the mission state, so interrupting and re-entering this node (a guard
    failed, the mission was paused) continues with the same leg. One child serves every leg, so
    the tree and its tick cost do not grow with the mission.
    """

    def __init__(self, child: py_trees.behaviour.Behaviour, name: str = "For each leg") -> None:
        super().__init__(name=name, child=child)
        self.mission_state: MissionPort | None = None

    def setup(self, **services: object) -> None:
        state = services.get("mission_state")
        if state is None:
            raise RuntimeError(f"{self.name}: setup() needs mission_state")
        self.mission_state = state  # type: ignore[assignment]

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        assert self.mission_state is not None
        if self.status != RUNNING:
            self.initialise()
        if self.mission_state.target is not None:
            yield from self.decorated.tick()
        new_status = self.update()
        if new_status != RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def update(self) -> Status:
        assert self.mission_state is not None
        state = self.mission_state
        if state.target is not None and self.decorated.status == SUCCESS:
            state.leg_done()
        if state.target is None:
            self.feedback_message = f"{state.leg_index}/{state.leg_count} legs done"
            return SUCCESS
        if self.decorated.status == FAILURE:
            self.feedback_message = f"leg {state.leg_index + 1}/{state.leg_count} failed: {_why_failed(self.decorated)}"
            return FAILURE
        self.feedback_message = f"leg {state.leg_index + 1}/{state.leg_count}"
        return RUNNING


def _why_failed(node: py_trees.behaviour.Behaviour) -> str:
    """The reason of the deepest failed behaviour under ``node`` that gives one (a composite gives none)."""
    for child in node.iterate():  # children before their parents
        if child.status == FAILURE and child.feedback_message:
            return child.feedback_message if child is node else f"{child.name}: {child.feedback_message}"
    return ""


#: Read every tick (an Enum class's member is slow to read from it: executive.behaviours.base.RUNNING says why).
_PAUSED = MissionStatus.PAUSED


class UnlessPaused(py_trees.decorators.Decorator):
    """Runs the mission body, except while the mission is PAUSED: then the body is stopped and the vehicle held.

    A pause by a person who took the vehicle (``MissionPort.hold_while_paused`` false) commands nothing.

    The body keeps no progress of its own (the leg is in the mission state), so on resume it
    starts again from its first child and carries on with the same leg: back to GUIDED, same target.
    A VTOL in fixed-wing flight is held in ``fixed_wing_hold_mode`` instead, when given.
    """

    from_mission = {"hold_mode": "vehicle.safe_mode", "fixed_wing_hold_mode": "vehicle.fixed_wing_hold_mode"}

    def __init__(
        self, child: py_trees.behaviour.Behaviour, hold_mode: str, name: str = "Unless paused", fixed_wing_hold_mode: str | None = None
    ) -> None:
        super().__init__(name=name, child=child)
        self.hold_mode = hold_mode
        self.fixed_wing_hold_mode = fixed_wing_hold_mode
        self.mission_state: MissionPort | None = None
        self.autopilot: AutopilotPort | None = None
        self._holding: str | None = None  # the mode asked for while paused
        self._hold_ticket: Request | None = None
        self._bb = self.attach_blackboard_client()
        self._bb.register_key(key="/vehicle/vtol_state", access=Access.READ)

    def setup(self, **services: object) -> None:
        missing = [n for n in ("mission_state", "autopilot") if services.get(n) is None]
        if missing:
            raise RuntimeError(f"{self.name}: setup() needs {', '.join(missing)}")
        self.mission_state = services["mission_state"]  # type: ignore[assignment]
        self.autopilot = services["autopilot"]  # type: ignore[assignment]

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        assert self.mission_state is not None and self.autopilot is not None
        if self.status != RUNNING:
            self.initialise()
        state = self.mission_state
        if state.status is _PAUSED:
            if self.decorated.status == RUNNING:
                self.decorated.stop(INVALID)
            if not state.hold_while_paused:  # a person took the vehicle (a mode we did not ask for): hands off
                self.feedback_message = f"paused at leg {state.leg_number}/{state.leg_count}: {state.reason}; hands off"
            else:
                if self._holding is None:
                    self._holding = hold_mode_for(self._bb.get("/vehicle/vtol_state"), self.hold_mode, self.fixed_wing_hold_mode) or self.hold_mode
                    self._hold_ticket = self.autopilot.set_mode(self._holding)
                self.feedback_message = f"paused at leg {state.leg_number}/{state.leg_count}: holding in {self._holding}"
            new_status = RUNNING
        else:
            if self._holding is not None:  # resumed: a hold still being retried must not undo the resumed leg
                self.autopilot.cancel(self._hold_ticket)
            self._holding = None
            yield from self.decorated.tick()
            self.feedback_message = ""
            new_status = self.decorated.status
        if new_status != RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def update(self) -> Status:
        return self.status  # decided in tick(): the body's status, or RUNNING while paused
