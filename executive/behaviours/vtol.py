"""VTOL and local-frame actions: take off, land, transition between multicopter and fixed-wing flight, go to a local point."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

from py_trees.common import Status

from executive.autopilot import AutopilotPort, Request, VtolState
from executive.autopilot.asking import Asker, Step, Voice, refusal_reason
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.commands import ONE_ASK, CommandAction
from executive.behaviours.repositioning import Repositioning
from executive.world import blackboard, frames
from executive.world.state import GlobalPosition, HomePosition, Outcome


class TakeOff(CommandAction):
    """Climb to ``alt_m`` above home (a VTOL climbs as a multicopter) with MAV_CMD_NAV_TAKEOFF.

    The vehicle must be in GUIDED and armed, on the ground (ArduPlane refuses otherwise: put SetMode
    and Arm before it). SUCCESS when ``/vehicle/landed_state`` is IN_AIR and the relative altitude
    is at least ``reached_fraction`` of ``alt_m``; FAILURE when refused or not there in time. On
    PX4 param7 is an altitude above sea level: home's plus ``alt_m`` (NaN, PX4's default take-off
    altitude, before home is known).

    Already off the ground (a climb stopped by a failsafe hold, then resumed), ArduPilot refuses
    NAV_TAKEOFF: the climb goes on with DO_REPOSITION straight above where the vehicle is (a QuadPlane
    with Q_GUIDED_MODE=1 flies it on its lift motors, as it does the hover point).
    """

    reads = ("/vehicle/landed_state", "/vehicle/position", "/vehicle/home", blackboard.command_key(Outcome.REPOSITION))
    outcome = Outcome.TAKE_OFF
    from_mission = {"alt_m": "vtol.takeoff_alt_m"}
    param_docs = {"alt_m": "the height above home to climb to", "reached_fraction": "reached at this fraction of alt_m (and IN_AIR)"}

    def __init__(self, alt_m: float, name: str | None = None, confirm_timeout_s: float = 60.0, reached_fraction: float = 0.95) -> None:
        super().__init__(name or f"Take off to {alt_m:g} m", confirm_timeout_s)
        self.alt_m = alt_m
        self.reached_fraction = reached_fraction

    def request(self) -> Request:
        request = self.autopilot.take_off(
            self.alt_m,
            home=self.get("/vehicle/home"),
            position=self.get("/vehicle/position"),
            airborne=self.get("/vehicle/landed_state") in ("TAKEOFF", "IN_AIR"),
        )
        self.outcome = request.outcome  # ArduPilot climbs on in the air with DO_REPOSITION: its ack says whether the climb was taken
        return request

    def confirmed(self) -> bool:
        position: GlobalPosition | None = self.get("/vehicle/position")
        high = position is not None and position.alt_rel_m >= self.reached_fraction * self.alt_m
        return self.get("/vehicle/landed_state") == "IN_AIR" and high

    def progress(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        alt = f"{position.alt_rel_m:.1f}" if position is not None else "?"
        return f"{self.get('/vehicle/landed_state') or 'landed state unknown'} at {alt}/{self.alt_m:g} m"


class Land(CommandAction):
    """Land with a landing mode (QLAND for a QuadPlane; on PX4 its equivalent, AUTO.LAND).

    SUCCESS when ``/vehicle/landed_state`` is ON_GROUND and the vehicle has disarmed (ArduPlane
    disarms once its land detector is sure); FAILURE when the mode is refused or the landing
    takes longer than ``confirm_timeout_s``.
    """

    reads = ("/vehicle/landed_state", "/vehicle/armed", "/vehicle/position")
    outcome = Outcome.MODE
    param_docs = {"mode": "the landing mode (QLAND, QRTL; PX4: AUTO.LAND)"}

    def __init__(self, mode: str = "QLAND", name: str = "Land", confirm_timeout_s: float = 120.0) -> None:
        super().__init__(name, confirm_timeout_s)
        self.mode = mode.upper()

    def request(self) -> Request:
        return self.autopilot.land(self.mode)

    def confirmed(self) -> bool:
        return self.get("/vehicle/landed_state") == "ON_GROUND" and not self.get("/vehicle/armed")

    def progress(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        alt = f" at {position.alt_rel_m:.1f} m" if position is not None else ""
        armed = "armed" if self.get("/vehicle/armed") else "disarmed"
        return f"{self.get('/vehicle/landed_state') or 'landed state unknown'}{alt}, {armed}"


class VtolTransition(TimedBehaviour):
    """Transition a VTOL to fixed-wing (``"FW"``) or multicopter (``"MC"``) flight.

    SUCCESS only when ``/vehicle/vtol_state`` (EXTENDED_SYS_STATE) reports the state asked for:
    an ack says nothing about the transition. How it is asked depends on the firmware:

    - ArduPilot accepts MAV_CMD_DO_VTOL_TRANSITION in AUTO only, so there it is used in AUTO;
      elsewhere the mode decides: to FW, a DO_REPOSITION to a point ``ahead_m`` ahead on the current
      heading at the current height (GUIDED, wing-borne: a GoTo with ``method="reposition"`` takes
      over from there); to MC, the mode ``mc_mode`` (QLOITER).
    - PX4 takes MAV_CMD_DO_VTOL_TRANSITION in flight.

    The autopilot port chooses (:meth:`~executive.autopilot.AutopilotPort.transition`).

    FAILURE when the request is refused or unanswered, or after ``timeout_s`` with the last state seen.
    Asked once by an :class:`~executive.autopilot.asking.Asker` (a command's rules,
    :data:`~executive.behaviours.commands.ONE_ASK`, judged at ``timeout_s``); an interruption leaves the
    ask to the commander (not cancelled).
    """

    reads = (
        "/vehicle/vtol_state", "/vehicle/mode", "/vehicle/position", "/vehicle/heading_deg", "/vehicle/statustext",
        blackboard.command_key(Outcome.TRANSITION), blackboard.command_key(Outcome.REPOSITION), blackboard.command_key(Outcome.MODE),
    )  # fmt: skip
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    from_mission = {"timeout_s": "vtol.transition_timeout_s"}
    param_docs = {
        "to": "FW (wing-borne) or MC (multicopter)",
        "mc_mode": "ArduPilot: the mode that makes it a multicopter",
        "ahead_m": "ArduPilot, to FW: how far ahead the reposition is aimed",
    }

    def __init__(self, to: VtolState, timeout_s: float = 30.0, name: str | None = None, mc_mode: str = "QLOITER", ahead_m: float = 300.0) -> None:
        if to not in ("FW", "MC"):
            raise ValueError(f"a VTOL transitions to FW or MC, not {to!r}")
        super().__init__(name or f"Transition to {to}")
        self.to = to
        self.timeout_s = timeout_s
        self.mc_mode = mc_mode.upper()
        self.ahead_m = ahead_m
        self.last_state: str | None = None
        self.how = ""
        self._asker = Asker(self, None, rules=ONE_ASK, voice=_TransitionVoice(self), escalate=False, bounded=True)

    def initialise(self) -> None:
        super().initialise()
        self.last_state = self.get("/vehicle/vtol_state")
        self.how = ""
        self._asker.forget()
        self._asker.rules = replace(ONE_ASK, judge_after_s=self.timeout_s)
        if self.last_state != self.to:
            self._asker.start_command(self.name, self._request, self._there, self.name)

    def _request(self) -> Request | None:
        """The port's ask for the transition; None without a position to aim ahead from (ArduPilot, to FW)."""
        position: GlobalPosition | None = self.get("/vehicle/position")
        heading = position.heading_deg if position is not None and position.heading_deg is not None else self.get("/vehicle/heading_deg") or 0.0
        request = self.autopilot.transition(
            self.to, mode=self.get("/vehicle/mode"), position=position, heading_deg=heading, mc_mode=self.mc_mode, ahead_m=self.ahead_m
        )
        if request is not None:
            self.how = request.how or request.outcome
        return request

    def _there(self) -> bool:
        return self.get("/vehicle/vtol_state") == self.to

    def update(self) -> Status:
        state = self.get("/vehicle/vtol_state")
        if state is not None:
            self.last_state = state
        if state == self.to:
            self.feedback_message = f"{self.to}" + (f" (by {self.how})" if self.how else "")
            return SUCCESS
        asking = self._asker.asking
        if asking is None:  # there when it began, or nothing could be asked: there is no "ahead" without a position
            self.feedback_message = "no position to transition from"
            return FAILURE
        self._asker.follow_up(self.clock.now(), ask=False)
        if asking.judged:  # refused, unanswered or not there in time: the voice said which
            return FAILURE
        self.feedback_message = f"{self.last_state} -> {self.to} (by {self.how})"
        return RUNNING


