"""A person's intervention: a mode change the executive did not ask for, mid-mission, pauses the mission, hands off.

Once the executive has put the vehicle in a mode of its own choosing in this run (the mode the
current leg needs), any later change of the heartbeat's mode to a mode it did not ask for (within
``asked_within_s``) is someone else's: a ground station's HOLD (QGroundControl's Pause on a rover),
an RC mode switch, the autopilot's own failsafe. The mission goes PAUSED in the tick the heartbeat
shows it, with the reason (``HOLD set by the ground station``) in the log, the status and, through
the ground-station reporter, a STATUSTEXT; the leg is kept and nothing is commanded while paused
(:attr:`MissionState.hold_while_paused` false). It resumes on ``ctl resume``, a ground station's
MISSION_START or DO_PAUSE_CONTINUE, or when the vehicle is put back in the mode the leg was in
(the operator switching back): the tree then starts the leg again, in its own mode.

Not an intervention: the autopilot's own transitions, judged by their cause
(:mod:`executive.autopilot.mode_cause`: PX4 loitering once the take-off or the mission is done, going back to
the user's mode once disarmed, its failsafe; ArduSub's SURFACE done at the surface; a failsafe the
autopilot announces, "EKF failsafe": our failsafe for the same condition holds and resumes the leg,
asking again for its mode while the firmware's latch refuses it), and a change while the RC
take-over switch is high (the ``rc_takeover`` failsafe's business). ``/vehicle/mode_set_by`` says
whose each change was: ``us``, ``autopilot`` or ``others`` (a person).

A person may also steer without a mode change: a ground station's Pause or Go-to moves the target the
autopilot reports (:mod:`executive.autopilot.target_watch`) while the mode stays the leg's. That pauses the
mission the same way, hands off (``a ground station sent it to 47.39712, 8.54562``), and only an
explicit resume (``ctl resume``, the ground station's MISSION_START or DO_PAUSE_CONTINUE, the RC's)
takes it back: the mode never changed, so it says nothing. ``/vehicle/target_set_by`` says whose the
reported target is.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable

from executive.autopilot.mode_cause import PX4_TAKEOFF_ALT_RAD_PARAM, AutopilotCause, ModeChange, autopilot_cause, facts_may_lag
from executive.autopilot.port import AutopilotPort
from executive.autopilot.target_watch import PersonsTarget, TargetWatch
from executive.mission.events import Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.mission.model import RcConfig
from executive.sensing.rc import RcReading
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import MISSION_STATE_COMPLETE, EkfStatus, FenceStatus, GlobalPosition, MissionCurrent, MissionItemReached
from executive.world.vehicles import AutopilotName, VehicleProfile

log = logging.getLogger("executive.intervention")  # the name the log and the journal show, kept since 0.1

#: An RC channel that jumps this far between two reports was a switch thrown (a stick moves in smaller steps at 5-10 Hz).
SWITCH_JUMP_US = 300
#: A STATUSTEXT or a switch this recent explains a mode change.
EXPLAINS_WITHIN_S = 2.0
#: A change that facts streamed after the heartbeat may explain waits this long for them at most (MISSION_CURRENT comes at 1 Hz).
FACTS_WAIT_S = 1.5


def rc_takeover(rc: RcConfig, read: Callable[[str], object]) -> str | None:
    """Why the RC says a person has the vehicle (the take-over channel high, or switch C in MANUAL), if it does."""
    return RcReading.of(rc).person_has_vehicle(read)


class InterventionWatch:
    """A reader service: call :meth:`service` once per tick, after the RC reader and before the tree ticks."""

    def __init__(
        self,
        clock: Clock,
        autopilot: AutopilotPort,
        mission_state: MissionState,
        profile: VehicleProfile,
        rc: RcConfig,
        *,
        asked_within_s: float = 10.0,
        firmware: Callable[[], AutopilotName] | None = None,
    ) -> None:
        """``firmware``: whose rules judge a mode change (default: the port's autopilot, once the heartbeat told it)."""
        self._clock = clock
        self._autopilot = autopilot
        self.mission_state = mission_state
        self.profile = profile
        self.rc = rc
        self.asked_within_s = asked_within_s
        self.firmware = firmware or (lambda: autopilot.capabilities.autopilot)
        self._bb = blackboard.reader(
            "intervention watch",
            [
                "/vehicle/mode", "/link/up", "/vehicle/statustext", "/rc/channels", "/rc/switches", "/rc/connected", "/vehicle/armed",
                "/vehicle/landed_state", "/vehicle/mission_current", "/vehicle/mission_reached", "/vehicle/ekf", "/vehicle/system_status",
                "/vehicle/position", "/vehicle/position_target", "/vehicle/fence_status", "/vehicle/params",
            ],
        )  # fmt: skip
        self._out = blackboard.writer("intervention watch", ["/vehicle/mode_set_by", "/vehicle/target_set_by"])
        self._shown: str | None = None  # the mode the heartbeat showed at the last tick
        #: The mode the executive put the vehicle in (the current leg's); None until it has in this run.
        self.expected: str | None = None
        self._paused_here = False  # this watch paused the mission (a person has the vehicle)
        self._targets = TargetWatch()
        self._target_paused = False  # ... for a target of a person's, the mode unchanged: only an explicit resume ends it
        self._texts: deque[tuple[float, str]] = deque(maxlen=8)
        self._last_text: tuple[int, str] | None = None
        self._channels: tuple[int, ...] = ()
        self._switch_at = float("-inf")
        self._seen_rc = False  # an RC transmitter was seen: its loss can explain a mode change
        self._armed = False  # the armed flag at the last tick
        self._asks_seen: dict[str, float] = {}  # mode -> the time of our ask of it that the heartbeat has shown done
        self._disarmed_at = float("-inf")
        self._fence_breaches = 0  # FENCE_STATUS breach_count last said
        self._change_seen_at: float | None = None  # when a change still waiting for its facts (_facts_to_come) was first seen
        mission_state.events.subscribe(Transition, self._on_transition, Stage.INTERVENTION)

    def service(self) -> None:
        now = self._clock.now()
        self._note_texts(now)
        self._note_switches(now)
        self._note_fence()
        disarmed_just_now = self._note_arming(now)
        mode: str | None = self._bb.get("/vehicle/mode")
        if mode is None or not self._bb.get("/link/up"):
            return
        previous, self._shown = self._shown, mode
        if mode == previous:
            self._change_seen_at = None  # a change waiting for its facts that went back before they came
        cause: AutopilotCause | None = None
        set_by: str | None = None
        ours = self._our_ask(mode, now)
        if mode != previous and previous is not None and previous != "INITIALISING":
            if ours:
                set_by = "us"
            else:
                change = self._change(previous, mode, now, disarmed_just_now)
                cause = autopilot_cause(self.firmware(), self.profile.kind, change)
                if cause is None and self._facts_to_come(change, now):
                    self._shown = previous  # judged again at the next tick
                    return
                set_by = "others" if cause is None else "autopilot"
            self._out.set("/vehicle/mode_set_by", set_by)
        report, position = self._bb.get("/vehicle/position_target"), self._bb.get("/vehicle/position")
        persons_target = self._targets.judge(mode, report, self._autopilot.target_asked, position)
        self._out.set("/vehicle/target_set_by", self._targets.set_by)
        status = self.mission_state.status
        if status is MissionStatus.PAUSED and self._paused_here:
            if mode == self.expected and not self._target_paused:
                self._paused_here = False
                log.warning("the vehicle is back in %s -> resume", mode)
                try:
                    self.mission_state.resume(f"{mode} set again")
                except Refused as exc:  # a replacing mission's zones not on the autopilot: it stays paused, said
                    log.error("%s: not resumed: %s", mode, exc)
            return
        if status is MissionStatus.RUNNING and persons_target is not None:
            self._pause_for_target(persons_target)
            return
        if status is not MissionStatus.RUNNING or mode == previous:
            return
        if set_by == "us":
            self.expected = mode
            return
        if cause is not None and cause.pauses:  # the autopilot's own fence holds the vehicle: we do not drive it back out
            reason = f"{mode} set by the autopilot: {cause.why}"
            log.warning("%s -> pause, hands off (`ctl resume` goes on)", reason)
            self._paused_here = self._target_paused = True  # only an explicit resume: the leg's mode set again would drive on
            self.mission_state.pause(reason, hold=False)
            return
        if cause is not None:  # the autopilot's own transition: its failsafe is answered by ours, which resume the leg's mode
            if cause.failsafe:
                log.warning("%s set by the autopilot (%s): left to the failsafes, no pause", mode, cause.why)
            else:
                log.warning("%s (from %s) set by the autopilot (%s): no pause", mode, previous, cause.why)
            self.expected = mode if self.expected is not None else None
            return
        if self.expected is None or rc_takeover(self.rc, self._bb.get) is not None:
            return  # not yet mid-mission (nothing of ours to keep), or a take-over the rc_takeover failsafe answers
        reason = f"{mode} set by {self._who(now)}"
        log.warning("%s (the leg was in %s) -> pause, hands off", reason, self.expected)
        self._paused_here = True
        self.mission_state.pause(reason, hold=False)

    def _facts_to_come(self, change: ModeChange, now: float) -> bool:
        """Whether to judge ``change`` later: it may be the autopilot's by facts it streams after its heartbeat
        (:func:`~executive.autopilot.mode_cause.facts_may_lag`), and MISSION_CURRENT or EKF_STATUS_REPORT has not come since the change was
        first seen, for :data:`FACTS_WAIT_S` at most."""
        if not facts_may_lag(self.firmware(), self.profile.kind, change):
            self._change_seen_at = None
            return False
        seen_at = self._change_seen_at = now if self._change_seen_at is None else self._change_seen_at
        current: MissionCurrent | None = self._bb.get("/vehicle/mission_current")
        ekf: EkfStatus | None = self._bb.get("/vehicle/ekf")
        fresh = current is not None and current.time > seen_at and ekf is not None and ekf.time > seen_at
        if fresh or now - seen_at >= FACTS_WAIT_S:
            self._change_seen_at = None
            return False
        return True

    def _pause_for_target(self, target: PersonsTarget) -> None:
        """A target the autopilot reports that we did not ask for, in the leg's mode: a person's; pause, hands off."""
        if self.expected is None or rc_takeover(self.rc, self._bb.get) is not None:
            return  # not yet mid-mission, or a take-over the rc_takeover failsafe answers
        reason = f"a ground station {target.what}"
        log.warning("intervention: %s (POSITION_TARGET_GLOBAL_INT, the mode still %s) -> pause, hands off", reason, self._shown)
        self._paused_here = self._target_paused = True
        self.mission_state.pause(reason, hold=False)

    def _our_ask(self, mode: str, now: float) -> bool:
        """Whether the vehicle is in ``mode`` because we asked for it: an ask of ours (within ``asked_within_s``) not shown done before.

        An ask is done once the heartbeat shows its mode (then, or when asked for the mode the vehicle is in already): a later
        change to the same mode is not ours. The autopilot loitering after a take-off is not the pre-flight's LOITER, long done.
        """
        asked = self._autopilot.mode_asked_at(mode)
        if asked is None or now - asked > self.asked_within_s or self._asks_seen.get(mode) == asked:
            return False
        self._asks_seen[mode] = asked
        return True

    def _note_arming(self, now: float) -> bool:
        """Whether the vehicle disarmed at this tick or within :data:`EXPLAINS_WITHIN_S` (and is disarmed)."""
        armed = bool(self._bb.get("/vehicle/armed"))
        if self._armed and not armed:
            self._disarmed_at = now
        self._armed = armed
        return not armed and now - self._disarmed_at <= EXPLAINS_WITHIN_S

    def _change(self, previous: str, mode: str, now: float, disarmed_just_now: bool) -> ModeChange:
        current: MissionCurrent | None = self._bb.get("/vehicle/mission_current")
        position: GlobalPosition | None = self._bb.get("/vehicle/position")
        reached: MissionItemReached | None = self._bb.get("/vehicle/mission_reached")
        ekf: EkfStatus | None = self._bb.get("/vehicle/ekf")
        return ModeChange(
            previous=previous,
            mode=mode,
            armed=self._armed,
            disarmed_just_now=disarmed_just_now,
            landed_state=self._bb.get("/vehicle/landed_state"),
            mission_complete=current is not None and current.state == MISSION_STATE_COMPLETE,
            system_status=self._bb.get("/vehicle/system_status"),
            failsafe_text=self._failsafe_text(now),
            alt_rel_m=position.alt_rel_m if position is not None else None,
            takeoff_alt_msl_m=self._autopilot.takeoff_alt_msl_m,
            alt_msl_m=position.alt_msl_m if position is not None else None,
            climb_m_s=-position.vd_m_s if position is not None else 0.0,
            position_age_s=now - position.time if position is not None else 0.0,
            fence_breached=self._fence_breached(now),
            mission_end_reached=current is not None and current.total > 0 and reached is not None and reached.highest >= current.total,
            position_ok=ekf.position_ok() if ekf is not None else None,
            takeoff_alt_rad_m=(self._bb.get("/vehicle/params") or {}).get(PX4_TAKEOFF_ALT_RAD_PARAM),
        )

    def _note_fence(self) -> None:
        """A new breach of the autopilot's own fence is said (log, ground station) whatever the mission's state: a person may have
        driven it there."""
        status: FenceStatus | None = self._bb.get("/vehicle/fence_status")
        if status is None or not status.breached or status.count <= self._fence_breaches:
            return
        self._fence_breaches = status.count
        log.warning("the autopilot's own fence is breached (FENCE_STATUS, breach %d): its FENCE_ACTION acts", status.count)
        self.mission_state.announce("autopilot's fence breached")

    def _fence_breached(self, now: float) -> bool:
        """FENCE_STATUS reported the autopilot's fence breached within :data:`EXPLAINS_WITHIN_S` (it comes with the breach, at once)."""
        status: FenceStatus | None = self._bb.get("/vehicle/fence_status")
        return status is not None and status.breached and now - status.time <= EXPLAINS_WITHIN_S

    def _failsafe_text(self, now: float) -> str | None:
        """The autopilot's failsafe notice just before the change ("EKF failsafe"), if it sent one; its RC failsafe if the transmitter is gone.

        ArduRover reports every RC channel 0 only once its own RC failsafe has acted (FS_ACTION: HOLD, RTL...).
        """
        text = next((text for t, text in reversed(self._texts) if now - t <= EXPLAINS_WITHIN_S and "failsafe" in text.lower()), None)
        if text is None and self._seen_rc and not self._bb.get("/rc/connected"):
            return "RC failsafe: the transmitter is gone"
        return text

    def _who(self, now: float) -> str:
        if now - self._switch_at <= EXPLAINS_WITHIN_S:
            return "the RC"
        return "the ground station"

    def _note_texts(self, now: float) -> None:
        text = self._bb.get("/vehicle/statustext")
        if text is not None and text is not self._last_text:
            self._last_text = text
            self._texts.append((now, text[1]))

    def _note_switches(self, now: float) -> None:
        self._seen_rc = self._seen_rc or bool(self._bb.get("/rc/connected"))
        channels: tuple[int, ...] = self._bb.get("/rc/channels")
        if channels is self._channels:
            return
        if channels != self._channels and any(a and b and abs(a - b) >= SWITCH_JUMP_US for a, b in zip(channels, self._channels, strict=False)):
            self._switch_at = now
        self._channels = channels

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is MissionStatus.RUNNING and before is not MissionStatus.PAUSED:
            self.expected = None  # a new run: nothing of ours yet
        if after is not MissionStatus.PAUSED:
            self._paused_here = self._target_paused = False
        if after is MissionStatus.RUNNING:
            self._targets.forget()  # the leg's target goes out again: judged anew from its report
