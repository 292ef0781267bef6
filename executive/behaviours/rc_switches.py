"""The operator's RC switches as commands (the tracked UGV's AgileX / FlySky transmitter).

Each behaviour watches one switch of ``/rc/switches`` (the RC reader writes it from RC channels; a
CAN reader from frame 0x241). Switch C (the mode) acts on its POSITION (:class:`ModeSwitch`); the
others act when the switch MOVES:

- the first position seen is only taken note of: a switch left down at start-up arms nothing;
- a position already acted on is not acted on again when the behaviour is re-entered (a guard
  recovered, a pause ended), so the executive does not fight a ground station or a failsafe that
  changed the mode since;
- a move made while the behaviour was not ticked (RC stale, link lost) is acted on when it is
  seen: it is the operator's latest wish.

They never end: RUNNING, with the outcome of the last move in the feedback. A refusal (by these
rules or by the autopilot) is the operator's to answer by moving the switch again; it does not end
the mission. Guard them with :class:`~executive.behaviours.rc_guards.RcFresh`: a frozen report must not
pass for a switch held still.
"""

from __future__ import annotations

import logging

from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.autopilot.asking import ARM, Asker, Rules, Step, Voice, refusal_reason
from executive.autopilot.fallbacks import DISARM
from executive.behaviours.auto_route import AUTO
from executive.behaviours.base import RUNNING, ExecutiveBehaviour
from executive.mission.lifecycle import Refused
from executive.mission.model import Waypoint
from executive.mission.port import MissionPort
from executive.mission.route import RouteError, add_at_end, clear, current_index, remove_current
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import EkfStatus, GlobalPosition, Outcome, RcSwitches, SwitchPosition

log = logging.getLogger(__name__)

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN

#: The knob VRA does not always come back to 0: within 25 either side it is in the middle (the thesis's margin).
KNOB_MIDDLE = 25
#: ArduRover arms only in this mode, as the thesis states (its rc_arm_disarm node relies on it).
ARMABLE_MODE = "MANUAL"


class SwitchWatcher(ExecutiveBehaviour):
    """Calls :meth:`moved` when ``switch`` (``"swa"`` .. ``"swd"``) takes a new position, :meth:`follow` on every tick."""

    def __init__(self, switch: str, name: str) -> None:
        self.reads = ("/rc/switches", *self.reads)
        super().__init__(name)
        self.switch = switch
        self.label = f"switch {switch[-1].upper()}"
        self.position: SwitchPosition | None = None  # the last position seen, kept across re-entries

    def update(self) -> Status:
        switches: RcSwitches | None = self.get("/rc/switches")
        now: SwitchPosition | None = getattr(switches, self.switch) if switches is not None else None
        if now is None and self.position is None:
            self.feedback_message = f"no {self.label} position yet"
        elif now is not None and now != self.position:
            first, self.position = self.position is None, now
            if first:
                self.feedback_message = f"{self.label} {now}: move it to act"
            else:
                assert switches is not None
                self.moved(now, switches)
        self.follow()
        return RUNNING

    def moved(self, position: SwitchPosition, switches: RcSwitches) -> None:
        """The switch was moved to ``position``."""
        raise NotImplementedError

    def report(self, message: str) -> None:
        """What a move did, or came to: the feedback, and the log (the operator's actions are worth a line each)."""
        self.feedback_message = message
        log.info("%s", message)

    def follow(self) -> None:
        """Watch what the last move asked for (every tick)."""


