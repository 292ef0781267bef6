"""A scripted autopilot for tick tests: it answers what the tree asks for at once, and a test (or a subclass) says how."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from py_trees.common import Status

from executive.geo import destination, distance_bearing
from executive.io.mavlink.dialect import MAVLinkMessage, mavlink
from executive.state import GlobalPosition
from executive.testing.harness import Harness

_M = mavlink


class ScriptedAutopilot:
    """An autopilot behind a :class:`Harness` that obeys at once: modes and arming acked, GUIDED targets stepped toward.

    After each tick, :meth:`respond` takes what the tree sent, answers each message (acks go to
    the commander, as the reader would pass them on), moves the vehicle one tick (:meth:`move`)
    and publishes its facts to the blackboard (:meth:`facts`). :attr:`commands` is what it was
    told, readable: ``("mode", "GUIDED")``, ``("arm", 1.0)``, ``("goto", lat, lon)``; a command kind
    (``"arm"``, a mode name, a command name such as ``"DO_CHANGE_SPEED"``) in :attr:`refuse` is
    answered :attr:`refusal`. Subclass it for another firmware: override :meth:`on_command`,
    :meth:`on_setpoint`, :meth:`enter_mode`, :meth:`move` and :meth:`facts`.
    """

    def __init__(self, harness: Harness, start: tuple[float, float] = (0.0, 0.0), *, step_m: float = 8.0, mode: str = "MANUAL") -> None:
        self.h = harness
        self.lat, self.lon = start
        self.alt = 0.0
        self.step_m = step_m
        self.mode, self.armed = mode, False
        self.target: tuple[float, float] | None = None
        self.commands: list[tuple[Any, ...]] = []
        self.refuse: set[str] = set()
        self.refusal = _M.MAV_RESULT_FAILED
        self.received = 0
        self.publish()

    # -- what it tells the executive -----------------------------------------------------------
    def facts(self) -> dict[str, object]:
        """The blackboard facts it publishes after each tick (``vehicle__mode=...``, as :meth:`Vehicle.set` takes them)."""
        return {
            "vehicle__mode": self.mode,
            "vehicle__armed": self.armed,
            "vehicle__position": GlobalPosition(self.lat, self.lon, self.alt, 0.0, 0.0, 0.0, 0.0, 0.0),
        }

    def publish(self) -> None:
        """Write :meth:`facts` to the blackboard."""
        self.h.vehicle.set(**self.facts())

    # -- how it answers -------------------------------------------------------------------------
    def respond(self) -> None:
        """Answer what the tree sent since the last call, move one tick, publish."""
        for msg in self.h.link.take():
            self.received += 1
            kind = msg.get_type()
            if kind in ("COMMAND_LONG", "COMMAND_INT"):
                result = self.on_command(msg)
                if result is not None:
                    self.h.ack(msg.command, result)
            elif kind.startswith("SET_POSITION_TARGET"):
                self.on_setpoint(msg)
            else:
                self.on_message(msg)
        self.move()
        self.publish()

    def answer(self, kind: str) -> int:
        """The result for a command of ``kind``: refused if listed in :attr:`refuse`, else accepted."""
        return self.refusal if kind in self.refuse else _M.MAV_RESULT_ACCEPTED

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        """Answer a COMMAND_LONG / COMMAND_INT: the MAV_RESULT to ack with (None: no ack). Modes and arming here; others accepted."""
        if msg.command == _M.MAV_CMD_DO_SET_MODE:
            mode = self.h.commander.modes.decode(int(msg.param2))
            self.commands.append(("mode", mode))
            result = self.answer(mode)
            if result == _M.MAV_RESULT_ACCEPTED and not self.enter_mode(mode):
                result = _M.MAV_RESULT_FAILED
            return result
        if msg.command == _M.MAV_CMD_COMPONENT_ARM_DISARM:
            self.commands.append(("arm", msg.param1))
            result = self.answer("arm")
            if result == _M.MAV_RESULT_ACCEPTED:
                self.armed = bool(msg.param1)
            return result
        from executive.io.mavlink.commander import command_name

        name = command_name(msg.command)
        self.commands.append((name,))
        return self.answer(name)

    def enter_mode(self, mode: str) -> bool:
        """Switch to ``mode`` (False refuses it); the target is forgotten, as a mode change does."""
        self.mode, self.target = mode, None
        return True

    def on_setpoint(self, msg: MAVLinkMessage) -> None:
        """A position target: followed in the guided mode (ignored silently elsewhere, as ArduPilot does)."""
        if msg.get_type() == "SET_POSITION_TARGET_GLOBAL_INT" and self.mode == self.h.commander.profile.guided_mode:
            self.target = (msg.lat_int / 1e7, msg.lon_int / 1e7)
            self.commands.append(("goto", round(self.target[0], 7), round(self.target[1], 7)))

    def on_message(self, msg: MAVLinkMessage) -> None:
        """Anything else the executive sent (ignored)."""

    def move(self) -> None:
        """One tick of motion: armed, in the guided mode, ``step_m`` toward the target."""
        if self.target and self.armed and self.mode == self.h.commander.profile.guided_mode:
            d, b = distance_bearing(self.lat, self.lon, *self.target)
            self.lat, self.lon = destination(self.lat, self.lon, b, min(d, self.step_m))

    # -- driving the test ----------------------------------------------------------------------
    def run(self, ticks: int, until: Callable[[], bool] | None = None, dt: float = 0.1) -> list[Status]:
        """Tick and respond up to ``ticks`` times, stopping when the tree is no longer RUNNING or ``until()``; the statuses."""
        statuses = []
        for _ in range(ticks):
            statuses.append(self.h.tick(dt))
            self.respond()
            if statuses[-1] != Status.RUNNING or (until is not None and until()):
                break
        return statuses