class _TransitionVoice(Voice):
    """A transition's failed ask, as its feedback: the refusal, or the last state seen when its time is up."""

    def __init__(self, node: VtolTransition) -> None:
        self.node = node

    def failed(self, step: Step, outcome: str, *, first: bool, counted: bool) -> None:
        node = self.node
        refusal = refusal_reason(step.status, step.request, node.get("/vehicle/statustext"))
        if refusal is not None:
            node.feedback_message = f"{node.how} {refusal}; still {node.last_state}"
        else:
            node.feedback_message = f"still {node.last_state} after {node.timeout_s:g} s (by {node.how})"


class GoToLocal(TimedBehaviour):
    """Go to a point of the local frame given in ENU (ROS): MAVLink's frames are NED, so it goes as NED.

    Arrival is judged from the global position taken to the local frame with home as its origin
    (ArduPilot and PX4 put the local origin where home was set at the first fix; a home moved
    later would shift this judgement): SUCCESS within ``acceptance_radius_m`` (3-D), FAILURE after
    ``timeout_s``. ``method``:

    - ``"setpoint"``: SET_POSITION_TARGET_LOCAL_NED (MAV_FRAME_LOCAL_NED), re-sent every
      ``resend_s`` (no ack exists): PX4 (offboard), ArduCopter, ArduRover and ArduSub in GUIDED.
    - ``"reposition"``: ArduPlane takes from SET_POSITION_TARGET_LOCAL_NED only an altitude change
      (MAV_FRAME_LOCAL_OFFSET_NED, in GUIDED; any other frame or mode is ignored), so the NED point
      is taken to latitude and longitude from home (the local origin), at ``up`` metres above home,
      and sent as MAV_CMD_DO_REPOSITION (acked; switches to GUIDED): once, and again only when
      refused or unanswered, at most every ``resend_s`` (:mod:`executive.behaviours.repositioning`,
      the one asking mechanism). Nothing is sent before home is known. A
      QuadPlane with Q_GUIDED_MODE=1 flies a point within WP_LOITER_RAD on its lift motors and
      hovers there; otherwise it flies there as a plane and circles the point.
    """

    reads = ("/vehicle/position", "/vehicle/home", "/vehicle/statustext", blackboard.command_key(Outcome.REPOSITION))
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    from_mission = {"acceptance_radius_m": "limits.acceptance_radius_m", "timeout_s": "limits.leg_timeout_s"}
    param_docs = {"target": "the point, metres {east, north, up} from home (ROS's ENU)"}

    def __init__(
        self,
        target: frames.Enu,
        acceptance_radius_m: float,
        timeout_s: float,
        name: str | None = None,
        resend_s: float = 1.0,
        method: Literal["setpoint", "reposition"] = "setpoint",
    ) -> None:
        if method not in ("setpoint", "reposition"):
            raise ValueError(f"method must be setpoint or reposition, not {method!r}")
        super().__init__(name or f"Go to local E{target.east:g} N{target.north:g} U{target.up:g}")
        self.target = frames.Enu(*target)
        self.ned = frames.enu_to_ned(self.target)
        self.acceptance_radius_m = acceptance_radius_m
        self.timeout_s = timeout_s
        self.resend_s = resend_s
        self.method = method
        self.distance_m: float | None = None
        self._repositioning = Repositioning(self, resend_s)

    def initialise(self) -> None:
        super().initialise()
        self._last_sent = float("-inf")
        self._repositioning.restart()
        self.distance_m = None

    def update(self) -> Status:
        now = self.clock.now()
        position: GlobalPosition | None = self.get("/vehicle/position")
        home: HomePosition | None = self.get("/vehicle/home")
        if self.method == "setpoint" and now - self._last_sent >= self.resend_s:
            self.autopilot.go_to_local(*self.ned)
            self._last_sent = now
        elif self.method == "reposition" and home is not None:
            self._repositioning.follow_up(self._reposition)
        if position is not None and home is not None:
            north, east = frames.global_to_local(home.lat, home.lon, position.lat, position.lon)
            self.distance_m = math.dist((north, east, -position.alt_rel_m), self.ned)
            if self.distance_m <= self.acceptance_radius_m:
                self.feedback_message = f"reached ({self.distance_m:.1f} m)"
                return SUCCESS
        left = f"{self.distance_m:.1f} m" if self.distance_m is not None else "no position or home"
        if self.elapsed > self.timeout_s:
            refusal = self._repositioning.refusal
            why = f" (DO_REPOSITION {refusal})" if refusal else ""
            self.feedback_message = f"timed out after {self.timeout_s:g} s: {left}{why}"
            return FAILURE
        self.feedback_message = left
        return RUNNING

    def _reposition(self) -> Request:
        """Ask for the point: north and east of home (the local origin, known: asked only then), ``up`` metres above it."""
        home: HomePosition = self.get("/vehicle/home")
        lat, lon = frames.local_to_global(home.lat, home.lon, self.ned.north, self.ned.east)
        return self.autopilot.reposition(lat, lon, -self.ned.down)
