"""A ground station for the simulated vehicle (tests/sim): one talking to an autopilot directly, one over a socket.

A module of its own, not conftest.py: test modules import these classes and constants, and ``conftest``
names whichever conftest.py pytest loaded last when several test folders are collected together.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from executive.sim import FirmwareSim
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage, encoder, mavlink, mavutil

GCS_SYSTEM, GCS_COMPONENT = 255, 190
HOME = (47.397742, 8.545594, 0.0)
EKF_READY_S = 10.0
M_PER_DEG_LAT = 111_319.49


class Gcs:
    """Talks to an :class:`FirmwareSim` as a ground station would, without sockets, on a manual clock."""

    def __init__(self, ap: FirmwareSim, clock: ManualClock) -> None:
        self.ap = ap
        self.clock = clock
        self.mav = encoder(GCS_SYSTEM, GCS_COMPONENT)
        self.log: list[MAVLinkMessage] = []  # everything the autopilot sent, oldest first

    def send(self, msg: MAVLinkMessage) -> list[MAVLinkMessage]:
        """Hand a message to the autopilot (packed, so it carries our ids); returns its direct replies."""
        msg.pack(self.mav)
        replies = self.ap.handle(msg)
        self.log += replies
        return replies

    def update(self) -> list[MAVLinkMessage]:
        out = self.ap.update()
        self.log += out
        return out

    def command(self, command: int, *params: float, target: tuple[int, int] = (1, 1)) -> list[MAVLinkMessage]:
        padded = (list(params) + [0.0] * 7)[:7]
        return self.send(self.mav.command_long_encode(*target, command, 0, *padded))

    def ack(self, command: int, *params: float) -> MAVLinkMessage:
        """Send a COMMAND_LONG and return its COMMAND_ACK (which must be the first reply)."""
        replies = self.command(command, *params)
        assert replies and replies[0].get_type() == "COMMAND_ACK", replies
        assert replies[0].command == command
        return replies[0]

    def set_mode(self, mode: str) -> int:
        return self.ack(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, self.ap.profile.modes[mode]).result

    def arm(self, force: bool = False) -> int:
        return self.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, 2989 if force else 0).result

    def goto(
        self, lat: float, lon: float, type_mask: int = 0x0DF8, frame: int = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, alt: float = 0.0
    ) -> list[MAVLinkMessage]:
        x, y = round(lat * 1e7), round(lon * 1e7)
        return self.send(self.mav.set_position_target_global_int_encode(0, 1, 1, frame, type_mask, x, y, alt, *[0.0] * 8))

    def reposition(self, lat: float, lon: float, alt: float, flags: int = 0, radius: float = 0.0) -> MAVLinkMessage:
        """COMMAND_INT MAV_CMD_DO_REPOSITION (relative-altitude frame); returns its COMMAND_ACK."""
        x, y = round(lat * 1e7), round(lon * 1e7)
        frame = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        replies = self.send(self.mav.command_int_encode(1, 1, frame, mavlink.MAV_CMD_DO_REPOSITION, 0, 0, -1, flags, radius, 0, x, y, alt))
        assert replies and replies[0].get_type() == "COMMAND_ACK" and replies[0].command == mavlink.MAV_CMD_DO_REPOSITION, replies
        return replies[0]

    def east(self, metres: float) -> tuple[float, float]:
        """A point ``metres`` east of where the vehicle started."""
        return self.ap.start[0], self.ap.start[1] + metres / (M_PER_DEG_LAT * math.cos(math.radians(self.ap.start[0])))

    def last(self, kind: str) -> MAVLinkMessage:
        """The latest message of a type the autopilot sent."""
        return self.of_type(self.log, kind)[-1]

    def north(self, metres: float) -> tuple[float, float]:
        """A point ``metres`` north of where the vehicle started."""
        return self.ap.start[0] + metres / M_PER_DEG_LAT, self.ap.start[1]

    def run(self, seconds: float, step: float = 0.1) -> list[MAVLinkMessage]:
        """Let ``seconds`` of clock time pass; returns everything the autopilot sent meanwhile."""
        out: list[MAVLinkMessage] = []
        for _ in range(round(seconds / step)):
            self.clock.advance(step)
            out += self.update()
        return out

    @staticmethod
    def texts(messages: list[MAVLinkMessage]) -> list[str]:
        """The STATUSTEXTs, chunks (same non-zero id) joined."""
        texts: list[str] = []
        previous_id = 0
        for msg in (m for m in messages if m.get_type() == "STATUSTEXT"):
            if msg.id and msg.id == previous_id:
                texts[-1] += msg.text
            else:
                texts.append(msg.text)
            previous_id = msg.id
        return texts

    @staticmethod
    def of_type(messages: list[MAVLinkMessage], kind: str) -> list[MAVLinkMessage]:
        return [m for m in messages if m.get_type() == kind]


class Client:
    """A pymavlink client on a real socket, keeping every message it received; waits are bounded by a wall deadline."""

    def __init__(self, url: str) -> None:
        self.conn = mavutil.mavlink_connection(url, source_system=GCS_SYSTEM, source_component=GCS_COMPONENT, dialect="ardupilotmega")
        self.received: list[MAVLinkMessage] = []

    def wait(self, kind: str, condition: Callable[[MAVLinkMessage], bool] = lambda m: True, timeout: float = 30.0) -> MAVLinkMessage:
        """The first ``kind`` message meeting ``condition``; ``timeout`` (wall seconds) only bounds a hung simulator."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.conn.recv_msg()
            if msg is None:
                time.sleep(0.001)
                continue
            self.received.append(msg)
            if msg.get_type() == kind and condition(msg):
                return msg
        raise AssertionError(f"no matching {kind} within {timeout} s")

    def command(self, command: int, *params: float, timeout: float = 30.0) -> MAVLinkMessage:
        """Send a COMMAND_LONG to the vehicle and wait for its COMMAND_ACK."""
        padded = (list(params) + [0.0] * 7)[:7]
        self.conn.mav.command_long_send(1, 1, command, 0, *padded)
        return self.wait("COMMAND_ACK", lambda m: m.command == command, timeout)

    def close(self) -> None:
        self.conn.close()
