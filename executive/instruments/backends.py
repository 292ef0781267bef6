"""Which instrument takes a mission's samples: the back ends (built in, and plugins of the ``executive.instruments`` entry-point group).

A back end is an :class:`~executive.instruments.sampler.InstrumentSampler` subclass, named by the
mission's ``sampling.instrument.type`` and found through :mod:`executive.registry`: ``simulated``
(made-up readings, the built-in simulator only) and ``serial`` (a line-protocol instrument,
:mod:`executive.instruments.serial`) are built in; a package adds one with an entry point, as
python-can's interfaces are added::

    [project.entry-points."executive.instruments"]
    mysonde = "mypackage.sonde:SondeSampler"

A mission that samples names its instrument; without one, the simulated instrument is used with
the built-in simulator and the mission is refused against a real vehicle: samples are real or
absent, never invented.
"""

from __future__ import annotations

from importlib.metadata import EntryPoint

from pydantic import BaseModel, ValidationError

from executive import registry
from executive.instruments.sampler import InstrumentError, InstrumentSampler
from executive.mission.errors import Path
from executive.mission.model import InstrumentConfig, Mission, SamplingOptions
from executive.world.clock import Clock

GROUP = registry.INSTRUMENTS


def known() -> list[str]:
    """Every instrument type: the built-in ones and those plugins add."""
    return registry.names(GROUP)


def plugin_backend(point: EntryPoint) -> type[InstrumentSampler]:
    """The class an ``executive.instruments`` entry point names; PluginError if it cannot be loaded or is no instrument."""
    return registry.load_class(point, InstrumentSampler, "an instrument (subclass executive.instruments.sampler.InstrumentSampler)")


def backend(kind: str) -> type[InstrumentSampler]:
    """The sampler class of an instrument type; InstrumentError when there is none."""
    if kind in registry.BUILT_IN[GROUP]:
        found: type[InstrumentSampler] = registry.load_built_in(GROUP, kind)
        return found
    points = registry.named(GROUP)
    if kind not in points:
        raise InstrumentError(f"unknown instrument type {kind!r} (known: {', '.join(known())})")
    try:
        return plugin_backend(points[kind])
    except registry.PluginError as exc:
        raise InstrumentError(str(exc)) from exc


def options_of(config: InstrumentConfig) -> BaseModel:
    """The instrument's options, validated by its back end (ValidationError, InstrumentError)."""
    return backend(config.type).Options.model_validate(config.model_extra or {})


def option_errors(config: InstrumentConfig, at: Path) -> list[tuple[Path, str]]:
    """What is wrong with ``sampling.instrument`` (at path ``at``): its type, each of its options."""
    try:
        options = backend(config.type).Options
        options.model_validate(config.model_extra or {})
    except InstrumentError as exc:
        return [((*at, "type"), str(exc))]
    except ValidationError as exc:
        errors: list[tuple[Path, str]] = []
        for e in exc.errors(include_url=False):
            if e["type"] == "missing":
                errors.append((at, f"{e['loc'][-1]}: required field is missing (type {config.type})"))
            elif e["type"] == "extra_forbidden":
                errors.append(((*at, *e["loc"]), f"unknown field (allowed for type {config.type}: {', '.join(['type', *options.model_fields])})"))
            else:
                shown = "" if isinstance(e["input"], dict | list) else f"{e['input']!r}: "
                errors.append(((*at, *e["loc"]), shown + e["msg"].removeprefix("Value error, ")))
        return errors
    return []


def samples(mission: Mission) -> bool:
    """The mission takes samples (a sample point, or a sampling section)."""
    return mission.sampling is not None or any(wp.sample for wp in mission.waypoints)


def refusal(mission: Mission, *, simulator: bool) -> str | None:
    """Why this mission's samples could not be real on this vehicle (``simulator``: the built-in one), or None."""
    if not samples(mission):
        return None
    config = mission.sampling.instrument if mission.sampling is not None else None
    if config is None:
        if simulator:
            return None
        return (
            "sampling.instrument: the mission takes samples and names no instrument; against a real vehicle the samples must come "
            "from one (e.g. {type: serial, port: /dev/ttyUSB0}): the simulated instrument runs only with the built-in simulator"
        )
    try:
        simulated = backend(config.type).simulated
    except InstrumentError as exc:
        return f"sampling.instrument.type: {exc}"
    if simulated and not simulator:
        return f"sampling.instrument: {config.type!r} makes readings up: only with the built-in simulator, not against a real vehicle"
    return None


def open_sampler(mission: Mission, clock: Clock, *, simulator: bool) -> InstrumentSampler | None:
    """The sampler of a mission that takes samples (None for one that does not); InstrumentError when it cannot be had here."""
    why = refusal(mission, simulator=simulator)
    if why is not None:
        raise InstrumentError(why)
    if not samples(mission):
        return None
    sampling = mission.sampling or SamplingOptions()
    config = sampling.instrument or InstrumentConfig(type="simulated")
    try:
        options = options_of(config)
    except ValidationError as exc:
        raise InstrumentError(f"sampling.instrument: {exc}") from None
    return backend(config.type)(clock, sampling, options)
