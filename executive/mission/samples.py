"""The samples taken in a run: kept once per leg, published as ``/mission/samples`` (its one writer).

A partial sample (an instrument without a reading) is kept but does not count as the leg's sample.
The lifecycle (:class:`~executive.mission.lifecycle.MissionState`) decides when a sample may be
kept and who hears of it; this holds them.
"""

from __future__ import annotations

from collections.abc import Iterable

from executive.mission.model import Mission
from executive.world import blackboard
from executive.world.state import SampleRecord


class SampleLog:
    """The samples of this run, oldest first."""

    def __init__(self) -> None:
        self._bb = blackboard.writer("sample log", ["/mission/samples"])
        self.taken: tuple[SampleRecord, ...] = ()

    def sampled(self, leg_index: int) -> bool:
        """A complete sample of this leg is already kept: do not take it again (a partial one does not count)."""
        return any(s.leg_index == leg_index and s.complete for s in self.taken)

    def clear(self) -> None:
        self.taken = ()

    def keep(self, sample: SampleRecord) -> None:
        self.taken = (*self.taken, sample)

    def restore(self, samples: Iterable[SampleRecord]) -> None:
        """Put back the samples a previous process kept, each leg's once."""
        for sample in samples:
            if not self.sampled(sample.leg_index):
                self.keep(sample)

    def work_left(self, mission: Mission | None) -> str | None:
        """What of ``mission``'s sampling is not done (a sample point not sampled, or sampled partially), if any: then it is not COMPLETED."""
        if mission is None:
            return None
        unsampled = [i for i, wp in enumerate(mission.waypoints) if wp.sample and not self.sampled(i)]
        partial = [i for i in unsampled if any(s.leg_index == i for s in self.taken)]
        missing = [i for i in unsampled if i not in partial]
        said = []
        if missing:
            said.append(f"no sample was recorded at leg {', '.join(str(i + 1) for i in missing)}")
        for i in partial:
            lacked = sorted({sensor for s in self.taken if s.leg_index == i for sensor in s.missing})
            said.append(f"the sample of leg {i + 1} is partial (no reading of {', '.join(lacked)})")
        return "; ".join(said) or None

    def publish(self) -> None:
        self._bb.set("/mission/samples", self.taken)