class ModeSwitch(SwitchWatcher):
    """Switch C sets the mode by its position: up MANUAL, middle AUTO, down ``aux_mode`` (none: ignored).

    The position is acted on when the switch moves and whenever the behaviour is (re-)entered: the
    mission starts, a failsafe recovered, a pause ended. So a switch left in AUTO puts the vehicle
    back in AUTO after a hold, and a switch already in AUTO at the start needs no flick. Between
    those, a mode someone else set is not fought (the runtime pauses the mission meanwhile).

    AUTO is asked only with a route recorded, and only once the autopilot holds it (an upload in
    progress is waited for; a later move replaces the wait). A mode already shown by the heartbeat
    is not asked again. Confirmed by the heartbeat. Refused or not shown within
    ``confirm_timeout_s``: asked again ``retry_s`` later (the firmware's own failsafe may still be
    latched: ArduRover refuses AUTO while its EKF failsafe is) until ``give_up_after_s`` from the
    wish, then said in the feedback and left to the operator. Asked by an
    :class:`~executive.autopilot.asking.Asker`; each step is reported (the feedback and the log).
    """

    reads = ("/vehicle/mode", "/vehicle/statustext", "/vehicle/mission_items", blackboard.command_key(Outcome.MODE))
    needs = ("clock", "autopilot", "mission_state")
    clock: Clock
    autopilot: AutopilotPort
    mission_state: MissionPort
    from_mission = {"aux_mode": "rc_route.aux_mode"}

    def __init__(
        self,
        aux_mode: str | None = None,
        name: str = "Switch C: mode",
        confirm_timeout_s: float = 5.0,
        retry_s: float = 2.0,
        give_up_after_s: float = 20.0,
    ) -> None:
        super().__init__("swc", name)
        self.modes = {UP: "MANUAL", MIDDLE: AUTO, DOWN: aux_mode.upper() if aux_mode else None}
        self.confirm_timeout_s = confirm_timeout_s
        self.retry_s = retry_s
        self.give_up_after_s = give_up_after_s
        self._wanted: str | None = None
        self._wished_at = 0.0
        self._entered = False
        rules = Rules(
            judge_after_s=confirm_timeout_s,
            again_after_s=0.0,
            rest_s=retry_s,
            asks_before_next=None,
            needs_ack=False,
            link_down_counts=True,
            give_up_after_s=give_up_after_s,
        )
        self._asker = Asker(self, None, rules=rules, voice=_ModeVoice(self), escalate=False, bounded=True)

    def initialise(self) -> None:
        self._entered = True  # act on the position the switch is in, once it is known

    def update(self) -> Status:
        switches: RcSwitches | None = self.get("/rc/switches")
        now = switches.swc if switches is not None else None
        if now is not None and (self._entered or now != self.position):
            self._entered = False
            self.position = now
            self.moved(now, switches)  # type: ignore[arg-type]
        elif self.position is None:
            self.feedback_message = f"no {self.label} position yet"
        self.follow()
        return RUNNING

    def moved(self, position: SwitchPosition, switches: RcSwitches) -> None:
        self._asker.forget()
        self._wanted = self.modes[position]
        self._wished_at = self.clock.now()
        if self._wanted is None:
            self.report(f"{self.label} {position}: no aux mode set (rc_route.aux_mode): ignored")

    def follow(self) -> None:
        mode = self._wanted
        if mode is None:
            return
        now = self.clock.now()
        said = f"{self.label} {self.position}: {mode}"
        asker = self._asker
        if asker.asking is None:
            if self.get("/vehicle/mode") == self.autopilot.mode_name(mode):
                self.report(f"{said} (already)")
                self._wanted = None
            elif self._may_ask(mode, said):
                asker.start(mode, said, since=self._wished_at)
            return
        asker.follow_up(now, ask=False)
        if asker.done or asker.exhausted:
            self._wanted = None
        elif asker.due(now):
            if self._may_ask(mode, said):
                asker.ask_again()
        elif not asker.asking.judged:
            self.feedback_message = f"{said}: asked, mode is {self.get('/vehicle/mode')}"

    def _may_ask(self, mode: str, said: str) -> bool:
        """AUTO only with a route recorded (else the wish is dropped), and once the autopilot holds it (an upload is waited for)."""
        if mode != AUTO:
            return True
        if not self.mission_state.route.waypoints:
            self.report(f"{said} not asked: no route recorded")
            self._wanted = None
            return False
        waiting = self.autopilot.route_differs(self.mission_state.route.waypoints, self.get("/vehicle/mission_items"))
        if waiting is not None:
            self.feedback_message = f"{said} waits for the route upload: {waiting}"
            return False
        return True


