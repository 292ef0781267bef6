"""A whole runtime ticked by hand over an in-memory link, an obedient autopilot at the other end."""

from __future__ import annotations

from typing import Any

from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.runtime.assembly import build_runtime
from executive.sim.options import simulated_home
from executive.testing.harness import START_S
from executive.testing.links import FakeLink
from executive.testing.scripted import ObedientAutopilot
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink


class RuntimeOnLink:
    """The runtime of ``mission`` (its readers, tree, operator, plugs) on a :class:`FakeLink`, ticked by hand on a manual clock.

    ``r = RuntimeOnLink(mission, root=my_tree, safe_timeout_s=1.0)``: keyword arguments go to
    :func:`~executive.runtime.assembly.build_runtime` (``plugs=``...). :attr:`autopilot`, an
    :class:`ObedientAutopilot` of the mission's vehicle in ``mode`` (``armed``) where its simulated
    vehicle would start (the mission's home, else its first waypoint), answers each command and
    heartbeat as it is sent, its position with each heartbeat; with ``beat`` its heartbeat also
    arrives before every tick; ``commanded=False``: a run that has commanded nothing yet (its make-safe
    has nothing to undo). Other facts (the EKF) are the test's to write. :meth:`tick` advances the clock
    and ticks; :meth:`modes_sent` and :meth:`texts` are what the executive sent since the last call.
    """

    def __init__(
        self,
        mission: Mission,
        *,
        clock: ManualClock | None = None,
        link: FakeLink | None = None,
        mode: str = "GUIDED",
        armed: bool = True,
        beat: bool = False,
        commanded: bool = True,
        **runtime_options: Any,
    ) -> None:
        self.clock = clock if clock is not None else ManualClock(START_S)
        self.link = link if link is not None else FakeLink()
        self.runtime = build_runtime(mission, self.link, self.clock, **runtime_options)
        if commanded:  # the vehicle stands as this run left it mid-mission (in GUIDED, armed): its make-safe acts
            self.runtime.link.watch.commanded = "the run before the test"
        start = simulated_home(mission)
        self.autopilot = ObedientAutopilot(self.link, mission.vehicle, mode=mode, armed=armed, start=(start[0], start[1]))
        self.beat = beat

    def tick(self, n: int = 1, dt: float = 0.1) -> None:
        """``n`` ticks of the runtime, the clock ``dt`` seconds on before each (the autopilot's heartbeat first, with ``beat``)."""
        for _ in range(n):
            self.clock.advance(dt)
            if self.beat:
                self.autopilot.beat()
            self.runtime.tick()

    def modes_sent(self) -> list[str]:
        """The modes the executive asked for since the last call (taken off the link with the other COMMAND_LONGs)."""
        modes = self.runtime.link.commander.modes
        return [modes.decode(int(m.param2)) for m in self.link.take("COMMAND_LONG") if m.command == mavlink.MAV_CMD_DO_SET_MODE]

    def texts(self) -> list[str]:
        """The STATUSTEXTs the executive sent since the last call."""
        return [m.text for m in self.link.take("STATUSTEXT")]

    @property
    def status(self) -> MissionStatus:
        """The mission's status now."""
        return self.runtime.mission_state.status

    def close(self) -> None:
        """Release what the runtime holds (control socket, instruments)."""
        self.runtime.close()
