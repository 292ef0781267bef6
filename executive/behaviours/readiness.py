"""Pre-flight: wait (bounded) for the readings the mission's guards cannot judge without, then refuse naming what never came.

A guard never passes on a reading it has not had (:mod:`executive.behaviours.guards`): a check
ticked before the answer arrives fails. So pre-flight first waits for those readings, for as long
as a few of their reports take, and only then checks them: an EKF ready at the first tick (a
``--resume`` on a vehicle that never stopped) does not get ahead of the autopilot's answers.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from py_trees.common import Status

from executive.autopilot import AutopilotPort
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.guards import BatteryAbove, Guard
from executive.behaviours.mode_switch import ModeSwitchClear


class ReadingsIn(TimedBehaviour):
    """RUNNING until the readings the mission's guards need are in (SUCCESS); FAILURE after ``timeout_s`` naming each that never came.

    It waits for what :class:`~executive.behaviours.mode_switch.ModeSwitchClear` needs (the autopilot's
    mode-switch parameter, MODE_CH or FLTMODE_CH, when the mission has RC switches and the firmware
    such a channel; asked for every ``ask_every_s``) and what
    :class:`~executive.behaviours.guards.BatteryAbove` needs when a floor is set (a SYS_STATUS with
    the remaining % for ``floor_pct``, the voltage for ``floor_v``). 10 s by default: ten requests
    of the parameter a second apart (as the runtime's own ParameterWatch asks), ten SYS_STATUS at
    the 1 Hz they are asked at. Nothing else is sent.
    """

    reads = ("/vehicle/params", "/vehicle/battery")
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    from_mission = {"switches": "rc.switch_channels", "floor_pct": "limits.battery_min_pct", "floor_v": "limits.battery_min_v"}
    param_docs = {
        "switches": "the mission's RC switch channels (the autopilot's mode-switch channel is read for them)",
        "floor_pct": "a battery floor in %: the remaining % must be reported (null: not waited for)",
        "floor_v": "a battery floor in volts: the voltage must be reported (null: not waited for)",
        "timeout_s": "FAILURE, naming what never came, when it has not all come by then",
        "ask_every_s": "how often a missing parameter is asked for",
    }

    def __init__(
        self,
        switches: Mapping[int, str],
        floor_pct: float | None = None,
        floor_v: float | None = None,
        timeout_s: float = 10.0,
        ask_every_s: float = 1.0,
        name: str = "Readings in?",
    ) -> None:
        super().__init__(name)
        self.switches = dict(switches)
        self.floor_pct, self.floor_v = floor_pct, floor_v
        self.timeout_s, self.ask_every_s = timeout_s, ask_every_s
        battery = [BatteryAbove(floor_pct, floor_v)] if floor_pct is not None or floor_v is not None else []
        self._guards: list[Guard] = [ModeSwitchClear(self.switches), *battery]

    def setup(self, **services: Any) -> None:
        super().setup(**services)
        for guard in self._guards:
            guard.setup(**services)

    def initialise(self) -> None:
        super().initialise()
        self._asked_at = float("-inf")

    def missing(self) -> list[str]:
        """What has not come yet, as a person reads it."""
        return [what for guard in self._guards if (what := guard.awaits()) is not None]

    def update(self) -> Status:
        missing = self.missing()
        if not missing:
            self.feedback_message = "every reading the guards need is in"
            return SUCCESS
        if self.elapsed > self.timeout_s:
            self.feedback_message = f"never came within {self.timeout_s:g} s: {'; '.join(missing)}"
            return FAILURE
        now = self.clock.now()
        if now - self._asked_at >= self.ask_every_s:
            self._asked_at = now
            for guard in self._guards:
                if isinstance(guard, ModeSwitchClear) and guard.awaits() is not None:
                    guard.ask()
        self.feedback_message = f"waiting ({self.elapsed:.0f}/{self.timeout_s:g} s) for {'; '.join(missing)}"
        return RUNNING
