"""What every executive behaviour shares, ours and plugins': declared blackboard keys and injected services.

Services (the clock, the autopilot port, the mission port: ``mission_state``) are handed to
``tree.setup(**services)``, which passes them to every behaviour's ``setup``; a behaviour takes what it ``needs``.

A plugin's behaviour (a guard, an action, a decorator of its own) subclasses
:class:`ExecutiveBehaviour` (or :class:`~executive.behaviours.guards.Guard`,
:class:`~executive.behaviours.commands.CommandAction`, :class:`TimedBehaviour`) and says, as class
attributes, which documented keys it ``reads``, which new keys of its own it ``declares``
(under ``/plugin/<plugin name>/``) and which of those it ``writes``::

    class CountTicks(ExecutiveBehaviour):
        declares = (blackboard.Key("/plugin/mypkg/ticks", 0, "CountTicks", "ticks seen"),)
        reads = ("/vehicle/armed",)
        writes = ("/plugin/mypkg/ticks",)
        needs = ("clock",)

        def update(self) -> py_trees.common.Status:
            self.set("/plugin/mypkg/ticks", self.get("/plugin/mypkg/ticks") + 1)
            return py_trees.common.Status.SUCCESS

The vehicle's state, the link and the mission are written by the executive's readers and the
mission's lifecycle only: a behaviour never writes them (it asks the autopilot port for a command,
whose ack comes back on the blackboard; it reports a leg done or a sample taken through the mission
port, :class:`~executive.mission.port.MissionPort`, and the lifecycle applies it). When a node is
made its declared keys are documented and its keys checked: an undocumented key is a KeyError.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.common import Access, Status

from executive.world import blackboard
from executive.world.clock import Clock

#: py_trees' statuses as names of this module, for code run every tick: ``Status.RUNNING`` reads an attribute of an Enum
#: class, which Python 3.11 looks up through EnumType's ``__getattr__`` hook, its slow path (about 900 instructions, a
#: global about 50). They are the same members (``RUNNING is Status.RUNNING``).
RUNNING, SUCCESS, FAILURE, INVALID = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID
#: py_trees' INFO log level (an IntEnum member, as slow to read from its class).
_INFO = py_trees.logging.Level.INFO


class ExecutiveBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour that reads documented blackboard keys and may need injected services."""

    #: Blackboard keys this behaviour reads.
    reads: tuple[str, ...] = ()
    #: New keys (a plugin's own, under ``/plugin/<plugin name>/``), documented when a node of the class is made.
    declares: tuple[blackboard.Key, ...] = ()
    #: Keys this behaviour writes: only keys under ``/plugin/`` (it may read them too).
    writes: tuple[str, ...] = ()
    #: Names of the services ``setup`` must receive (``clock``, ``autopilot``, ``mission_state``).
    needs: tuple[str, ...] = ()

    @classmethod
    def declared_keys(cls) -> tuple[blackboard.Key, ...]:
        """The keys this class and its bases declare (read from their ``declares``, nothing documented by reading them)."""
        return tuple(key for klass in reversed(cls.__mro__) for key in vars(klass).get("declares", ()))

    def __init__(self, name: str) -> None:
        super().__init__(name)
        for key in self.declared_keys():
            blackboard.declare(key)
        self.bb = blackboard.Client(name=name)  # attach_blackboard_client(), with the fast get
        self.blackboards.append(self.bb)
        for key in self.reads:
            if key not in blackboard.KEYS:
                raise KeyError(f"{type(self).__name__} reads undocumented blackboard key {key!r}")
            self.bb.register_key(key=key, access=Access.READ)
        for key in self.writes:
            if not key.startswith(blackboard.PLUGIN_NAMESPACE):
                raise KeyError(f"{type(self).__name__} writes {key!r}: behaviours write only keys under {blackboard.PLUGIN_NAMESPACE} they declare")
            if key not in blackboard.KEYS:
                raise KeyError(f"{type(self).__name__} writes undeclared blackboard key {key!r} (declare it in `declares`)")
            self.bb.register_key(key=key, access=Access.WRITE)
        if type(self).get is ExecutiveBehaviour.get:  # a subclass's own get is kept
            self.get = self.bb.get  # type: ignore[method-assign]  # what get does, without a call through it: a tick reads dozens

    # py_trees' Behaviour.tick and stop (py_trees/behaviour.py, 2.6), the same steps in the same order, without what they
    # cost each tick with py_trees' debug log off: a formatted debug line each (an enum formatted in every stop) and
    # ``list(Status)`` built to check the status. A leaf guard is ticked and stopped every tick.
    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Tick once: ``initialise`` when not RUNNING, ``update``, ``stop`` when it ends (py_trees' own with its debug log on)."""
        if py_trees.logging.level < _INFO:  # as py_trees.logging.Logger.debug decides
            yield from super().tick()
            return
        if self.status != RUNNING:
            self.initialise()
        new_status = self.update()
        if new_status not in _STATUSES:
            self.logger.error(f"A behaviour returned an invalid status, setting to INVALID [{new_status}][{self.name}]")
            new_status = INVALID
        if new_status != RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def stop(self, new_status: Status) -> None:
        """``terminate``, then the new status (py_trees' own with its debug log on)."""
        if py_trees.logging.level < _INFO:  # as py_trees.logging.Logger.debug decides
            super().stop(new_status)
            return
        self.terminate(new_status)
        self.status = new_status

    @property
    def iterator(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' ``iterator``: a tick of this node, not started, made when it is read.

        py_trees' ``__init__`` and ``stop`` set a new one each time and nothing reads it; a generator made and dropped costs
        about 2,000 instructions, and a leaf guard is stopped every tick. What a read gives is what py_trees keeps.
        """
        return self.tick()

    @iterator.setter
    def iterator(self, _: Iterator[py_trees.behaviour.Behaviour]) -> None:
        """What py_trees sets is dropped: a read makes its own."""

    def setup(self, **services: Any) -> None:
        """Take the services this behaviour ``needs`` (the clock, the autopilot port, the mission state) from the runtime."""
        missing = [n for n in self.needs if services.get(n) is None]
        if missing:
            raise RuntimeError(f"{self.name}: setup() needs {', '.join(missing)}")
        for name in self.needs:
            setattr(self, name, services[name])

    def get(self, key: str) -> Any:
        """The value of a blackboard key this behaviour reads (or writes)."""
        return self.bb.get(key)

    def set(self, key: str, value: Any) -> None:
        """Write a key this behaviour ``writes``."""
        self.bb.set(key, value)


#: The statuses a behaviour's ``update`` may return (py_trees checks against ``list(Status)``: the same test by ==).
_STATUSES = tuple(Status)


class TimedBehaviour(ExecutiveBehaviour):
    """A behaviour that measures time since it started, on the injected clock."""

    needs = ("clock",)
    clock: Clock

    def initialise(self) -> None:
        self.started = self.clock.now()

    @property
    def elapsed(self) -> float:
        return self.clock.now() - self.started
