"""The autopilot's parameters the pre-flight checks need, asked for until it answers (answers land on ``/vehicle/params``)."""

from __future__ import annotations

import math

from executive import blackboard
from executive.autopilot.port import AutopilotPort
from executive.clock import Clock


class ParameterWatch:
    """Asks for the autopilot's mode-switch channel (ArduRover MODE_CH...) while the link is up and it has not answered.

    A writer service: at most one PARAM_REQUEST_READ every ``retry_s``, ``tries`` in all (an
    autopilot that has no such parameter never answers: the pre-flight check then passes, noting it).
    """

    def __init__(self, port: AutopilotPort, clock: Clock, *, retry_s: float = 1.0, tries: int = 10) -> None:
        self._port = port
        self._clock = clock
        self.retry_s = retry_s
        self.tries = tries
        self._asked = 0
        self._asked_at = -math.inf
        self._bb = blackboard.reader("parameter watch", ["/vehicle/params", "/link/up"])

    def service(self) -> None:
        param = self._port.capabilities.mode_switch_param
        if param is None or self._asked >= self.tries or not self._bb.get("/link/up"):
            return
        if param in (self._bb.get("/vehicle/params") or {}):
            return
        now = self._clock.now()
        if now - self._asked_at >= self.retry_s:
            self._asked_at, self._asked = now, self._asked + 1
            self._port.read_parameter(param)
