"""Test helpers: MAVLink peers whose messages look as if they came off the wire, fake links and vehicles, a runtime over a real socket."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Status

from executive import blackboard
from executive.clock import ManualClock, ScaledClock
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.dialect import MAVLinkMessage, encoder, mavlink
from executive.io.mavlink.link import MemoryLink, PymavlinkLink
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.runtime import Outcome, Runtime


class Peer:
    """``Peer(1, 1).heartbeat(...)``: the message a component would send, header and all."""

    def __init__(self, system_id: int, component_id: int) -> None:
        self._encoder = encoder(system_id, component_id)
        self._parser = mavlink.MAVLink(None)

    def __getattr__(self, name: str) -> Callable[..., MAVLinkMessage]:
        encode = getattr(self._encoder, f"{name}_encode")

        def send(*args: Any) -> MAVLinkMessage:
            return self._parser.decode(bytearray(encode(*args).pack(self._encoder)))

        return send


AUTOPILOT = Peer(1, 1)
GCS = Peer(255, 190)


def ack(command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> MAVLinkMessage:
    return AUTOPILOT.command_ack(command, result, 0, 0, 1, 191)


class FakeLink(MemoryLink):
    """A Link that records what is sent and returns what a test queued for reception."""

    def take(self, kind: str | None = None) -> list[MAVLinkMessage]:
        """Messages sent since the last take (of one type, if given), oldest first."""
        taken = [m for m in self.sent if kind is None or m.get_type() == kind]
        self.sent = [m for m in self.sent if m not in taken]
        return taken


class ObedientAutopilot:
    """Answers on the fake link: heartbeats every tick and instant mode changes."""

    def __init__(self, link) -> None:
        self.link, self.mode = link, 15  # GUIDED
        self._send = link.send
        link.send = self.receive

    def receive(self, msg) -> None:
        self._send(msg)
        if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            self.mode = int(msg.param2)
            self.link.incoming.append(AUTOPILOT.command_ack(msg.command, 0, 0, 0, 1, 191))
        if msg.get_type() == "HEARTBEAT":
            self.beat()

    def beat(self) -> None:
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        self.link.incoming.append(AUTOPILOT.heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, 3, base, self.mode, 4))


class Vehicle:
    """Writes vehicle facts to the blackboard as the reader would (for tick tests)."""

    def __init__(self) -> None:
        self.bb = blackboard.writer("test vehicle", blackboard.keys_under("/link/", "/vehicle/", "/rc/", "/heading/"))

    def set(self, **facts: object) -> None:
        """``set(vehicle__mode="GUIDED", link__up=True)`` -> ``/vehicle/mode``, ``/link/up``."""
        for name, value in facts.items():
            self.bb.set("/" + name.replace("__", "/"), value)


class Harness:
    """A tree ticked by hand: the clock advances ``dt`` before each tick; commands are flushed after."""

    def __init__(
        self, root: py_trees.behaviour.Behaviour, clock: ManualClock, link: FakeLink, commander: Commander, mission_state: MissionState
    ) -> None:
        self.root = root
        self.clock = clock
        self.link = link
        self.commander = commander
        self.mission_state = mission_state
        self.tree = py_trees.trees.BehaviourTree(root)
        self.tree.setup(clock=clock, commander=commander, mission_state=mission_state)

    def tick(self, dt: float = 0.1) -> Status:
        self.clock.advance(dt)
        self.tree.tick()
        self.commander.flush()
        return self.root.status

    def ack(self, command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> None:
        """A COMMAND_ACK arrives from the autopilot."""
        self.commander.on_ack(ack(command, result))


def mission_errors(text: str, filename: str = "m.yaml") -> list[str]:
    """Every located error of a mission text (none when it is valid)."""
    from executive.mission.errors import MissionError
    from executive.mission.loader import load_mission_text

    try:
        load_mission_text(text, filename)
    except MissionError as exc:
        return [str(e) for e in exc.errors]
    return []


def run_over(url: str, mission: Mission, clock: ScaledClock, **options: Any) -> tuple[Runtime, Outcome]:
    """A runtime on a real link to ``url`` (a simulator), connected and run to the mission's end; the link closed after.

    ``options`` go to :class:`Runtime` (progress, can_bus, obstacle_socket...).
    """
    link = PymavlinkLink(url)
    try:
        runtime = Runtime(mission, link, clock, **options)
        assert runtime.connect(10.0 * clock.speedup)
        return runtime, runtime.run()
    finally:
        link.close()
