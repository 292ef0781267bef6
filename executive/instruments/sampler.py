"""The sample-taking instrument: started by the Sample action, serviced by the runtime, reported on ``/sampler/status``.

A sampler never blocks. :meth:`Sampler.start` asks for a sample and returns a ticket;
:meth:`Sampler.service` (called by the runtime once per tick, after the tree) takes the reads that
are due and writes a :class:`~executive.world.state.SamplerStatus` carrying that ticket; the action
watches for its ticket reaching DONE or FAILED.
"""

from __future__ import annotations

import logging
import math
import random
import zlib
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol

from pydantic import BaseModel, ConfigDict

from executive.mission.model import SamplingOptions
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import GlobalPosition, SampleRead, SamplerState, SamplerStatus

log = logging.getLogger(__name__)

_EPSILON_S = 1e-6  # clock times closer than this are the same instant


class InstrumentError(Exception):
    """An instrument that cannot be used (unknown, not allowed here, its port cannot be opened); ``str()`` says why."""


class Sampler(Protocol):
    """What the Sample action and the runtime need from a sampling instrument."""

    #: Which instrument takes the samples ("simulated", "serial:/dev/ttyUSB0"): every sample recorded says it.
    instrument: str

    def start(self, leg_index: int) -> int:
        """Start sampling for a leg (superseding any sample in progress); returns the ticket its status will carry."""
        ...

    def cancel(self) -> None:
        """Stop the sample in progress: it ends FAILED ("cancelled"). Nothing happens when idle."""
        ...

    def service(self) -> None:
        """Called by the runtime every tick: take what is due and publish ``/sampler/status``."""
        ...

    def close(self) -> None:
        """Release the instrument (its port); the sampler is not used after."""
        ...


class NoOptions(BaseModel):
    """An instrument that takes no options besides ``type``."""

    model_config = ConfigDict(strict=True, extra="forbid", frozen=True)


