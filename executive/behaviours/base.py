"""What every executive behaviour shares: read-only blackboard access and injected services.

Services (the clock, the autopilot port, the mission state) are handed to ``tree.setup(**services)``,
which passes them to every behaviour's ``setup``; a behaviour takes what it needs.
"""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Access

from executive import blackboard
from executive.clock import Clock


class ExecutiveBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour that reads documented blackboard keys and may need injected services."""

    #: Blackboard keys this behaviour reads.
    reads: tuple[str, ...] = ()
    #: Names of the services ``setup`` must receive (``clock``, ``autopilot``, ``mission_state``).
    needs: tuple[str, ...] = ()

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.bb = blackboard.Client(name=name)  # attach_blackboard_client(), with the fast get
        self.blackboards.append(self.bb)
        for key in self.reads:
            if key not in blackboard.KEYS:
                raise KeyError(f"{type(self).__name__} reads undocumented blackboard key {key!r}")
            self.bb.register_key(key=key, access=Access.READ)

    def setup(self, **services: Any) -> None:
        missing = [n for n in self.needs if services.get(n) is None]
        if missing:
            raise RuntimeError(f"{self.name}: setup() needs {', '.join(missing)}")
        for name in self.needs:
            setattr(self, name, services[name])

    def get(self, key: str) -> Any:
        """The value of a blackboard key this behaviour reads."""
        return self.bb.get(key)


class TimedBehaviour(ExecutiveBehaviour):
    """A behaviour that measures time since it started, on the injected clock."""

    needs = ("clock",)
    clock: Clock

    def initialise(self) -> None:
        self.started = self.clock.now()

    @property
    def elapsed(self) -> float:
        return self.clock.now() - self.started
