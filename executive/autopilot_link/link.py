"""The autopilot link: the one object the runtime holds for the autopilot at the other end of a MAVLink link.

Its four phases: :meth:`AutopilotLink.connect` (announce ourselves, wait for the autopilot's
heartbeat, ask for its parameters), :meth:`~AutopilotLink.pump` (what it said since, onto the
blackboard), :meth:`~AutopilotLink.flush` (what the tick asked of it, and the link's own upkeep)
and :meth:`~AutopilotLink.make_safe`. Its parts (commander, mission transfer, reader, our
heartbeat, stream set-up, route keeper, parameter watch, and the port the tree asks) are made and
wired to each other in its constructor.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from executive.autopilot import AutopilotName
from executive.autopilot.asking import READS, Announce, Asker
from executive.autopilot.selection import Autopilot
from executive.autopilot_link.commanded import CommandWatch
from executive.autopilot_link.parameters import ParameterWatch, wanted_parameters
from executive.autopilot_link.replaced_zones import ReplacedZones
from executive.autopilot_link.route_keeper import RouteKeeper
from executive.autopilot_link.safe_state import SURFACE_COMPLETE_MODE, SafePlan, Until, progress, settled, where
from executive.autopilot_link.safe_state import plan as safe_plan
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.link import Link, PymavlinkLink
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.streams import StreamRequester, rates_for
from executive.mission.declaration import vehicle_profile
from executive.mission.events import Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.operator.intervention import rc_takeover
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import AUTOPILOT_COMPONENT, MAVLinkMessage, mavlink

log = logging.getLogger("executive.runtime")  # the make-safe's lines, as the log and the journal (event kind "runtime") have them

#: The cause the make-safe's steps are logged and announced under: ``make safe: HOLD refused (FAILED)``.
MAKE_SAFE = "make safe"

#: The make-safe's word when this run never sent the vehicle anything that could change it (:mod:`.commanded`).
NOTHING_TO_MAKE_SAFE = "nothing to make safe: the vehicle was never armed or commanded by this run"

#: After the first autopilot's heartbeat, how long (vehicle time) to listen for others when none was named.
SURVEY_S = 3.0
#: While the make-safe waits for the safe state (surfaced, landed), how often (vehicle time) it says how far the vehicle is.
SAY_WAITING_EVERY_S = 10.0


class _PersonTookOver(Exception):
    """A person took the vehicle while it was made safe: nothing more is asked (the reason is the message)."""


class SeveralAutopilots(RuntimeError):
    """More than one autopilot answers on the link and none was named (``--target-system``): commanding one would be a guess."""

    def __init__(self, systems: dict[int, int]) -> None:
        heard = ", ".join(f"system {sysid} (MAV_TYPE {mav_type})" for sysid, mav_type in sorted(systems.items()))
        super().__init__(f"{len(systems)} autopilots on the link: {heard}; name the one to command with --target-system N")
        self.systems = dict(systems)


@dataclass(frozen=True)
class MadeSafe:
    """What a make-safe came to: ``made`` once the vehicle is seen in the safe mode; ``report`` says it for a person."""

    made: bool
    report: str


class AutopilotLink:
    """The autopilot on ``transport``: commands and acks, mission transfers, telemetry, our heartbeat, streams, route uploads.

    ``mission``: the mission it serves (its vehicle, link timeout and RC; :meth:`use` a replacement);
    ``mission_state``: whose route edits are uploaded (:class:`RouteKeeper`). ``target_system`` and
    ``target_component``: the autopilot to command, alone (None: the only one on the link).
    ``forced``: the back end whatever the heartbeat says (None: the heartbeat's). ``period_s``: how
    often it is pumped while waiting (connecting, making safe): the runtime's tick.
    """

    def __init__(
        self,
        transport: Link,
        clock: Clock,
        mission: Mission,
        mission_state: MissionState,
        *,
        system_id: int = 1,
        target_system: int | None = None,
        target_component: int = AUTOPILOT_COMPONENT,
        forced: AutopilotName | None = None,
        period_s: float = 0.1,
    ) -> None:
        profile = vehicle_profile(mission.vehicle)
        #: What is sent, watched: the make-safe acts only on a vehicle this run has commanded.
        self.watch = CommandWatch(transport)
        self.transport: Link = self.watch
        transport = self.watch
        self.clock = clock
        self.mission = mission
        self.period_s = period_s
        self._mission_state = mission_state
        self.commander = Commander(transport, clock, profile, system_id=system_id)
        self.mission_transfer = MissionTransfer(transport, clock, system_id=system_id)
        #: What the tree asks of the autopilot: intents, turned into its firmware's commands by the back end its heartbeat names (or forced).
        self.autopilot = Autopilot(self.commander, self.mission_transfer, profile, forced=forced)
        self.streams = StreamRequester(self.commander, rates_for(mission.vehicle))
        self.heartbeat = Heartbeat(transport, clock, system_id=system_id)
        self.reader = MavlinkReader(
            transport,
            clock,
            self.commander,
            link_timeout_s=mission.limits.link_timeout_s,
            mission=self.mission_transfer,
            rc_source=mission.rc.source == "mavlink",
            target_system=target_system,
            target_component=target_component,
            on_autopilot=self._found,
            on_reconnect=self.streams.restart,
        )
        if isinstance(self.watch.link, PymavlinkLink):
            self.watch.link.skim(self.reader.kinds_read)  # what the reader does not read is counted from its header, never decoded
        #: After each edit of the route (any tree, any source), the autopilot is given it: uploaded, read back, retried.
        self.route_keeper = RouteKeeper(mission_state, self.mission_transfer, self.commander, clock)
        #: A mission replaced while paused: its zones and rally points on the autopilot before it may resume.
        self.replaced_zones = ReplacedZones(mission_state, self.autopilot, clock)
        self.parameters = ParameterWatch(self.autopilot, clock)
        keys = {"/vehicle/mode", "/vehicle/mode_set_by", "/rc/channels", "/rc/switches", "/vehicle/position", "/vehicle/landed_state", *READS}
        self._bb = blackboard.reader("autopilot link", keys)
        #: Why a person holds the vehicle: the mission paused hands off (a person's mode or disarm), until it runs again.
        self._hands_off: str | None = None
        mission_state.events.subscribe(Transition, self._on_transition, Stage.AUTOPILOT_LINK)

    def _found(self, heartbeat_autopilot: int, mav_type: int) -> None:
        """The reader found the autopilot: the port takes its back end; the streams and our heartbeat follow the firmware."""
        self.autopilot.adopt(heartbeat_autopilot, mav_type)
        name = self.autopilot.backend.name
        self.streams.rates = rates_for(self.mission.vehicle, name)
        self.heartbeat.mav_type = mavlink.MAV_TYPE_GCS if name == "px4" else mavlink.MAV_TYPE_ONBOARD_CONTROLLER

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if after is MissionStatus.PAUSED and not self._mission_state.hold_while_paused:
            self._hands_off = f"a person holds the vehicle (the mission paused hands off: {reason})"
        elif after in (MissionStatus.RUNNING, MissionStatus.READY, MissionStatus.IDLE):
            self._hands_off = None

    def use(self, mission: Mission) -> None:
        """A mission replacing the one served (hot reload): its link timeout and RC from now on."""
        self.mission = mission
        self.reader.link_timeout_s = mission.limits.link_timeout_s

    def get(self, key: str) -> Any:
        """A blackboard key the link reads (what its make-safe's :class:`~executive.autopilot.asking.Asker` reads)."""
        return self._bb.get(key)

    # -- the phases ------------------------------------------------------------------------------
    def connect(self, timeout_s: float, survey_s: float = SURVEY_S) -> bool:
        """Announce ourselves and wait for the autopilot's heartbeat (bounded); True once heard.

        With no target system named, listen ``survey_s`` longer: a second autopilot heard raises
        :class:`SeveralAutopilots` (nothing has been sent to either but our heartbeat).
        """
        deadline = self.clock.now() + timeout_s
        while self.clock.now() < deadline:
            self.heartbeat.service()
            self.reader.drain()
            if self.reader.autopilot is not None:
                break
            self.clock.sleep_until(self.clock.now() + self.period_s)
        else:
            return False
        if self.reader.target_system is None:
            survey_end = self.clock.now() + survey_s
            while len(self.reader.autopilots_heard) < 2 and self.clock.now() < survey_end:
                self.clock.sleep_until(self.clock.now() + self.period_s)
                self.heartbeat.service()
                self.reader.drain()
            if len(self.reader.autopilots_heard) > 1:
                raise SeveralAutopilots(self.reader.autopilots_heard)
        # known by pre-flight: the mission's switches are checked against the mode channel before arming, and the
        # look-ahead drives by the vehicle's own parameters (ParameterWatch asks again for any not answered)
        wanted = wanted_parameters(self.autopilot)
        for param in wanted:
            self.autopilot.read_parameter(param)
        if wanted:
            self.commander.flush()
        return True

    def pump(self) -> None:
        """What the autopilot said since the last pump, onto the blackboard; our heartbeat when it is due."""
        self.reader.drain()
        self.heartbeat.service()

    def commands_for_us(self) -> list[MAVLinkMessage]:
        """The COMMAND_LONGs a ground station sent us through the autopilot since the last call (answered on :attr:`transport`)."""
        return self.reader.take_commands()

    def flush(self) -> None:
        """Send what the tick asked of the autopilot, after the link's own upkeep: stream set-up, route uploads, parameter asks."""
        self.streams.service()
        self.route_keeper.service()
        self.replaced_zones.service()
        self.parameters.service()
        self.autopilot.service()  # the back end's own traffic (PX4's offboard setpoint stream), before the commands
        self.commander.flush()
        self.mission_transfer.flush()

    def make_safe(
        self, mode: str | None, *, announce: Announce | None = None, timeout_s: float | None = None, report: Callable[[], object] = lambda: None
    ) -> MadeSafe:
        """Command ``mode`` (None: the vehicle's safe mode) until the vehicle is seen in it, then (a sub, a VTOL near the ground) in its safe state.

        Where depends on the kind and what the vehicle is doing (:mod:`executive.autopilot_link.safe_state`): a sub surfaces,
        a VTOL low down or landing lands and disarms, the others hold. The mode is asked by the failsafe reactions' rules
        (:mod:`executive.autopilot.asking`): again every 1.5 s of vehicle time until the autopilot accepts it and the
        heartbeat shows it; after 3 failed asks the next reaction of the firmware's table (ArduRover: HOLD, then a disarm).
        Bounded: by ``timeout_s`` if given, else by the time the table's chain takes (3 asks 1.5 s apart for each reaction: 9 s
        for a rover's HOLD then disarm); the safe state after it by :meth:`SafePlan.bound_s`. Never against a person: a
        person's mode (or the RC take-over switch), there at the start or chosen meanwhile, is left alone, and so is any vehicle
        a person holds (the mission paused hands off: a ground station's RTL or Go-to is not stopped by a HOLD of ours).
        Its steps go to ``announce``; ``report`` is called each time what was asked is sent (the ground station's reports).
        Its outcome is logged last (INFO when made safe, ERROR when not).
        """
        if self.watch.commanded is None:  # nothing of ours to undo: commanding the safe mode would be a change of our own
            self.reader.drain()  # what came meanwhile (a ground station's command) is answered all the same
            return self._made_safe(True, NOTHING_TO_MAKE_SAFE, report)
        self.reader.drain()
        self.heartbeat.service()
        kind = self.mission.vehicle
        plan = safe_plan(kind, self.autopilot.capabilities.autopilot, mode, self.autopilot.capabilities.safe_mode, self._bb.get)
        safe = plan.mode
        person = self._person_has_the_vehicle(safe) or self._hands_off
        if person:
            log.warning("not commanding %s: %s", safe, person)
            return MadeSafe(False, f"not commanding {safe}: {person}")
        if plan.why is not None:
            log.warning("%s: %s", MAKE_SAFE, plan.why)
        found_in = self._bb.get("/vehicle/mode")
        try:
            done, account = self._ask(safe, found_in, announce, timeout_s, report, plan)
            if done and plan.until is not Until.SHOWN:
                return self._settle(plan, account, found_in, announce, timeout_s, report)
        except _PersonTookOver as person_took:
            return self._made_safe(False, f"not commanding {safe}: {person_took}", report, logging.WARNING)
        if done:
            return self._made_safe(True, f"the vehicle made safe: {account}", report)
        if announce is not None:
            announce("could not make the vehicle safe", True)
        return self._made_safe(False, f"could not make the vehicle safe: {account}", report)

    def _ask(
        self,
        safe: str,
        found_in: str | None,
        announce: Announce | None,
        timeout_s: float | None,
        report: Callable[[], object],
        plan: SafePlan | None = None,
    ) -> tuple[bool, str]:
        """Ask ``safe`` by the reactions' rules until the heartbeat shows it, bounded: (done, what each reaction came to).

        Done too once the vehicle is in ``plan``'s safe state (a sub near the surface may show SURFACE and ArduSub's own
        ALT_HOLD after it in one drain). _PersonTookOver when a person takes the vehicle meanwhile (nothing more is asked).
        """
        own = self._own_follow_on(plan)
        asker = Asker(self, self.mission.vehicle, announce=announce, bounded=True, logger=log, prefix="")
        if self._bb.get("/link/up") and asker.seen(safe):
            return True, f"{self.autopilot.mode_name(safe)} (already in it)"
        asker.start(safe, MAKE_SAFE)
        deadline = self.clock.now() + (timeout_s if timeout_s is not None else asker.time_to_exhaust(safe))
        while True:
            self.autopilot.service()  # PX4: the offboard stream goes on until the heartbeat shows we left OFFBOARD
            self.commander.flush()
            report()  # the steps' STATUSTEXTs
            self.clock.sleep_until(min(deadline, self.clock.now() + self.period_s / 2))
            self.reader.drain()
            self.heartbeat.service()
            if person := self._person_took_over(found_in, asker.mode_in_force, own):
                asker.cancel()
                raise _PersonTookOver(person)
            if plan is not None and plan.until is not Until.SHOWN and settled(plan, self._bb.get):
                asker.cancel()
                return True, f"{self.autopilot.mode_name(safe)} ({plan.until})"
            time_up = self.clock.now() >= deadline - 1e-6  # as the reactions' 1.5 s: a sum of half periods lands a hair short
            asker.follow_up(self.clock.now(), ask=not time_up)
            if asker.done or asker.exhausted or time_up:
                break
        if not asker.done:
            asker.cancel()  # nothing asked goes on being retried after the make-safe gave up (with --wait the executive stays up)
        return asker.done, asker.account()

    def _settle(
        self,
        plan: SafePlan,
        account: str,
        found_in: str | None,
        announce: Announce | None,
        timeout_s: float | None,
        report: Callable[[], object],
    ) -> MadeSafe:
        """The mode is shown: wait (bounded, saying for what) until the vehicle is in the plan's safe state, then ask its next mode."""
        start = self.clock.now()
        bound = plan.bound_s()
        log.warning("%s: %s; waiting until %s (%s; at most %.0f s)", MAKE_SAFE, account, plan.until, progress(plan, self._bb.get), bound)
        if announce is not None:
            announce(f"{MAKE_SAFE}: waiting until {plan.until}", False)
        said_at = start
        while not settled(plan, self._bb.get) and self.clock.now() < start + bound - 1e-6:
            self.autopilot.service()
            self.commander.flush()
            report()
            self.clock.sleep_until(min(start + bound, self.clock.now() + self.period_s / 2))
            self.reader.drain()
            self.heartbeat.service()
            if person := self._person_took_over(found_in, plan.mode, self._own_follow_on(plan)):
                raise _PersonTookOver(person)
            if self.clock.now() - said_at >= SAY_WAITING_EVERY_S:
                said_at = self.clock.now()
                log.info("%s: waiting until %s: %s (%.0f s)", MAKE_SAFE, plan.until, progress(plan, self._bb.get), said_at - start)
        took = self.clock.now() - start
        if not settled(plan, self._bb.get):
            if announce is not None:
                announce(f"could not make the vehicle safe: not {plan.until}", True)
            text = f"{account}, not {plan.until} after {took:.0f} s ({progress(plan, self._bb.get)})"
            return self._made_safe(False, f"could not make the vehicle safe: {text}", report)
        steps = f"{account}, {plan.until} after {took:.1f} s"
        done = True
        if plan.then is not None:
            done, then_account = self._ask(plan.then, self._bb.get("/vehicle/mode"), announce, timeout_s, report)
            steps += f", {then_account}"
        left = where(self.mission.vehicle, self._bb.get("/vehicle/mode"), self._bb.get)
        if announce is not None:
            announce(f"made safe: {left}", False)
        return self._made_safe(done or plan.until is Until.SURFACED, f"the vehicle made safe: {left} ({steps})", report)

    def _own_follow_on(self, plan: SafePlan | None) -> str | None:
        """The mode the firmware goes on to by itself from the plan's (ArduSub: ALT_HOLD at the surface): not a person's."""
        return SURFACE_COMPLETE_MODE if plan is not None and plan.until is Until.SURFACED else None

    def _made_safe(self, made: bool, text: str, report: Callable[[], object], level: int | None = None) -> MadeSafe:
        """The make-safe's last word: logged (INFO made safe, else ERROR, or ``level``), what was asked sent, the ground station told."""
        log.log(level if level is not None else logging.INFO if made else logging.ERROR, "%s", text)
        self.commander.flush()
        report()
        return MadeSafe(made, text)

    def _person_took_over(self, found_in: str | None, asked: str | None, own: str | None = None) -> str | None:
        """Why a person has taken the vehicle while it is made safe: the RC take-over switch, or a mode in which a person drives set meanwhile.

        ``own``: a mode the firmware goes on to by itself from the one asked (ArduSub's ALT_HOLD at the surface), nobody's.
        """
        takeover = rc_takeover(self.mission.rc, self._bb.get)
        if takeover is not None:
            return takeover
        mode = self._bb.get("/vehicle/mode")
        if mode in vehicle_profile(self.mission.vehicle).pilot_modes and mode not in (found_in, asked, own):
            return f"the vehicle is in {mode}, set by the RC or a ground station while the executive made it safe: a person drives it"
        return None

    def _person_has_the_vehicle(self, ours: str) -> str | None:
        """Why a person has the vehicle, if one has: then hands off.

        The RC take-over switch high, switch C in MANUAL, or a mode in which a person drives (MANUAL,
        ACRO...) other than ``ours`` (the mode a failsafe of ours left it in) that someone chose while
        we watched (``/vehicle/mode_set_by``): the RC or a ground station, or we at a person's request
        (``ctl mode``, the UGV's switch C). The mode the vehicle was in when we found it (its boot mode)
        is nobody's choice: a pilot mode there is no person driving, and the safe mode is commanded
        (said so, as the manual's "When a person intervenes" (docs/failsafes.md) has it).
        """
        takeover = rc_takeover(self.mission.rc, self._bb.get)
        if takeover is not None:
            return takeover
        mode = self._bb.get("/vehicle/mode")
        if mode not in vehicle_profile(self.mission.vehicle).pilot_modes or mode == ours:
            return None
        set_by = self._bb.get("/vehicle/mode_set_by")
        if set_by in (None, "autopilot"):  # as the failsafes judge it (behaviours/failsafe.py): nobody's choice
            found = (
                "the mode it was in when the executive found it (its boot mode, or one set before; nobody changed it while the executive watched)"
                if set_by is None
                else "set by the autopilot itself (its own transition, executive.autopilot.mode_cause)"
            )
            log.info("commanding %s: the vehicle is in %s, %s", ours, mode, found)
            return None
        who = "through the executive at a person's request" if set_by == "us" else "by the RC or a ground station"
        return f"the vehicle is in {mode}, set {who} while the executive watched: a person drives it"
