"""Actions: ask the commander for a command, then watch the blackboard for its effect.

An action never waits inside a tick. It sends in ``initialise`` (the commander transmits after
the tick) and each ``update`` looks at what came back: the ack in ``/command/...`` and, for the
effect itself, the vehicle state (ArduPilot can ack a mode change that the heartbeat never shows).
"""

from __future__ import annotations

from py_trees.common import Status

from executive import blackboard, geo
from executive.behaviours.base import TimedBehaviour
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.dialect import mavlink
from executive.state import CommandState, CommandStatus, GlobalPosition


def _result_name(result: int | None) -> str:
    entry = mavlink.enums["MAV_RESULT"].get(result) if result is not None else None
    return entry.name.removeprefix("MAV_RESULT_") if entry else "no ack"


class CommandAction(TimedBehaviour):
    """Request a command once; SUCCESS when the vehicle state confirms it, FAILURE when refused or unconfirmed."""

    needs = ("clock", "commander")
    commander: Commander
    command_name = ""  # MAV_CMD name without prefix

    def __init__(self, name: str, confirm_timeout_s: float = 5.0) -> None:
        self.reads = (*self.reads, blackboard.command_key(self.command_name), "/vehicle/statustext")
        super().__init__(name)
        self.confirm_timeout_s = confirm_timeout_s
        self._ticket: int | None = None

    def request(self) -> int:
        """Ask the commander for the command; returns its ticket."""
        raise NotImplementedError

    def confirmed(self) -> bool:
        """The vehicle state shows the command took effect."""
        raise NotImplementedError

    def initialise(self) -> None:
        super().initialise()
        self._ticket = None if self.confirmed() else self.request()

    def update(self) -> Status:
        if self.confirmed():
            self.feedback_message = "confirmed"
            return Status.SUCCESS
        status: CommandStatus | None = self.get(blackboard.command_key(self.command_name))
        if status is not None and status.ticket == self._ticket and status.state in (CommandState.REJECTED, CommandState.TIMED_OUT):
            text = self.get("/vehicle/statustext")
            self.feedback_message = f"refused: {_result_name(status.result)}" + (f" ({text[1]})" if text else "")
            if status.state is CommandState.TIMED_OUT:
                self.feedback_message = f"no ack after {status.attempts} attempts"
            return Status.FAILURE
        if self.elapsed > self.confirm_timeout_s:
            self.feedback_message = f"not confirmed after {self.confirm_timeout_s:g} s"
            return Status.FAILURE
        self.feedback_message = "waiting for the autopilot"
        return Status.RUNNING


class SetMode(CommandAction):
    """Put the autopilot in a flight mode (by name); confirmed by the heartbeat."""

    reads = ("/vehicle/mode",)
    command_name = "DO_SET_MODE"

    def __init__(self, mode: str, name: str | None = None, confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name or f"Set {mode.upper()}", confirm_timeout_s)
        self.mode = mode.upper()

    def request(self) -> int:
        return self.commander.set_mode(self.mode)

    def confirmed(self) -> bool:
        return self.get("/vehicle/mode") == self.commander.modes.canonical(self.mode)


class Arm(CommandAction):
    """Arm the vehicle; confirmed by the heartbeat. A refusal (pre-arm checks) is a FAILURE to retry later."""

    reads = ("/vehicle/armed",)
    command_name = "COMPONENT_ARM_DISARM"

    def __init__(self, name: str = "Arm", confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name, confirm_timeout_s)

    def request(self) -> int:
        return self.commander.arm()

    def confirmed(self) -> bool:
        return bool(self.get("/vehicle/armed"))


class Disarm(Arm):
    """Disarm the vehicle; confirmed by the heartbeat."""

    def __init__(self, name: str = "Disarm", confirm_timeout_s: float = 5.0) -> None:
        super().__init__(name, confirm_timeout_s)

    def request(self) -> int:
        return self.commander.disarm()

    def confirmed(self) -> bool:
        return not self.get("/vehicle/armed")


class GoTo(TimedBehaviour):
    """Drive to the current leg's waypoint in GUIDED.

    RUNNING with feedback (distance, bearing) on the way; SUCCESS inside the acceptance radius;
    FAILURE after the leg timeout. The setpoint is re-sent every ``resend_s``: ArduPilot gives no
    ack for it and drops it silently outside GUIDED.
    """

    reads = ("/mission/target", "/mission/leg_index", "/mission/leg_count", "/vehicle/position")
    needs = ("clock", "commander")
    commander: Commander

    def __init__(self, acceptance_radius_m: float, leg_timeout_s: float, name: str = "Go to waypoint", resend_s: float = 1.0) -> None:
        super().__init__(name)
        self.acceptance_radius_m = acceptance_radius_m
        self.leg_timeout_s = leg_timeout_s
        self.resend_s = resend_s
        self.distance_m: float | None = None
        self.bearing_deg: float | None = None

    def initialise(self) -> None:
        super().initialise()
        self.target = self.get("/mission/target")
        self.distance_m = self.bearing_deg = None
        self._last_sent = float("-inf")

    def update(self) -> Status:
        if self.target is None:
            self.feedback_message = "no active leg"
            return Status.FAILURE
        now = self.clock.now()
        if now - self._last_sent >= self.resend_s:
            self.commander.goto(self.target.lat, self.target.lon, self.target.alt_m)
            self._last_sent = now
        leg = f"leg {self.get('/mission/leg_index') + 1}/{self.get('/mission/leg_count')}"
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is not None:
            self.distance_m, self.bearing_deg = geo.distance_bearing(position.lat, position.lon, self.target.lat, self.target.lon)
            if self.distance_m <= self.acceptance_radius_m:
                self.feedback_message = f"{leg}: reached ({self.distance_m:.1f} m)"
                return Status.SUCCESS
        if self.elapsed > self.leg_timeout_s:
            short = f", {self.distance_m:.1f} m short" if self.distance_m is not None else ""
            self.feedback_message = f"{leg}: timed out after {self.leg_timeout_s:g} s{short}"
            return Status.FAILURE
        if self.distance_m is None:
            self.feedback_message = f"{leg}: no position"
        else:
            self.feedback_message = f"{leg}: {self.distance_m:.1f} m at {self.bearing_deg:03.0f}°"
        return Status.RUNNING