class InstrumentSampler(ABC):
    """A sampler's bookkeeping, whatever the instrument: tickets, ``/sampler/status``, the sample's duration, cancel.

    A back end (``sampling.instrument.type``) subclasses it: :meth:`_collect` returns the readings
    the instrument gave since the last call (called every tick, sampling or not: readings outside
    a sample are dropped), :attr:`instrument` names it, :meth:`close` releases it. ``Options``
    validates the mission's ``sampling.instrument`` fields besides ``type``; ``simulated`` back ends
    make readings up and run only with the built-in simulator. A sample ends after
    ``sampling.duration_s``: DONE with a reading of every sensor ``sampling.sensors`` names (with
    ``sampling.require: any``, of any one; the others are listed as missing), PARTIAL with readings
    but a named sensor missing, FAILED with none. Readings of a sensor the mission does not name
    are dropped, and logged once per sensor: a sample holds what the mission asked for.
    """

    Options: ClassVar[type[BaseModel]] = NoOptions
    simulated: ClassVar[bool] = False

    def __init__(self, clock: Clock, sampling: SamplingOptions, options: BaseModel | None = None) -> None:
        self._clock = clock
        self.options = sampling
        self.instrument_options = options if options is not None else self.Options()
        self._bb = blackboard.writer("sampler", ["/sampler/status"])
        self._tickets = 0
        self._status: SamplerStatus | None = None
        self._leg_index: int | None = None
        self._started = 0.0
        self._reads: list[SampleRead] = []
        self._named = frozenset(sampling.sensors)
        self._unnamed_logged: set[str] = set()

    @property
    @abstractmethod
    def instrument(self) -> str:
        """Which instrument this is, as samples record it."""

    @abstractmethod
    def _collect(self, now: float) -> list[SampleRead]:
        """The readings the instrument gave since the last call (never blocks)."""

    def _begin(self) -> None:  # noqa: B027 - a hook: most instruments need nothing
        """A sample starts (after :attr:`_started` is set)."""

    def close(self) -> None:  # noqa: B027 - a hook: most instruments hold nothing
        """Release the instrument."""

    @property
    def status(self) -> SamplerStatus | None:
        """The status last published."""
        return self._status

    @property
    def sampling(self) -> bool:
        return self._status is not None and self._status.state is SamplerState.SAMPLING

    def start(self, leg_index: int) -> int:
        self._tickets += 1
        self._leg_index = leg_index
        self._started = self._clock.now()
        self._reads = []
        self._begin()
        log.info("sampler: sampling for leg %d with %s (ticket %d)", leg_index + 1, self.instrument, self._tickets)
        self._publish(SamplerState.SAMPLING, "")
        return self._tickets

    def cancel(self) -> None:
        self.fail("cancelled")

    def fail(self, reason: str) -> None:
        """End the sample in progress FAILED (what a cancel or an instrument fault does)."""
        if self.sampling:
            log.warning("sampler: leg %d: %s", (self._leg_index or 0) + 1, reason)
            self._publish(SamplerState.FAILED, reason)

    def service(self) -> None:
        now = self._clock.now()
        fresh = self._named_only(self._collect(now))
        if not self.sampling:
            return
        self._reads += fresh
        if now + _EPSILON_S >= self._started + self.options.duration_s:
            self._end()
        elif fresh:
            self._publish(SamplerState.SAMPLING, "")

    def _named_only(self, reads: list[SampleRead]) -> list[SampleRead]:
        """The readings of sensors the mission names; another sensor's are dropped, said once per sensor."""
        if all(r.sensor in self._named for r in reads):
            return reads
        for sensor in sorted({r.sensor for r in reads} - self._named - self._unnamed_logged):
            self._unnamed_logged.add(sensor)
            log.warning(
                "sampler: %s gives readings of %r, which sampling.sensors does not name (%s): dropped",
                self.instrument, sensor, ", ".join(self.options.sensors),
            )  # fmt: skip
        return [r for r in reads if r.sensor in self._named]

    def _end(self) -> None:
        """The sample's time is up: DONE, PARTIAL (a named sensor gave no reading) or FAILED (none did)."""
        if not self._reads:
            self.fail(f"no reading from {self.instrument} in {self.options.duration_s:g} s")
            return
        read = {r.sensor for r in self._reads}
        missing = tuple(s for s in self.options.sensors if s not in read)
        if missing and self.options.require == "all":
            reason = f"no reading of {', '.join(missing)} from {self.instrument} in {self.options.duration_s:g} s (sampling.require: all)"
            log.warning("sampler: leg %d: partial sample: %s", (self._leg_index or 0) + 1, reason)
            self._publish(SamplerState.PARTIAL, reason, missing)
            return
        self._publish(SamplerState.DONE, "", missing)

    def _publish(self, state: SamplerState, reason: str, missing: tuple[str, ...] = ()) -> None:
        self._status = SamplerStatus(self._tickets, state, tuple(self._reads), reason, self._clock.now(), self.instrument, missing)
        self._bb.set("/sampler/status", self._status)


class UnavailableSampler(InstrumentSampler):
    """Stands for an instrument that could not be had (its port gone): every sample fails at once, with the reason."""

    def __init__(self, clock: Clock, sampling: SamplingOptions, reason: str) -> None:
        super().__init__(clock, sampling)
        self.reason = reason

    @property
    def instrument(self) -> str:
        return "no instrument"

    def _collect(self, now: float) -> list[SampleRead]:
        return []

    def start(self, leg_index: int) -> int:
        ticket = super().start(leg_index)
        self.fail(self.reason)
        return ticket


@dataclass(frozen=True)
class SensorModel:
    """How a simulated sensor reads: a base value, a spatial variation of ``amplitude``, gaussian noise."""

    unit: str
    base: float
    amplitude: float
    noise: float
    minimum: float | None = None  # no reading below this (turbidity cannot be negative)
    decimals: int = 3


