"""The mission's one event stream: what happened to it, told to its subscribers in an order each declares.

The mission's state (:mod:`executive.mission.lifecycle`) says what happened as an event: a
:class:`Transition`, a :class:`SampleTaken`, a :class:`RouteChanged`, a :class:`Replaced`, an
:class:`Announcement`. Who hears it first is not who subscribed first: each subscriber declares
its :class:`Stage`, and every event goes to the stages in their order (the runtime's tree exists
before the autopilot is told, the autopilot before the ground station and the recordings hear of it).
A stage has one subscriber of a kind, except :attr:`Stage.RECORDING` and :attr:`Stage.OBSERVER`:
they only take note, so their order among themselves changes nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum
from typing import TYPE_CHECKING, Any, NamedTuple

if TYPE_CHECKING:
    from executive.mission.model import Mission
    from executive.mission.route import Route
    from executive.mission.status import MissionStatus
    from executive.world.state import SampleRecord


class Transition(NamedTuple):
    """The lifecycle went from ``before`` to ``after`` (an upload, a start, a pause, an end...), ``reason`` says why."""

    before: MissionStatus
    after: MissionStatus
    reason: str


class SampleTaken(NamedTuple):
    """A sample was recorded (a journal keeps it)."""

    sample: SampleRecord


class RouteChanged(NamedTuple):
    """The route changed (an operator's edit, a recorded waypoint): the new route and why."""

    route: Route
    reason: str


class Replaced(NamedTuple):
    """The paused mission was replaced (hot reload): the new mission and why."""

    mission: Mission
    reason: str


class Announcement(NamedTuple):
    """What a person must hear now (a failsafe's reaction, refused, another asked): a STATUSTEXT; ``warning`` or a notice."""

    text: str
    warning: bool


Event = Transition | SampleTaken | RouteChanged | Replaced | Announcement


class Stage(IntEnum):
    """Where a subscriber hears an event, first to last."""

    #: The runtime: the mission's tree (and the journal's run) exist before anyone else hears of a start or a replacement.
    TREE = 0
    #: The route keeper: the edited or replacing route taken to the autopilot.
    ROUTE_KEEPER = 1
    #: A replacing mission's zones and rally points taken to the autopilot.
    ZONES = 2
    #: The autopilot link: hands off while a person holds the vehicle.
    AUTOPILOT_LINK = 3
    #: The ground stations: the mission reported, announcements as STATUSTEXT.
    GROUND_STATION = 4
    #: The recordings (the journal, the snapshot files): any number, in any order.
    RECORDING = 5
    #: The watch on a person's intervention.
    INTERVENTION = 6
    #: Anyone else that only takes note (a test, a plugin's display): after all, any number, in any order.
    OBSERVER = 7


#: Stages whose subscribers only take note: any number of them.
_MANY = frozenset({Stage.RECORDING, Stage.OBSERVER})


class MissionEvents:
    """The stream: :meth:`subscribe` a handler to a kind of event at a stage; :meth:`tell` an event to its subscribers by stage."""

    def __init__(self) -> None:
        self._subscribers: dict[type, list[tuple[Stage, Callable[..., Any]]]] = {}

    def subscribe(self, kind: type[Event], handler: Callable[..., Any], stage: Stage = Stage.OBSERVER) -> None:
        """``handler(*event)`` hears each event of ``kind`` at ``stage``; ValueError if another holds that stage for that kind."""
        heard = self._subscribers.setdefault(kind, [])
        if stage not in _MANY and any(s is stage for s, _ in heard):
            raise ValueError(f"{kind.__name__} at stage {stage.name} already has a subscriber")
        heard.append((stage, handler))
        heard.sort(key=lambda entry: entry[0])  # stable: observers stay among themselves as they came

    def tell(self, event: Event) -> None:
        for _, handler in self._subscribers.get(type(event), ()):
            handler(*event)
