"""Taking a sample at a sample point: the sampler does the work, the action watches it and records the result."""

from __future__ import annotations

import math

from py_trees.common import Status

from executive.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.guards import Guard
from executive.instruments.sampler import Sampler
from executive.mission.model import Waypoint
from executive.mission.port import MissionPort
from executive.world.state import GlobalPosition, SampleRecord, SamplerState, SamplerStatus


class Sample(TimedBehaviour):
    """Take the current leg's sample: start the sampler, SUCCESS when it is DONE (the sample recorded).

    Needs ``clock``, ``mission_state`` and ``sampler`` from ``tree.setup``. The sample is recorded
    through the mission port (``mission_state.sample_taken``) with the reads, the start and end times, the last
    position seen while sampling (NaN if none was) and the sensors named that gave no reading. A
    leg already sampled in this run (the action re-entered after a guard recovered, a resume, a
    restart that restored the samples) is SUCCESS at once, without sampling again. A partial sample
    (a named sensor gave no reading; ``sampling.require: all``) is recorded as partial and is a
    FAILURE: its sample point is not done. FAILURE too when the sampler fails, after ``timeout_s``
    (None: the sampler's own duration bounds it), or with no active leg. Interrupted (an RC
    take-over, a cancel, a pause: the guards above stop it), it cancels the sampler; nothing is recorded.
    """

    reads = ("/sampler/status", "/vehicle/position", "/mission/leg_count")
    needs = ("clock", "mission_state", "sampler")
    mission_state: MissionPort
    sampler: Sampler
    param_docs = {"timeout_s": "FAILURE when no sample by then (null: the sampler's own duration bounds it)"}

    def __init__(self, name: str = "Sample", timeout_s: float | None = None) -> None:
        super().__init__(name)
        self.timeout_s = timeout_s
        self.leg_index: int | None = None
        self._ticket: int | None = None
        self._finished = True
        self._skip: Status | None = None
        self._position: GlobalPosition | None = None

    def initialise(self) -> None:
        super().initialise()
        state = self.mission_state
        self.leg_index, self._ticket, self._finished, self._skip, self._position = state.leg_index, None, True, None, None
        if state.target is None:
            self._skip, self.feedback_message = FAILURE, "no active leg"
        elif state.sampled(state.leg_index):
            self._skip, self.feedback_message = SUCCESS, f"leg {state.leg_index + 1}: already sampled"
        else:
            self._ticket = self.sampler.start(state.leg_index)
            self._finished = False

    def update(self) -> Status:
        if self._skip is not None:
            return self._skip
        assert self.leg_index is not None
        leg = f"leg {self.leg_index + 1}/{self.get('/mission/leg_count')}"
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is not None:
            self._position = position
        status: SamplerStatus | None = self.get("/sampler/status")
        mine = status is not None and status.ticket == self._ticket
        if mine and status is not None and status.state in (SamplerState.DONE, SamplerState.PARTIAL):
            self._finished = True
            partial = status.state is SamplerState.PARTIAL
            lat, lon = (self._position.lat, self._position.lon) if self._position is not None else (math.nan, math.nan)
            record = SampleRecord(self.leg_index, lat, lon, status.reads, self.started, status.time, status.instrument, status.missing, partial)
            self.mission_state.sample_taken(record)
            if partial:
                self.feedback_message = f"{leg}: partial sample, {len(status.reads)} reads: {status.reason}"
                return FAILURE
            without = f"; none of {', '.join(status.missing)} (sampling.require: any)" if status.missing else ""
            self.feedback_message = f"{leg}: sampled, {len(status.reads)} reads ({status.instrument}){without}"
            return SUCCESS
        if mine and status is not None and status.state is SamplerState.FAILED:
            self._finished = True
            self.feedback_message = f"{leg}: sampler failed: {status.reason}"
            return FAILURE
        if self.timeout_s is not None and self.elapsed > self.timeout_s:
            self.sampler.cancel()
            self._finished = True
            self.feedback_message = f"{leg}: no sample after {self.timeout_s:g} s"
            return FAILURE
        reads = len(status.reads) if mine and status is not None else 0
        self.feedback_message = f"{leg}: sampling ({self.elapsed:.0f} s, {reads} reads)"
        return RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status == INVALID and not self._finished:
            self.sampler.cancel()  # interrupted: the sample in progress is abandoned, not recorded
            self._finished = True
            self.feedback_message = "interrupted: sample cancelled"


class NothingToSample(Guard):
    """The current leg needs no sample: its waypoint is not a sample point (``sample: true``), or its sample is already recorded.

    FAILURE ("sample due") at a sample point not sampled yet in this run: put the sampling after it
    in a selector. No active leg passes with a note.
    """

    reads = ("/mission/target", "/mission/leg_index", "/mission/samples")
    unknown_or_stale = "reads the mission's own state (its leg, its samples), never a reading of the vehicle's: nothing to be unknown or old"

    def __init__(self, name: str = "Nothing to sample here?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        target: Waypoint | None = self.get("/mission/target")
        if target is None:
            self.note = "no active leg"
            return None
        leg: int = self.get("/mission/leg_index")
        samples: tuple[SampleRecord, ...] = self.get("/mission/samples")
        if not target.sample:
            self.note = f"leg {leg + 1} is not a sample point"
            return None
        if any(s.leg_index == leg and s.complete for s in samples):
            self.note = f"leg {leg + 1} already sampled"
            return None
        return f"leg {leg + 1}: sample due"
