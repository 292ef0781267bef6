"""Whether this run has commanded the vehicle: what it sent that could change it, as opposed to who it is and what it wants to hear.

The make-safe acts only on what this run started: a run refused before it armed, set a mode, sent a
target or a route, has nothing to undo, and commanding the safe mode then would be a change of our
own (real ArduPlane, on the ground and disarmed, was put in QLOITER by a pre-flight that never armed).
"""

from __future__ import annotations

from collections.abc import Callable

from executive.io.mavlink.link import Link
from executive.world.dialect import MAVLinkMessage, mavlink

#: What the executive says that changes nothing on the vehicle: who it is, what to stream, the parameters it reads, its
#: reports, acks of a ground station's commands, the obstacle distances it forwards. Anything else counts as commanding.
HARMLESS = frozenset({
    "HEARTBEAT", "REQUEST_DATA_STREAM", "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST", "STATUSTEXT", "NAMED_VALUE_FLOAT",
    "COMMAND_ACK", "OBSTACLE_DISTANCE", "TIMESYNC", "MISSION_REQUEST_LIST", "MISSION_REQUEST_INT", "MISSION_ACK",
})  # fmt: skip
#: Commands that only ask for messages.
HARMLESS_COMMANDS = frozenset({mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAV_CMD_REQUEST_MESSAGE})


def commands_the_vehicle(msg: MAVLinkMessage) -> bool:
    """``msg`` could change the vehicle: a command (but asking for messages), a mode, a target, a route, a parameter set."""
    kind = msg.get_type()
    if kind in ("COMMAND_LONG", "COMMAND_INT"):
        return msg.command not in HARMLESS_COMMANDS
    return kind not in HARMLESS


class CommandWatch:
    """A link that notes the first message sent that commands the vehicle (:attr:`commanded`), and passes everything on.

    Every message received and sent on the autopilot's link passes here: :attr:`listeners` hear each
    (``in`` or ``out``, the message), on the thread that received or sent it (the MCAP recording's MAVLink channels).
    """

    def __init__(self, link: Link) -> None:
        self.link = link
        #: The first message sent that could change the vehicle (its type); None: none yet.
        self.commanded: str | None = None
        self.listeners: list[Callable[[str, MAVLinkMessage], object]] = []

    def recv(self) -> MAVLinkMessage | None:
        msg = self.link.recv()
        if msg is not None and self.listeners:
            for listener in self.listeners:
                listener("in", msg)
        return msg

    def send(self, msg: MAVLinkMessage) -> None:
        if self.commanded is None and commands_the_vehicle(msg):
            self.commanded = msg.get_type()
        self.link.send(msg)
        for listener in self.listeners:
            listener("out", msg)

    def close(self) -> None:
        self.link.close()

    # The reader asks these two every tick, and most links have neither: through __getattr__ each miss raised twice.
    @property
    def unsigned_dropped(self) -> int:
        """The link's unsigned packets dropped while signing is on (0: a link that does not sign)."""
        return getattr(self.link, "unsigned_dropped", 0)

    @property
    def device_lost(self) -> str | None:
        """Why the link's serial device is gone (None: it is there, or the link has none)."""
        return getattr(self.link, "device_lost", None)

    def __getattr__(self, name: str) -> object:  # the link's own other attributes (url...)
        return getattr(self.link, name)
