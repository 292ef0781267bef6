"""Pre-flight: the autopilot's own RC mode switch is on none of the mission's switch channels.

ArduRover changes mode by itself when its mode channel (MODE_CH, channel 8 by default) moves: a
mission switch on that channel (the UGV's arm switch D) would switch the vehicle to MANUAL with no
command from the executive. The runtime asks for the parameter (PARAM_REQUEST_READ) when it finds
the autopilot and until it answers (:class:`~executive.autopilot_link.parameters.ParameterWatch`); the
answer is on ``/vehicle/params``. The check never waits and never passes on a value it has not
read: pre-flight waits for the answer first (:class:`~executive.behaviours.readiness.ReadingsIn`,
bounded), so an EKF ready at the first tick (a ``--resume``) does not get ahead of it.
"""

from __future__ import annotations

from collections.abc import Mapping

from executive.autopilot.port import AutopilotPort
from executive.behaviours.guards import Guard


class ModeSwitchClear(Guard):
    """The autopilot's mode-switch channel is none of ``switches`` (channel -> what it is); FAILURE names the parameter.

    Passes, with a note, when the firmware has no such channel (ArduSub, PX4); fails while the
    autopilot has not told it (pre-flight waits for it before this check).
    """

    reads = ("/vehicle/params",)
    unknown_or_stale = (
        "MODE_CH (ArduRover) or FLTMODE_CH (ArduPlane) not read yet: fails (pre-flight waits for it, 10 s, then refuses); no age: "
        "ArduPilot sends PARAM_VALUE to every link whenever a parameter is set (AP_Param::save), and the reader keeps the latest"
    )
    needs = ("autopilot",)
    from_mission = {"switches": "rc.switch_channels"}
    param_docs = {"switches": "the mission's RC switch channels"}
    autopilot: AutopilotPort

    def __init__(self, switches: Mapping[int, str], name: str = "Mode switch clear?") -> None:
        super().__init__(name)
        self.switches = dict(switches)

    def awaits(self) -> str | None:
        param = self.autopilot.capabilities.mode_switch_param
        if param is None or not self.switches or param in (self.get("/vehicle/params") or {}):
            return None
        return f"{param} (PARAM_VALUE)"

    def ask(self) -> None:
        """Ask the autopilot for the parameter (PARAM_REQUEST_READ; its answer lands on /vehicle/params)."""
        param = self.autopilot.capabilities.mode_switch_param
        if param is not None:
            self.autopilot.read_parameter(param)

    def check(self) -> str | None:
        param = self.autopilot.capabilities.mode_switch_param
        if param is None:
            self.note = "the autopilot has no RC mode-switch channel"
            return None
        value = (self.get("/vehicle/params") or {}).get(param)
        if value is None:
            return f"{param} not read yet (the autopilot has not answered PARAM_REQUEST_READ): the mission's switches cannot be checked"
        channel = round(value)
        if channel in self.switches:
            return (
                f"RC channel {channel} ({self.switches[channel]}) is the autopilot's mode switch ({param} = {channel}): moving it would change "
                f"the mode by itself; set {param} to a channel the mission does not use (0: none)"
            )
        self.note = f"{param} = {channel}: no mission switch on it"
        return None