class _ModeVoice(Voice):
    """Switch C's asks, as the operator hears of them: the behaviour's feedback and the log."""

    def __init__(self, switch: ModeSwitch) -> None:
        self.switch = switch

    def asked(self, step: Step, again: bool) -> None:
        self.switch.report(f"{step.cause}: asked" + (" again" if again else ""))

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        switch = self.switch
        refusal = refusal_reason(step.status, step.request, switch.get("/vehicle/statustext"))
        why = refusal or f"not shown after {switch.confirm_timeout_s:g} s (mode is {switch.get('/vehicle/mode')})"
        switch.report(f"{step.cause} {why}" + ("" if step.gave_up else f"; asking again in {switch.retry_s:g} s"))

    def no_such_mode(self, cause: str, step: str) -> None:
        self.switch.report(f"{cause}: the autopilot has no such mode")

    def confirmed(self, step: Step, took_s: float) -> None:
        self.switch.report(step.cause)


class ArmSwitch(SwitchWatcher):
    """Switch D arms (down) and disarms (up); arming only in MANUAL (else refused here, with the reason).

    Nothing is asked when the vehicle already is as the switch says. Switch D down while switch C is
    up but the heartbeat does not show MANUAL yet (the operator flicked both at once, or the tick that
    saw them both came late) arms once it does, if within ``confirm_timeout_s`` and switch C is still
    up. Confirmed by the heartbeat; refused (pre-arm checks), unanswered or not shown within
    ``confirm_timeout_s``: said in the feedback.
    """

    reads = ("/vehicle/mode", "/vehicle/armed", "/vehicle/statustext", blackboard.command_key(Outcome.ARMING))
    needs = ("clock", "autopilot")
    clock: Clock
    autopilot: AutopilotPort

    def __init__(self, name: str = "Switch D: arm", confirm_timeout_s: float = 5.0) -> None:
        super().__init__("swd", name)
        self.confirm_timeout_s = confirm_timeout_s
        rules = Rules(judge_after_s=confirm_timeout_s, asks_before_next=1, needs_ack=False, link_down_counts=True)
        self._asker = Asker(self, None, rules=rules, voice=_ArmVoice(self), escalate=False, bounded=True)
        self._manual_awaited_since: float | None = None  # switch D down with switch C up: arming once MANUAL shows

    def moved(self, position: SwitchPosition, switches: RcSwitches) -> None:
        self._asker.forget()
        self._manual_awaited_since = None
        said = f"{self.label} {position}"
        if position is MIDDLE:
            self.report(f"{said}: a two-position switch has no middle: ignored")
            return
        arm = position is DOWN
        what = "armed" if arm else "disarmed"
        if bool(self.get("/vehicle/armed")) == arm:
            self.report(f"{said}: already {what}")
            return
        mode = self.get("/vehicle/mode")
        if arm and mode != self.autopilot.mode_name(ARMABLE_MODE):
            if switches.swc is UP:
                self._manual_awaited_since = self.clock.now()
                self.report(f"{said}: arming once the mode is {ARMABLE_MODE} (switch C up; the mode is {mode})")
                return
            self.report(f"{said}: arming refused: the mode is {mode}; ArduRover arms only in {ARMABLE_MODE} (switch C up)")
            return
        self._ask(arm)

    def _ask(self, arm: bool) -> None:
        self._asker.start(ARM if arm else DISARM, f"{self.label} {self.position}")

    def follow(self) -> None:
        if self._manual_awaited_since is not None:
            self._await_manual(self._manual_awaited_since)
        if self._asker.asking is not None and not self._asker.done and not self._asker.exhausted:
            self._asker.follow_up(self.clock.now(), ask=False)

    def _await_manual(self, since: float) -> None:
        mode = self.get("/vehicle/mode")
        switches: RcSwitches | None = self.get("/rc/switches")
        said = f"{self.label} {self.position}"
        if switches is None or switches.swc is not UP:
            self._manual_awaited_since = None
            self.report(f"{said}: arming refused: switch C left MANUAL before the mode showed it (the mode is {mode})")
        elif mode == self.autopilot.mode_name(ARMABLE_MODE):
            self._manual_awaited_since = None
            self._ask(arm=True)
        elif self.clock.now() - since > self.confirm_timeout_s:
            self._manual_awaited_since = None
            self.report(f"{said}: arming refused: the mode is {mode}, not {ARMABLE_MODE} after {self.confirm_timeout_s:g} s (switch C up)")


