"""What the runtime runs around each tick of the tree: services, and the few shapes they take.

A *reader* is drained before the tree ticks (a link, a sensor, an estimator over the blackboard,
an operator's input); a *writer* is serviced after it (streams, reports, commands to send). A
*paced* service has a rate of its own above the tick's and is also serviced between ticks (the
AgileX base's 50 Hz motion commands). A *run observer* hears of each mission run (the journal, the
snapshot recorder, the live view). A new link is a new service handed to the runtime, never a branch in it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import executive

if TYPE_CHECKING:
    import py_trees

    from executive.mission.model import Mission


@runtime_checkable
class Service(Protocol):
    """One thing the runtime does each tick; it never blocks or sleeps."""

    def service(self) -> object: ...


class PacedService(Protocol):
    """A service with its own rate, serviced between ticks until ``next_due``; stopped at once when the vehicle is made safe."""

    @property
    def next_due(self) -> float: ...

    def pace(self) -> object:
        """Do what is due now (never blocks)."""

    def stop(self) -> None:
        """Stop what it drives, now (the runtime is making the vehicle safe)."""


class RunObserver(Protocol):
    """Hears of each mission run: its start (with its tree), each tick of the tree, its end."""

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None: ...

    def ticked(self, tick: int, now: float) -> None: ...

    def end(self, status: str, reason: str) -> None: ...


@dataclass(frozen=True)
class FunctionService:
    """A service made of a function: ``FunctionService("mavlink reader", reader.drain)``."""

    name: str
    run: Callable[[], object]

    def service(self) -> object:
        return self.run()


def service_name(service: object) -> str:
    """A service's name for reports: a FunctionService's own, else its class's."""
    return service.name if isinstance(service, FunctionService) else type(service).__name__


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Step is FunctionService
    return executive.moved_attribute(__name__, name)
