"""Test helpers of our own suite (the rest is the public kit, :mod:`executive.testing`): a runtime over a real socket."""

from __future__ import annotations

from typing import Any

from executive.assembly import build_runtime
from executive.clock import ScaledClock
from executive.io.mavlink.dialect import mavlink
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.model import Mission
from executive.pacing import SpeedGovernor
from executive.runtime import Outcome, Runtime
from executive.testing import AUTOPILOT


def run_over(url: str, mission: Mission, clock: ScaledClock, **options: Any) -> tuple[Runtime, Outcome]:
    """A runtime on a real link to ``url`` (a simulator), connected and run to the mission's end; the link closed after.

    ``options`` go to :func:`~executive.assembly.build_runtime` (progress, plugs...).
    """
    link = PymavlinkLink(url)
    try:
        runtime = build_runtime(mission, link, clock, **options)
        runtime.pacer.listeners.append(SpeedGovernor(clock))  # as `executive run` does: a busy machine slows the world, not the verdict
        assert runtime.connect(10.0 * clock.speedup)
        return runtime, runtime.run()
    finally:
        link.close()


class ObedientAutopilot:
    """Answers on a fake link: a heartbeat for each of ours (or :meth:`beat`), every mode change accepted at once."""

    def __init__(self, link: Any) -> None:
        self.link, self.mode = link, 15  # GUIDED
        self._send = link.send
        link.send = self.receive

    def receive(self, msg: Any) -> None:
        self._send(msg)
        if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            self.mode = int(msg.param2)
            self.link.incoming.append(AUTOPILOT.command_ack(msg.command, 0, 0, 0, 1, 191))
        if msg.get_type() == "HEARTBEAT":
            self.beat()

    def beat(self) -> None:
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        self.link.incoming.append(AUTOPILOT.heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, 3, base, self.mode, 4))
