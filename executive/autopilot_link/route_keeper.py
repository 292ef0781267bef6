"""The route keeper: after every edit of the route, the autopilot is given it - uploaded, read back, retried.

Whatever the tree, an edit (from ``executive ctl route``, the RC switches, the library API) reaches
the mission state's ``set_route``; the keeper, one of its route listeners, makes the autopilot's
mission the new route: one NAV_WAYPOINT per waypoint (a NAV_LOITER_UNLIM per sample point) after a home item 0 (the same items the
``ugv_rc_route`` tree's KeepRouteOnAutopilot uploads), read back item by item before it counts. A
failed upload is tried again ``retry_s`` later, up to ``attempts`` uploads per edit; a newer edit
replaces the one being uploaded. When the edit moved the mission's home (SET_HOME) the autopilot's
home is set too (MAV_CMD_DO_SET_HOME, acked; the commander retries it). The outcome is
``/link/route_upload`` (a :class:`RouteUpload`) and a log line.

With ``drive: auto`` the autopilot is given only the edited route's horizon (its waypoints through
the current leg's and ``limits.auto_horizon_legs`` beyond it): the tree's HorizonOnAutopilot
extends it as legs are reached (executive.behaviours.auto_legs).

A mission replaced while paused (hot reload, ``ctl upload``) is taken to the autopilot the same
way, at once: the operator sees it uploaded and read back (``ctl route show``) before resuming,
and a mission upload does not move a vehicle held in its safe mode (ArduPilot's mission is stopped
outside AUTO: AP_Mission::stop, "subsequent calls to update() will have no effect until the mission
is started or resumed", libraries/AP_Mission/AP_Mission.cpp). Its home is not an edit (as for a
mission uploaded READY): the autopilot keeps its own.

The ugv_rc_route tree also uploads on its own (the route it starts with, and whenever the autopilot
is found holding something else). There is one MissionTransfer, and neither supersedes a transfer
the other started: the keeper starts its upload from the route listener, within the tick of the
edit and before the tree's behaviour looks, which then finds the transfer busy, waits, and finds
the autopilot holding the route; the keeper likewise waits out a transfer it did not start and
uploads nothing when the autopilot already holds the route (``/vehicle/mission_items``). So an
edit is uploaded once.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from enum import StrEnum

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import (
    MissionTransfer,
    MissionTransferStatus,
    TransferState,
    horizon_not_on_autopilot,
    horizon_span,
    route_items,
    route_not_on_autopilot,
)
from executive.mission.events import Replaced, RouteChanged, Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.mission.route import Route
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import mavlink
from executive.world.state import CommandState, CommandStatus, HomePosition, Outcome

log = logging.getLogger(__name__)

_SET_HOME_KEY = blackboard.command_key(Outcome.HOME)
_PENDING = (CommandState.QUEUED, CommandState.SENT, CommandState.IN_PROGRESS, CommandState.RETRYING)


class RouteUploadState(StrEnum):
    """Where the latest edit stands on the autopilot."""

    UPLOADING = "UPLOADING"  # sending, reading back, or waiting to (for a retry, for another transfer, for the home's ack)
    DONE = "DONE"  # the autopilot holds the route, read back (and took the new home)
    FAILED = "FAILED"  # given up: the reason is in ``detail``


@dataclass(frozen=True, slots=True)
class RouteUpload:
    """The latest edit of the route and what became of it on the autopilot (``/link/route_upload``)."""

    state: RouteUploadState
    edit: str  # the edit, as the mission state was told it
    waypoints: int
    attempt: int  # uploads started for this edit (0: none was needed)
    attempts: int  # the most that will be
    detail: str  # what is going on, how it ended, or why it failed
    time: float


class RouteKeeper:
    """Uploads the mission state's route to the autopilot after each edit, with read-back and retries; call :meth:`service` every tick."""

    def __init__(
        self, mission_state: MissionState, transfer: MissionTransfer, commander: Commander, clock: Clock, *, attempts: int = 3, retry_s: float = 2.0
    ) -> None:
        self._transfer = transfer
        self._commander = commander
        self._clock = clock
        self.attempts = attempts
        self.retry_s = retry_s
        self._bb = blackboard.writer("route keeper", ["/link/route_upload"])
        self._vehicle = blackboard.reader("route keeper", ["/vehicle/mission_items", "/vehicle/home", _SET_HOME_KEY])
        self._mission_state = mission_state
        self._home = mission_state.legs.route.home  # the home the autopilot was last given or found with
        self._route: Route | None = None  # the edit being taken to the autopilot; None when there is none
        self._edit = ""
        self._attempt = 0
        self._retry_at = 0.0
        self._ticket: int | None = None
        self._superseded: int | None = None
        self._last_failure = ""
        self._home_ticket: int | None = None
        mission_state.events.subscribe(RouteChanged, self._on_route, Stage.ROUTE_KEEPER)
        mission_state.events.subscribe(Transition, self._on_transition, Stage.ROUTE_KEEPER)
        mission_state.events.subscribe(Replaced, self._on_replace, Stage.ROUTE_KEEPER)

    @property
    def status(self) -> RouteUpload | None:
        """The latest edit's fate (also ``/link/route_upload``)."""
        return self._bb.get("/link/route_upload")

    def service(self) -> None:
        """Follow the upload and the home; start an upload (or its retry) when due."""
        if self._route is None:
            return
        now = self._clock.now()
        route, n = self._route, len(self._route)
        if self._ticket is not None and not self._follow(self._transfer.status, now):
            return
        home_problem = self._home_problem()
        horizon = self._horizon()
        wanted = route.waypoints if horizon is None else route.waypoints[: horizon_span(n, *horizon)[1]]
        if self._ticket is None and self._held(route, horizon) is None:
            held = f"{n} waypoints, {'read back' if self._attempt else 'already held'}"
            if horizon is not None:
                held = f"the horizon of leg {horizon[0] + 1} (drive: auto), {'read back' if self._attempt else 'already held'}"
            if home_problem == "":
                self._finish(RouteUploadState.DONE, f"{held}{self._home_words()}", now)
            elif home_problem is not None:
                self._finish(RouteUploadState.FAILED, f"{held}, but the home was not set: {home_problem}", now)
            else:
                self._publish(RouteUploadState.UPLOADING, f"{held}; waiting for the home to be set", now)
            return
        if self._ticket is not None:
            return
        if self._attempt >= self.attempts:
            self._finish(RouteUploadState.FAILED, f"not on the autopilot after {self._attempt} uploads: {self._last_failure}", now)
            return
        if now < self._retry_at:
            wait = f"upload {self._attempt} failed ({self._last_failure}); again in {self._retry_at - now:.0f} s"
            self._publish(RouteUploadState.UPLOADING, wait, now)
            return
        running = self._transfer.status
        if not self._transfer.idle and not (running is not None and running.ticket == self._superseded):
            self._publish(RouteUploadState.UPLOADING, "waiting for another mission transfer to end", now)
            return
        self._attempt += 1
        self._superseded = None
        self._ticket = self._transfer.upload(route_items(wanted), self._home_item(), verify=True)
        self._publish(RouteUploadState.UPLOADING, f"uploading {len(wanted)} waypoints of {n} (upload {self._attempt}/{self.attempts})", now)

    # -- listeners ---------------------------------------------------------------------------
    def _on_route(self, route: Route, reason: str) -> None:
        """An edit: take it to the autopilot, starting now (before the tree looks, so that nothing else uploads it too)."""
        self._superseded, self._ticket = self._ticket, None  # our upload of the route before this edit, if it still runs, gives way
        self._route, self._edit, self._attempt, self._retry_at, self._last_failure = route, reason, 0, 0.0, ""
        if route.home is not None and route.home != self._home:
            self._home = route.home
            self._home_ticket = self._commander.set_home(route.home.lat, route.home.lon, self._home_altitude())
        self.service()

    def _on_replace(self, mission: Mission, reason: str) -> None:
        """With ``drive: auto`` the autopilot is given only the edited route's horizon (its waypoints through
        the current leg's and ``limits.auto_horizon_legs`` beyond it): the tree's HorizonOnAutopilot
        extends it as legs are reached (executive.behaviours.auto_legs).

        A mission replaced while paused: its route goes to the autopilot now; its home is not an edit."""
        route = self._mission_state.legs.route
        self._home = route.home
        self._on_route(route, reason)

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is MissionStatus.READY:  # another mission: its home is not an edit
            self._home = self._mission_state.legs.route.home

    # -- internals ---------------------------------------------------------------------------
    def _horizon(self) -> tuple[int, int] | None:
        """drive: auto: (the current leg, limits.auto_horizon_legs): the autopilot is given no more of the route than that horizon."""
        mission = self._mission_state.mission
        if mission is None or mission.drive != "auto":
            return None
        return self._mission_state.legs.leg_index, mission.limits.auto_horizon_legs

    def _held(self, route: Route, horizon: tuple[int, int] | None) -> str | None:
        """Why the autopilot does not hold the edit (its horizon, with drive: auto); None when it does."""
        held = self._vehicle.get("/vehicle/mission_items")
        if horizon is None:
            return route_not_on_autopilot(route.waypoints, held)
        return horizon_not_on_autopilot(route.waypoints, *horizon, held)

    def _follow(self, status: MissionTransferStatus | None, now: float) -> bool:
        """Follow our upload; True once it ended (for better or worse)."""
        if status is None or status.ticket != self._ticket:
            self._failed("superseded by another mission transfer", now)
            return True
        if status.state is TransferState.IN_PROGRESS:
            step = "reading back" if status.verifying else "sending"
            self._publish(RouteUploadState.UPLOADING, f"upload {self._attempt}/{self.attempts}: {step} {status.progress}/{status.total} items", now)
            return False
        self._ticket = None
        if status.state is TransferState.FAILED:
            self._failed(status.reason, now)
        return True

    def _failed(self, reason: str, now: float) -> None:
        self._ticket = None
        self._last_failure = reason
        self._retry_at = now + self.retry_s
        log.warning("route upload %d/%d failed: %s", self._attempt, self.attempts, reason)

    def _home_problem(self) -> str | None:
        """About the home this edit asked for: "" set (or none asked), None still waiting, else why it was not set."""
        if self._home_ticket is None:
            return ""
        command: CommandStatus | None = self._vehicle.get(_SET_HOME_KEY)
        if command is None or command.ticket != self._home_ticket or command.state in _PENDING:
            return None
        if command.state is CommandState.ACCEPTED:
            return ""
        result = mavlink.enums["MAV_RESULT"].get(command.result) if command.result is not None else None
        return f"DO_SET_HOME {command.state.lower().replace('_', ' ')}{f' ({result.name})' if result else ''}"

    def _home_words(self) -> str:
        return "; home set" if self._home_ticket is not None else ""

    def _home_item(self) -> tuple[float, float, float] | None:
        """Item 0: the home this edit set, else the autopilot's (ArduPilot keeps its own there anyway)."""
        if self._home_ticket is not None and self._home is not None:
            return self._home.lat, self._home.lon, self._home_altitude()
        home: HomePosition | None = self._vehicle.get("/vehicle/home")
        return (home.lat, home.lon, home.alt_m) if home else None

    def _home_altitude(self) -> float:
        """The new home keeps the autopilot's home altitude (above mean sea level): the mission's home has none."""
        home: HomePosition | None = self._vehicle.get("/vehicle/home")
        return home.alt_m if home is not None else 0.0

    def _finish(self, state: RouteUploadState, detail: str, now: float) -> None:
        self._publish(state, detail, now)
        if state is RouteUploadState.DONE:
            log.info("route on the autopilot: %s (%s)", detail, self._edit)
        else:
            log.error("route not on the autopilot: %s (%s)", detail, self._edit)
        self._route = None
        self._home_ticket = None

    def _publish(self, state: RouteUploadState, detail: str, now: float) -> None:
        assert self._route is not None
        self._bb.set("/link/route_upload", RouteUpload(state, self._edit, len(self._route), self._attempt, self.attempts, detail, now))


__all__ = ["RouteKeeper", "RouteUpload", "RouteUploadState"]
