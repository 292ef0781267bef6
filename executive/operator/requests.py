"""Operator requests - from ``executive ctl``, the ground station or RC switches - applied to the mission lifecycle.

Every request follows the lifecycle's transition table; a refused one changes nothing and says
why. The reply carries the resulting state so a client never has to ask twice.

``route`` requests edit the route (``{"op": "route", "operation": "offset", "distance_m": 5,
"bearing_deg": 90}``; the operations and their arguments are :func:`executive.mission.route.apply`'s)
or show it (``"operation": "show"``); their reply carries the route and what the autopilot holds.

``upload`` while PAUSED replaces the mission (hot reload, :mod:`executive.mission.reload`): the
same leg (or ``"leg": N``, 1-based), the samples already taken kept; the reply carries the new
route. Refused with the reason, nothing changed, when the mission is not compatible.

``arm``, ``disarm`` (``"force": true`` skips the autopilot's checks) and ``mode`` (``"mode": "HOLD"``)
command the vehicle for a person, and a person always wins: the command is sent whatever the
mission's state. What it did to the vehicle decides the rest (:mod:`executive.operator.persons_commands`):
a running mission pauses hands off once the heartbeat shows the mode or the disarm (the tree would
otherwise undo it), and one the autopilot refuses changes nothing; ``arm`` never pauses (a mission may
be waiting for it). The reply carries the command's ticket; ``command`` (``"ticket"``, ``"name"``) says
what the autopilot answered.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from executive.admission.checks import load_mission_text
from executive.io.mavlink.mission_protocol import route_not_on_autopilot
from executive.mission import reload
from executive.mission import route as routes
from executive.mission.errors import MissionError
from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.mission.model import Mission
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import CommandStatus, EkfStatus, GlobalPosition, Outcome

if TYPE_CHECKING:
    from executive.autopilot.port import AutopilotPort
    from executive.operator.persons_commands import PersonsCommands

log = logging.getLogger("executive.operator")  # as the log and the journal (event kind "operator") have it

REQUESTS = ("status", "start", "pause", "resume", "abort", "delete", "upload", "route", "tree", "arm", "disarm", "mode", "command")
#: The commands a person may give the vehicle, and the blackboard keys of their acks.
VEHICLE_REQUESTS = ("arm", "disarm", "mode")
_COMMAND_KEYS = {outcome: blackboard.command_key(outcome) for outcome in (Outcome.ARMING, Outcome.MODE)}


@dataclass(frozen=True)
class Reply:
    """What became of a request."""

    ok: bool
    reason: str
    state: str
    status: dict[str, Any] | None = None
    route: dict[str, Any] | None = None
    tree: dict[str, Any] | None = None
    command: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        return {k: v for k, v in asdict(self).items() if v is not None}


class Operator:
    """Applies operator requests to a :class:`MissionState`.

    ``status`` supplies the status snapshot for ``status`` requests; ``vehicle`` is the kind of
    vehicle this executive drives (an uploaded mission for another kind is refused). A route edit
    at the vehicle's position needs one the EKF vouches for, no older than ``max_position_age_s``
    (checked with ``clock``, when given). ``refuse`` says why a mission cannot run on this vehicle
    (its samples could not be real), if it cannot. ``autopilot`` takes a person's arm, disarm and
    mode (None: refused), followed by ``persons`` to what they did. ``tree`` supplies the running tree for ``tree`` requests
    (:meth:`executive.tree.waiting.TreeWatch.view`). ``autopilot_name`` names the firmware driven (a
    replacement mission for another is refused).
    """

    def __init__(
        self,
        mission_state: MissionState,
        vehicle: str,
        status: Callable[[], dict[str, Any]] | None = None,
        clock: Clock | None = None,
        max_position_age_s: float = 2.0,
        refuse: Callable[[Mission], str | None] | None = None,
        autopilot: AutopilotPort | None = None,
        tree: Callable[[], dict[str, Any] | None] | None = None,
        autopilot_name: Callable[[], str | None] | None = None,
        persons: PersonsCommands | None = None,
    ) -> None:
        self.mission_state = mission_state
        self.vehicle = vehicle
        self._status = status
        self._clock = clock
        self.max_position_age_s = max_position_age_s
        self._refuse = refuse
        self.autopilot = autopilot
        self._tree = tree
        self._autopilot_name = autopilot_name
        self._persons = persons
        keys = ["/vehicle/position", "/vehicle/ekf", "/vehicle/mission_items", "/link/route_upload", *_COMMAND_KEYS.values()]
        self._bb = blackboard.reader("operator", keys)

    def request(self, op: str, source: str = "operator", **args: Any) -> Reply:
        """Apply one request; ``source`` (ctl, gcs, rc) is recorded in the reasons."""
        state = self.mission_state
        try:
            if op == "status":
                return self._reply(True, state.reason, with_status=True)
            if op == "tree":
                return self._tree_reply()
            if op == "start":
                state.start(vehicle_at=self._here_if_known())
            elif op == "pause":
                state.pause(f"{source}: pause")
            elif op == "resume":
                state.resume()
            elif op == "abort":
                state.abort(f"{source}: abort")
            elif op == "delete":
                state.delete()
            elif op == "upload":
                return self._upload(str(args.get("filename", "<upload>")), args.get("text"), args.get("leg"), source)
            elif op == "route":
                return self._route(args, source)
            elif op in VEHICLE_REQUESTS:
                return self._command_vehicle(op, args, source)
            elif op == "command":
                return self._command_outcome(args)
            else:
                return self._reply(False, f"unknown request {op!r} (known: {', '.join(REQUESTS)})")
        except Refused as refused:
            return self._reply(False, str(refused))
        return self._reply(True, state.reason)

    def _tree_reply(self) -> Reply:
        """The tree at its latest tick, with the status (what it waits for); refused before any mission has run."""
        tree = self._tree() if self._tree is not None else None
        if tree is None:
            return self._reply(False, f"no mission has run yet ({self.mission_state.status})")
        return self._reply(True, self.mission_state.reason, with_status=True, tree=tree)

    def _upload(self, filename: str, text: object, leg: object, source: str) -> Reply:
        if not isinstance(text, str):
            return self._reply(False, "upload needs the mission file's text")
        if leg is not None and (isinstance(leg, bool) or not isinstance(leg, int) or leg < 1):
            return self._reply(False, f"leg: {leg!r} is not a waypoint number (1, 2, ...)")
        try:
            mission: Mission = load_mission_text(text, filename)
        except MissionError as exc:
            return self._reply(False, "\n".join(str(e) for e in exc.errors))
        if mission.vehicle != self.vehicle:
            return self._reply(False, f"{filename}: vehicle: this executive drives a {self.vehicle}, not a {mission.vehicle}")
        why = self._refuse(mission) if self._refuse is not None else None
        if why is not None:
            return self._reply(False, f"{filename}: {why}")
        here = self._here_if_known()
        if self.mission_state.status is MissionStatus.PAUSED:
            return self._replace(filename, mission, leg, here, source)
        if leg is not None:
            return self._reply(False, f"leg: a leg is chosen only when replacing a PAUSED mission (the mission is {self.mission_state.status})")
        if self.mission_state.status is MissionStatus.RUNNING:
            return self._reply(False, "cannot upload while RUNNING: pause it first (ctl pause), then upload to replace the mission")
        self.mission_state.upload(mission, vehicle_at=here)
        return self._reply(True, self.mission_state.reason)

    def _replace(self, filename: str, mission: Mission, leg: int | None, here: tuple[float, float] | None, source: str) -> Reply:
        """Hot reload: the paused mission replaced by ``mission`` at the same leg (or ``leg``), or refused with nothing changed."""
        state = self.mission_state
        assert state.mission is not None
        old = state.mission
        autopilot = self._autopilot_name() if self._autopilot_name is not None else None
        try:
            plan = reload.plan(old, state.legs.leg_index, state.sample_log.taken, mission, autopilot=autopilot, leg=leg)
        except reload.Incompatible as exc:
            return self._reply(False, f"{filename}: cannot replace {old.name!r}: {exc}")
        reason = f"{plan.describe(old)} ({source}: {filename}); paused until resumed"
        state.replace(plan.mission, plan.leg_index, plan.samples, reason, vehicle_at=here)
        waits = [why for check in state.resume_checks if (why := check()) is not None]  # its zones going to the autopilot
        return self._reply(True, "; ".join([reason, *waits]), route=self._route_view())

    def _route(self, args: dict[str, Any], source: str) -> Reply:
        """Edit the route (refused with the reason, changing nothing), or show it."""
        state = self.mission_state
        operation = args.get("operation")
        params = {k: v for k, v in args.items() if k != "operation"}
        if operation == "show":
            return self._reply(True, f"{len(state.legs.route)} waypoints", route=self._route_view())
        refusal = state.route_refusal()
        if refusal is not None:
            return self._reply(False, refusal)
        try:
            new, done = routes.apply(state.legs.route, operation, params, self._here)
            state.set_route(new.waypoints, f"{source}: {done}", leg_index=new.current, home=new.home, vehicle_at=self._here_if_known())
        except (routes.RouteError, Refused) as exc:
            return self._reply(False, f"route {operation}: {exc}")
        return self._reply(True, f"{source}: {done}", route=self._route_view())

    def _command_vehicle(self, op: str, args: dict[str, Any], source: str) -> Reply:
        """A person's arm, disarm or mode: sent whatever the state; what it did to the vehicle is followed (``persons``)."""
        if self.autopilot is None:
            return self._reply(False, f"{op}: no autopilot to command")
        force = args.get("force") is True
        shows: str | None = None
        if op == "mode":
            mode = args.get("mode")
            if not isinstance(mode, str) or not mode:
                return self._reply(False, "mode needs the mode's name")
            try:
                request = self.autopilot.set_mode(mode.upper())
            except KeyError:
                return self._reply(False, f"mode {mode}: not a mode of this vehicle's autopilot")
            shows = self.autopilot.mode_name(mode.upper())
            what = f"mode {request.how or shows}"
        else:
            request = self.autopilot.arm(force=force) if op == "arm" else self.autopilot.disarm(force=force)
            what = f"{'force ' if force else ''}{op}"
        said = f"{source}: {what}"
        if self._persons is not None:
            self._persons.sent(what, source, request, mode=shows, disarm=op == "disarm")
        if op != "arm" and self.mission_state.status is MissionStatus.RUNNING:
            said += "; the mission pauses, hands off, once the vehicle shows it (refused: nothing changes)"
        log.warning("%s, sent to the autopilot", said)
        return self._reply(True, f"{said}, sent to the autopilot", command={"ticket": request.ticket, "name": request.outcome, "what": what})

    def _command_outcome(self, args: dict[str, Any]) -> Reply:
        """What became of a command given by ``ticket`` and ``name`` (its outcome: arming, mode): its state and the autopilot's result."""
        key = _COMMAND_KEYS.get(str(args.get("name")))
        ticket = args.get("ticket")
        if key is None or not isinstance(ticket, int):
            return self._reply(False, f"command needs a ticket and one of {', '.join(_COMMAND_KEYS)}")
        status: CommandStatus | None = self._bb.get(key)
        if status is None or status.ticket < ticket:
            return self._reply(False, f"no command {ticket} of {args['name']}")
        if status.ticket > ticket:  # a newer one of its kind (the tree's, or another person's) took its place
            return self._reply(True, "superseded", command={"ticket": ticket, "state": "SUPERSEDED", "final": True})
        outcome = {"ticket": ticket, "state": str(status.state), "result": status.result_name, "final": status.state.done}
        return self._reply(True, f"{status.state}: {status.result_name}", command=outcome)

    def _here(self) -> tuple[float, float]:
        """The vehicle's position, if it is known well enough to put a waypoint or the home there."""
        position: GlobalPosition | None = self._bb.get("/vehicle/position")
        ekf: EkfStatus | None = self._bb.get("/vehicle/ekf")
        if position is None:
            raise routes.RouteError("no position")
        if ekf is None or not ekf.position_ok():
            raise routes.RouteError("the EKF has no position estimate")
        if self._clock is not None and (age := self._clock.now() - position.time) > self.max_position_age_s:
            raise routes.RouteError(f"the last position is {age:.1f} s old")
        return position.lat, position.lon

    def _here_if_known(self) -> tuple[float, float] | None:
        """The vehicle's position if the EKF vouches for it; None otherwise (the runtime checks the distances before the tree first ticks)."""
        try:
            return self._here()
        except routes.RouteError:
            return None

    def _route_view(self) -> dict[str, Any]:
        """The route as JSON: waypoints (lat, lon, alt_m), names, the one heading for (1-based; legs + 1 when done), home, the autopilot's copy."""
        route = self.mission_state.legs.route
        upload = self._bb.get("/link/route_upload")
        upload_view = (
            None if upload is None else {"state": str(upload.state), "edit": upload.edit, "attempt": upload.attempt, "detail": upload.detail}
        )
        return {
            "waypoints": [[wp.lat, wp.lon, wp.alt_m] for wp in route.waypoints],
            "names": [wp.name for wp in route.waypoints],
            "current": route.current + 1,
            "home": None if route.home is None else [route.home.lat, route.home.lon],
            "on_autopilot": route_not_on_autopilot(route.waypoints, self._bb.get("/vehicle/mission_items")) is None,
            "upload": upload_view,
        }

    def _reply(
        self,
        ok: bool,
        reason: str,
        with_status: bool = False,
        route: dict[str, Any] | None = None,
        tree: dict[str, Any] | None = None,
        command: dict[str, Any] | None = None,
    ) -> Reply:
        status = self._status() if with_status and self._status else None
        return Reply(ok, reason, str(self.mission_state.status), status, route, tree, command)
