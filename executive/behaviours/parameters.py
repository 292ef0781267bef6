"""Pre-flight checks of the autopilot's parameters: a mission that cannot work with them is refused before anything moves."""

from __future__ import annotations

from collections.abc import Collection

from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour


class ParameterIs(TimedBehaviour):
    """SUCCESS once the autopilot reports parameter ``name`` with one of ``allowed``; FAILURE naming it, its value, the value needed and ``why``.

    The value is asked for (PARAM_REQUEST_READ) every ``ask_every_s`` until a PARAM_VALUE brings it
    (``/vehicle/params``); none within ``timeout_s`` is a FAILURE too. Nothing else is sent.
    ``autopilot``: the firmware the parameter belongs to ("ardupilot"); on another one it passes
    with a note (its own rules apply there).
    """

    reads = ("/vehicle/params",)
    needs = ("clock", "autopilot")
    param_docs = {
        "name": "the parameter's name (Q_GUIDED_MODE): the node's name is label",
        "allowed": "the values that pass",
        "why": "what needs it, said in the failure",
        "autopilot": "the firmware the parameter belongs to (on another one it passes)",
        "ask_every_s": "how often the value is asked for until it comes",
        "label": "the node's name (name is the parameter's)",
    }
    #: Parameters kept under other attribute names (read back by executive.tree.formats.recompose); label is the node's name.
    param_attributes = {"name": "parameter", "autopilot": "firmware", "label": "name"}
    autopilot: AutopilotPort

    def __init__(
        self,
        name: str,
        allowed: Collection[float],
        why: str,
        autopilot: str = "ardupilot",
        timeout_s: float = 10.0,
        ask_every_s: float = 1.0,
        label: str | None = None,
    ) -> None:
        super().__init__(label or f"{name} in {{{', '.join(f'{v:g}' for v in allowed)}}}?")
        self.parameter, self.allowed, self.why, self.firmware = name, tuple(allowed), why, autopilot
        self.timeout_s, self.ask_every_s = timeout_s, ask_every_s

    def initialise(self) -> None:
        super().initialise()
        self._asked_at = float("-inf")

    def update(self) -> Status:
        if self.autopilot.capabilities.autopilot != self.firmware:
            self.feedback_message = f"{self.parameter}: not an {self.firmware} parameter ({self.autopilot.capabilities.autopilot})"
            return SUCCESS
        value = (self.get("/vehicle/params") or {}).get(self.parameter)
        if value is not None:
            if value in self.allowed:
                self.feedback_message = f"{self.parameter} {value:g}"
                return SUCCESS
            needed = " or ".join(f"{v:g}" for v in self.allowed)
            self.feedback_message = f"{self.parameter} is {value:g}: set it to {needed}: {self.why}"
            return FAILURE
        if self.elapsed > self.timeout_s:
            self.feedback_message = f"{self.parameter} not reported by the autopilot within {self.timeout_s:g} s (it needs {self.why})"
            return FAILURE
        now = self.clock.now()
        if now - self._asked_at >= self.ask_every_s:
            self.autopilot.read_parameter(self.parameter)
            self._asked_at = now
        self.feedback_message = f"asking the autopilot for {self.parameter}"
        return RUNNING
