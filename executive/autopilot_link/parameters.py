"""The autopilot's parameters the pre-flight checks and the look-ahead need, asked for until it answers (answers land on ``/vehicle/params``)."""

from __future__ import annotations

import logging
import math

from executive.autopilot.port import AutopilotPort
from executive.autopilot.rover_motion import FIRMWARE_DEFAULTS
from executive.world import blackboard
from executive.world.clock import Clock

log = logging.getLogger(__name__)


def wanted_parameters(port: AutopilotPort) -> tuple[str, ...]:
    """The parameters the executive reads from this autopilot: its mode-switch channel (ArduRover MODE_CH...), those of
    its driving (``capabilities.motion_params``), its battery's (``capabilities.battery_params``: the energy rule) and its
    take-off's end (``capabilities.takeoff_params``: whose mode change follows it)."""
    capabilities = port.capabilities
    switch = (capabilities.mode_switch_param,) if capabilities.mode_switch_param else ()
    return switch + tuple(capabilities.motion_params) + tuple(capabilities.battery_params) + tuple(capabilities.takeoff_params)


class ParameterWatch:
    """Asks for :func:`wanted_parameters` while the link is up and they have not all answered.

    A writer service: every ``retry_s`` one PARAM_REQUEST_READ for each parameter not answered yet,
    ``tries`` rounds in all. A parameter that never answers is said in the log once: the pre-flight's
    mode-switch check then passes, noting it; the look-ahead takes the firmware's default for it.
    """

    def __init__(self, port: AutopilotPort, clock: Clock, *, retry_s: float = 1.0, tries: int = 10) -> None:
        self._port = port
        self._clock = clock
        self.retry_s = retry_s
        self.tries = tries
        self._asked = 0
        self._asked_at = -math.inf
        self._bb = blackboard.reader("parameter watch", ["/vehicle/params", "/link/up"])
        # (the parameters answered, the back end's capabilities, what they leave missing): asked every tick, and
        # both are replaced, not changed, when they change (a new dict per PARAM_VALUE, a new back end when found)
        self._missing: tuple[object, object, list[str]] = (None, None, [])

    def missing(self) -> list[str]:
        """The wanted parameters the autopilot has not answered (yet)."""
        have = self._bb.get("/vehicle/params") or {}
        capabilities = self._port.capabilities
        known_have, known_capabilities, missing = self._missing
        if have is not known_have or capabilities is not known_capabilities:
            missing = [name for name in wanted_parameters(self._port) if name not in have]
            self._missing = (have, capabilities, missing)
        return list(missing)

    def service(self) -> None:
        if self._asked > self.tries or not self._bb.get("/link/up"):
            return
        missing = self.missing()
        if not missing:
            return
        now = self._clock.now()
        if now - self._asked_at < self.retry_s:
            return
        if self._asked == self.tries:
            self._asked += 1
            defaults = ", ".join(f"{name} {FIRMWARE_DEFAULTS[name]:g}" for name in missing if name in FIRMWARE_DEFAULTS)
            log.warning(
                "the autopilot never answered %s (asked %d times): %s", ", ".join(missing), self.tries,
                f"the look-ahead takes the firmware's defaults ({defaults})" if defaults else "taken as not set",
            )  # fmt: skip
            return
        self._asked_at, self._asked = now, self._asked + 1
        for name in missing:
            self._port.read_parameter(name)
