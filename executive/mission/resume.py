"""Where an unfinished run stopped, as the journal keeps it: what ``run --resume`` continues from."""

from __future__ import annotations

from dataclasses import dataclass

from executive.mission.model import Mission
from executive.mission.route import Route
from executive.world.state import SampleRecord


@dataclass(frozen=True)
class ResumePoint:
    """Where an unfinished run stopped: the leg to continue from, the samples it had taken, and its route if it was edited."""

    run: int
    leg_index: int
    samples: tuple[SampleRecord, ...]
    route: Route | None = None  # None: the mission file's own
    mission: Mission | None = None  # the mission that replaced the one asked for (hot reload); None: that one

    def started_text(self, leg_count: int) -> str:
        """What the resumed run's start says (log, journal, report): ``resumed at waypoint 4 of 8 (run 3 was unfinished)``."""
        return f"resumed at waypoint {self.leg_index + 1} of {leg_count} (run {self.run} was unfinished)"
