"""Guard conditions: SUCCESS when the condition holds, FAILURE (with the reason) when not.

Guards read the blackboard and nothing else; they never return RUNNING.
"""

from __future__ import annotations

from py_trees.common import Status

from executive.behaviours.base import ExecutiveBehaviour
from executive.state import EkfStatus


class Guard(ExecutiveBehaviour):
    """A condition on the blackboard; subclasses implement :meth:`check`."""

    #: When this guard fails a person has the vehicle: the executive keeps its hands off.
    pilot_in_control = False

    def check(self) -> str | None:
        """``None`` when the condition holds, else why it does not."""
        raise NotImplementedError

    def update(self) -> Status:
        reason = self.check()
        self.feedback_message = reason or "ok"
        return Status.FAILURE if reason else Status.SUCCESS


class LinkAlive(Guard):
    """The autopilot's heartbeat is fresh."""

    reads = ("/link/up",)

    def __init__(self, name: str = "Link alive?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        return None if self.get("/link/up") else "no heartbeat from the autopilot"


class EkfOk(Guard):
    """The EKF has a horizontal position (not constant-position mode) and its variances are sane."""

    reads = ("/vehicle/ekf",)

    def __init__(self, name: str = "EKF ok?", variance_threshold: float = 0.8) -> None:
        super().__init__(name)
        self.variance_threshold = variance_threshold

    def check(self) -> str | None:
        ekf: EkfStatus | None = self.get("/vehicle/ekf")
        if ekf is None:
            return "no EKF status yet"
        if not ekf.position_ok():
            return f"EKF has no position estimate (flags 0x{int(ekf.flags):x})"
        if not ekf.variances_ok(self.variance_threshold):
            return f"EKF variances over {self.variance_threshold}"
        return None


class Armed(Guard):
    """The vehicle is armed (disarmed mid-mission means the RC took over)."""

    reads = ("/vehicle/armed",)
    pilot_in_control = True

    def __init__(self, name: str = "Armed?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        return None if self.get("/vehicle/armed") else "vehicle is disarmed"


class ModeIs(Guard):
    """The autopilot is in a given flight mode."""

    reads = ("/vehicle/mode",)

    def __init__(self, mode: str, name: str | None = None) -> None:
        super().__init__(name or f"Mode is {mode}?")
        self.mode = mode.upper()

    def check(self) -> str | None:
        mode = self.get("/vehicle/mode")
        return None if mode == self.mode else f"mode is {mode}, not {self.mode}"


class RcNotTakingOver(Guard):
    """The RC take-over switch is not high (a missing transmitter is not a take-over)."""

    reads = ("/rc/channels",)
    pilot_in_control = True

    def __init__(self, channel: int, above_us: int, name: str = "RC not taking over?") -> None:
        super().__init__(name)
        self.channel = channel
        self.above_us = above_us

    def check(self) -> str | None:
        channels: tuple[int, ...] = self.get("/rc/channels")
        value = channels[self.channel - 1] if len(channels) >= self.channel else 0
        if value > self.above_us:
            return f"RC channel {self.channel} high ({value} µs): manual take-over"
        return None