class _ArmVoice(Voice):
    """Switch D's one ask, as the operator hears of it: the behaviour's feedback and the log."""

    def __init__(self, switch: ArmSwitch) -> None:
        self.switch = switch

    def asked(self, step: Step, again: bool) -> None:
        self.switch.report(f"{step.cause}: asked to be {_what(step)}")

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        switch = self.switch
        refusal = refusal_reason(step.status, step.request, switch.get("/vehicle/statustext"))
        switch.report(f"{step.cause}: not {_what(step)}: {refusal or f'not shown after {switch.confirm_timeout_s:g} s'}")

    def confirmed(self, step: Step, took_s: float) -> None:
        self.switch.report(f"{step.cause}: {_what(step)}")


def _what(step: Step) -> str:
    return "armed" if step.step == ARM else "disarmed"


class RouteEditSwitch(SwitchWatcher):
    """Switch A down edits the route, one edit per flip; the knob VRA says which edit.

    Knob in [-100, -26]: clear the route; [26, 100]: remove the current waypoint (the one the
    vehicle heads for, the last once the route is done); [-25, 25]: add a waypoint where the vehicle
    is, at the end. A flip while switch B is down does nothing (the thesis's guard against an edit
    by a slip of the hand). Adding needs a position the EKF vouches for, no older than
    ``max_position_age_s``. The new route goes to the mission state (``set_route``); refusals are
    said in the feedback and change nothing.
    """

    reads = ("/vehicle/position", "/vehicle/ekf")
    needs = ("clock", "mission_state")
    clock: Clock
    mission_state: MissionPort

    def __init__(self, name: str = "Switch A: edit the route", max_position_age_s: float = 1.0) -> None:
        super().__init__("swa", name)
        self.max_position_age_s = max_position_age_s

    def moved(self, position: SwitchPosition, switches: RcSwitches) -> None:
        if position is not DOWN:
            return
        if switches.swb is DOWN:
            self.report(f"{self.label} DOWN: ignored while switch B is down")
            return
        knob = switches.knob
        if knob is None:
            self.report(f"{self.label} DOWN: no knob VRA position: nothing done")
            return
        said = f"{self.label} DOWN, knob {knob:+d}"
        route = self.mission_state.route
        edit = "clear the route" if knob < -KNOB_MIDDLE else "remove the current waypoint" if knob > KNOB_MIDDLE else "add a waypoint here"
        try:
            if knob < -KNOB_MIDDLE:
                new, done = clear(route), f"route cleared ({len(route)} waypoints removed)"
            elif knob > KNOB_MIDDLE:
                new, done = remove_current(route), f"waypoint {(current_index(route) or 0) + 1}/{len(route)} removed"
            else:
                here = self._here()
                new, done = add_at_end(route, here), f"waypoint {len(route) + 1} added at {here.lat:.7f}, {here.lon:.7f}"
            position: GlobalPosition | None = self.get("/vehicle/position")
            at = (position.lat, position.lon) if position is not None else None
            self.mission_state.route_edited(new.waypoints, f"{said}: {done}", leg_index=new.current, vehicle_at=at)
        except (RouteError, Refused) as exc:
            self.report(f"{said}: {edit} refused: {exc}")
            return
        self.report(f"{said}: {done}")

    def _here(self) -> Waypoint:
        """A waypoint where the vehicle is; RouteError when that is not known well enough."""
        position: GlobalPosition | None = self.get("/vehicle/position")
        ekf: EkfStatus | None = self.get("/vehicle/ekf")
        if position is None:
            raise RouteError("no position")
        if ekf is None or not ekf.position_ok():
            raise RouteError("the EKF has no position estimate")
        age = self.clock.now() - position.time
        if age > self.max_position_age_s:
            raise RouteError(f"the last position is {age:.1f} s old")
        return Waypoint(lat=position.lat, lon=position.lon)
