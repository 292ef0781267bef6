"""Ground-station control of the executive over MAVLink, as the onboard-computer component.

Mission Planner or QGroundControl can pause, continue and start the mission with COMMAND_LONG
addressed to us (MAV_CMD_DO_PAUSE_CONTINUE, MAV_CMD_MISSION_START: continues a paused one), acked as ArduPilot acks
commands; only allow-listed system ids are obeyed. The mission state, current leg and distance
to the next waypoint are reported as STATUSTEXT on every change (a mission replaced while paused
too) and NAMED_VALUE_FLOAT at 1 Hz; so is what the mission announces (a failsafe's reaction, refused,
replaced by the next one the firmware allows, confirmed).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

from executive.io.mavlink.link import Link
from executive.mission.events import Announcement, Replaced, Stage, Transition
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.operator.requests import Operator
from executive.operator.status import StatusSource
from executive.world.clock import Clock
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, encoder, mavlink

log = logging.getLogger("executive.operator.gcs")  # the journal's event kind: "gcs", as ever

#: NAMED_VALUE_FLOAT "MSN_STATE" values.
STATE_CODES = {status: float(i) for i, status in enumerate(MissionStatus)}


class GroundStationControl:
    """Answers ground-station commands sent to us and reports the mission to every link."""

    def __init__(
        self,
        links: Iterable[Link],
        clock: Clock,
        operator: Operator,
        *,
        system_id: int = 1,
        component_id: int = EXECUTIVE_COMPONENT,
        allowed_systems: Iterable[int] = (255,),
        period_s: float = 1.0,
    ) -> None:
        self.links = list(links)
        self._clock = clock
        self._operator = operator
        self.system_id, self.component_id = system_id, component_id
        self.allowed_systems = frozenset(allowed_systems)
        self._encoder = encoder(system_id, component_id)
        self._status = StatusSource("ground station")
        self._period_s = period_s
        self._next = float("-inf")
        self._outbox: list[MAVLinkMessage] = []
        events = operator.mission_state.events
        events.subscribe(Transition, self._on_transition, Stage.GROUND_STATION)
        events.subscribe(Replaced, self._on_replace, Stage.GROUND_STATION)
        events.subscribe(Announcement, self._on_announce, Stage.GROUND_STATION)

    def on_command(self, msg: MAVLinkMessage, reply_to: Link) -> bool:
        """A COMMAND_LONG from someone other than the autopilot; returns whether it was ours to answer."""
        if (msg.target_system, msg.target_component) != (self.system_id, self.component_id):
            return False
        sender = msg.get_srcSystem()
        if sender not in self.allowed_systems:
            log.warning("ground station: command %d from system %d refused (not allow-listed)", msg.command, sender)
            result = mavlink.MAV_RESULT_DENIED
        elif msg.command == mavlink.MAV_CMD_DO_PAUSE_CONTINUE:
            result = self._apply("resume" if round(msg.param1) == 1 else "pause", msg)
        elif msg.command == mavlink.MAV_CMD_MISSION_START:  # a paused mission is continued, not started again
            result = self._apply("resume" if self._operator.mission_state.status is MissionStatus.PAUSED else "start", msg)
        else:
            result = mavlink.MAV_RESULT_UNSUPPORTED
        reply_to.send(self._encoder.command_ack_encode(msg.command, result, 0, 0, sender, msg.get_srcComponent()))
        return True

    def serve(self, link: Link, allowed_systems: Iterable[int]) -> None:
        """Ground stations on an endpoint of their own, ``link``, too: reported to; from now on only ``allowed_systems`` obeyed."""
        self.links.append(link)
        self.allowed_systems = frozenset(allowed_systems)

    def answer(self, messages: Iterable[MAVLinkMessage], reply_to: Link) -> None:
        """Answer the COMMAND_LONGs among ``messages``, which came on ``reply_to`` (the others, and commands not ours, are passed over)."""
        for msg in messages:
            if msg.get_type() == "COMMAND_LONG":
                self.on_command(msg, reply_to)

    def service(self) -> None:
        """Send the periodic report when due, and any state-change text."""
        now = self._clock.now()
        if now >= self._next:
            self._next = now + self._period_s
            status = self._status.snapshot()
            values = {
                "MSN_STATE": STATE_CODES.get(MissionStatus(status["state"]), -1.0),
                "MSN_LEG": float(status["leg"]),
                "WP_DIST": -1.0 if status["distance_m"] is None else float(status["distance_m"]),
            }
            if status.get("energy") is not None:  # Wh: left above the reserve, to finish and return, the margin (1 sigma off)
                energy = status["energy"]
                values |= {"EN_LEFT": energy["has_wh"], "EN_NEED": energy["need_wh"], "EN_MARGIN": energy["margin_wh"]}
            boot_ms = int(now * 1000) & 0xFFFFFFFF
            self._outbox += [self._encoder.named_value_float_encode(boot_ms, name.encode(), value) for name, value in values.items()]
        for msg in self._outbox:
            for link in self.links:
                link.send(msg)
        self._outbox.clear()

    def _apply(self, op: str, msg: MAVLinkMessage) -> int:
        reply = self._operator.request(op, source=f"ground station {msg.get_srcSystem()}")
        if not reply.ok:
            log.warning("ground station: %s refused: %s", op, reply.reason)
            self._text(mavlink.MAV_SEVERITY_WARNING, f"executive: {op} refused: {reply.reason}")
        return mavlink.MAV_RESULT_ACCEPTED if reply.ok else mavlink.MAV_RESULT_TEMPORARILY_REJECTED

    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        self._text(mavlink.MAV_SEVERITY_NOTICE, f"mission {after}: {reason}")

    def _on_replace(self, mission: Mission, reason: str) -> None:
        self._text(mavlink.MAV_SEVERITY_NOTICE, f"mission replaced: {mission.name}")  # the whole reason is in ctl status

    def _on_announce(self, text: str, warning: bool) -> None:
        self._text(mavlink.MAV_SEVERITY_WARNING if warning else mavlink.MAV_SEVERITY_NOTICE, text)

    def _text(self, severity: int, text: str) -> None:
        self._outbox.append(self._encoder.statustext_encode(severity, text.encode()[:50]))
