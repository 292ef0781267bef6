"""A sampling instrument on a serial line (pyserial): a CTD or a sonde that prints one reading per line.

The line protocol (``sampling.instrument: {type: serial, ...}``): each line, ended by LF (CR LF is
fine), is one reading of one or more sensors, either ``name=value`` pairs or bare values in the
order of ``columns`` (default: ``sampling.sensors``), separated by commas, semicolons or blanks::

    temperature=17.52, conductivity=44.10, ph=8.05
    17.52,44.10,8.05

Empty lines and lines starting with ``#`` (a header) are skipped; a line that does not parse is
counted and logged (the first of each sample), never fatal. The port is read without blocking
every tick; what arrives between samples is dropped, so a sample holds only its own readings,
each stamped with the time it was read. Units come from ``units`` (``{temperature: degC}``), else
the usual unit of a known sensor.
"""

from __future__ import annotations

import logging
import math
import re

import serial
from pydantic import BaseModel, ConfigDict, Field

from executive.instruments.sampler import SENSOR_MODELS, InstrumentError, InstrumentSampler
from executive.mission.model import SamplingOptions
from executive.world.clock import Clock
from executive.world.state import SampleRead

log = logging.getLogger(__name__)

_SEPARATORS = re.compile(r"[,;\s]+")
_MAX_LINE = 4096  # bytes without a line end: not this protocol; dropped


class SerialOptions(BaseModel):
    """``sampling.instrument`` for ``type: serial``."""

    model_config = ConfigDict(strict=True, extra="forbid", frozen=True)
    port: str = Field(min_length=1, description="the serial device (/dev/ttyUSB0) or a pyserial URL (socket://HOST:PORT)")
    baud: int = Field(9600, ge=50, le=4_000_000, description="baud rate")
    columns: list[str] | None = Field(
        None, min_length=1, max_length=32, description="the sensor of each bare value, in order (default: sampling.sensors)"
    )
    units: dict[str, str] = Field(default_factory=dict, description="unit of a sensor (default: the usual one of a known sensor)")


class SerialSampler(InstrumentSampler):
    """Readings from a line-protocol instrument on a serial port."""

    Options = SerialOptions

    def __init__(self, clock: Clock, sampling: SamplingOptions, options: SerialOptions) -> None:
        super().__init__(clock, sampling, options)
        self._options = options
        self._columns = options.columns or sampling.sensors
        try:
            self._port = serial.serial_for_url(options.port, baudrate=options.baud, timeout=0)
        except (serial.SerialException, ValueError) as exc:
            raise InstrumentError(f"serial instrument: cannot open {options.port}: {exc}") from None
        self._buffer = b""
        self.bad_lines = 0
        self._bad_logged = False

    @property
    def instrument(self) -> str:
        return f"serial:{self._options.port}"

    def close(self) -> None:
        self._port.close()

    def _begin(self) -> None:
        self._bad_logged = False

    def _collect(self, now: float) -> list[SampleRead]:
        try:
            data = self._port.read(self._port.in_waiting or 1)
        except (serial.SerialException, OSError) as exc:
            self.fail(f"{self.instrument}: {exc}")
            return []
        if not data:
            return []
        *lines, self._buffer = (self._buffer + data).split(b"\n")
        if len(self._buffer) > _MAX_LINE:
            self._buffer = b""
        reads = []
        for line in lines:
            reads += self._parse(line.decode("ascii", "replace").strip(), now)
        return reads

    def _parse(self, line: str, now: float) -> list[SampleRead]:
        if not line or line.startswith("#"):
            return []
        fields = [f for f in _SEPARATORS.split(line) if f]
        try:
            if all("=" in f for f in fields):
                pairs = [tuple(f.split("=", 1)) for f in fields]
            elif len(fields) == len(self._columns):
                pairs = list(zip(self._columns, fields, strict=True))
            else:
                raise ValueError(f"{len(fields)} values for {len(self._columns)} columns ({', '.join(self._columns)})")
            values = [(name, float(value)) for name, value in pairs]
            if not all(math.isfinite(v) for _, v in values):
                raise ValueError("a value that is not a finite number")
            return [SampleRead(name, value, self._unit(name), now) for name, value in values]
        except ValueError as exc:
            self.bad_lines += 1
            if self.sampling and not self._bad_logged:
                self._bad_logged = True
                log.warning("%s: line %r not understood (%s); such lines are skipped", self.instrument, line[:80], exc)
            return []

    def _unit(self, name: str) -> str:
        model = SENSOR_MODELS.get(name.lower())
        return self._options.units.get(name, model.unit if model else "")