#: Plausible coastal-water values for the sensors a sampling sonde carries.
SENSOR_MODELS: dict[str, SensorModel] = {
    "temperature": SensorModel("degC", 17.5, 1.5, 0.02, decimals=2),
    "conductivity": SensorModel("mS/cm", 44.0, 3.0, 0.05, minimum=0.0, decimals=2),
    "salinity": SensorModel("PSU", 31.0, 2.0, 0.03, minimum=0.0, decimals=2),
    "ph": SensorModel("pH", 8.05, 0.12, 0.005, minimum=0.0),
    "dissolved_oxygen": SensorModel("mg/L", 7.8, 0.6, 0.02, minimum=0.0, decimals=2),
    "turbidity": SensorModel("NTU", 3.0, 2.0, 0.1, minimum=0.0, decimals=2),
    "chlorophyll": SensorModel("ug/L", 2.5, 1.5, 0.05, minimum=0.0, decimals=2),
}
_UNKNOWN_SENSOR = SensorModel("", 0.0, 1.0, 0.01)
_WAVELENGTH_M = 400.0  # how far apart the simulated water's patches are
_M_PER_DEG = 111_320.0


class SimulatedSampler(InstrumentSampler):
    """A simulated sonde: every ``1/rate_hz`` s one read per sensor, for ``duration_s``, then DONE.

    Values vary smoothly with the vehicle's position (read-only from ``/vehicle/position``, or from
    ``position``) plus seeded noise, so runs are repeatable and two sample points differ. Made-up
    readings: only with the built-in simulator.
    """

    simulated = True

    def __init__(
        self,
        clock: Clock,
        options: SamplingOptions,
        instrument_options: BaseModel | None = None,
        *,
        position: Callable[[], GlobalPosition | None] | None = None,
        seed: int = 0,
    ) -> None:
        super().__init__(clock, options, instrument_options)
        self._models = {name: SENSOR_MODELS.get(name.lower(), _UNKNOWN_SENSOR) for name in options.sensors}
        unknown = [name for name in options.sensors if name.lower() not in SENSOR_MODELS]
        if unknown:
            log.warning("simulated sampler: no model for %s; they read noise around 0", ", ".join(unknown))
        self._reader = blackboard.reader("sampler", ["/vehicle/position"])
        self._position = position if position is not None else self._vehicle_position
        self._random = random.Random(seed)
        self._taken = 0  # read rounds taken for the sample in progress

    @property
    def instrument(self) -> str:
        return "simulated"

    @property
    def rounds(self) -> int:
        """Read rounds (one read per sensor) in a sample: ``duration_s * rate_hz``, at least one."""
        return max(1, math.floor(self.options.duration_s * self.options.rate_hz + 1e-9))

    def _begin(self) -> None:
        self._taken = 0

    def _collect(self, now: float) -> list[SampleRead]:
        if not self.sampling:
            return []
        reads: list[SampleRead] = []
        while self._taken < self.rounds and self._due(self._taken + 1) <= now + _EPSILON_S:
            self._taken += 1
            reads += self._read_round(self._due(self._taken))
        return reads

    # -- internals ---------------------------------------------------------------------------
    def _vehicle_position(self) -> GlobalPosition | None:
        position: GlobalPosition | None = self._reader.get("/vehicle/position")
        return position

    def _due(self, round_number: int) -> float:
        """When read round ``round_number`` (1-based) is due: every ``1/rate_hz`` s, never after the end."""
        return self._started + min(round_number / self.options.rate_hz, self.options.duration_s)

    def _read_round(self, t: float) -> list[SampleRead]:
        here = self._position()
        reads = []
        for name, model in self._models.items():
            value = model.base + model.amplitude * self._field(name, here) + self._random.gauss(0.0, model.noise)
            if model.minimum is not None:
                value = max(model.minimum, value)
            reads.append(SampleRead(name, round(value, model.decimals), model.unit, t))
        return reads

    @staticmethod
    def _field(name: str, here: GlobalPosition | None) -> float:
        """A smooth pattern in [-1, 1] over the water, different for each sensor."""
        if here is None:
            return 0.0
        phase = (zlib.crc32(name.encode()) % 628) / 100.0
        north = here.lat * _M_PER_DEG
        east = here.lon * _M_PER_DEG * math.cos(math.radians(here.lat))
        k = 2.0 * math.pi / _WAVELENGTH_M
        return math.sin(k * north + phase) * math.cos(k * east - phase)
