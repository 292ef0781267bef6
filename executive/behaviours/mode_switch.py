"""Pre-flight: the autopilot's own RC mode switch is on none of the mission's switch channels.

ArduRover changes mode by itself when its mode channel (MODE_CH, channel 8 by default) moves: a
mission switch on that channel (the UGV's arm switch D) would switch the vehicle to MANUAL with no
command from the executive. The runtime asks for the parameter (PARAM_REQUEST_READ) when it finds
the autopilot and until it answers (:class:`~executive.io.mavlink.parameters.ParameterWatch`); the
answer is on ``/vehicle/params``. The check never waits: trees put it right before arming, after
the EKF wait, by when the answer is in.
"""

from __future__ import annotations

from collections.abc import Mapping

from executive.autopilot.port import AutopilotPort
from executive.behaviours.guards import Guard


class ModeSwitchClear(Guard):
    """The autopilot's mode-switch channel is none of ``switches`` (channel -> what it is); FAILURE names the parameter.

    Passes, with a note, when the autopilot has no such channel or has not told it yet.
    """

    reads = ("/vehicle/params",)
    needs = ("autopilot",)
    from_mission = {"switches": "rc.switch_channels"}
    param_docs = {"switches": "the mission's RC switch channels"}
    autopilot: AutopilotPort

    def __init__(self, switches: Mapping[int, str], name: str = "Mode switch clear?") -> None:
        super().__init__(name)
        self.switches = dict(switches)

    def check(self) -> str | None:
        param = self.autopilot.capabilities.mode_switch_param
        if param is None:
            self.note = "the autopilot has no RC mode-switch channel"
            return None
        value = (self.get("/vehicle/params") or {}).get(param)
        if value is None:
            self.note = f"{param} not known (the autopilot has not told it)"
            return None
        channel = round(value)
        if channel in self.switches:
            return (
                f"RC channel {channel} ({self.switches[channel]}) is the autopilot's mode switch ({param} = {channel}): moving it would change "
                f"the mode by itself; set {param} to a channel the mission does not use (0: none)"
            )
        self.note = f"{param} = {channel}: no mission switch on it"
        return None
