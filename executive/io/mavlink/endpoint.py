"""MAVLink connection strings (``--mavlink``, ``--gcs``): checked before anything is opened, and what opening one can say.

pymavlink takes almost any text: ``foo://bar`` becomes a UDP socket on port "//bar" (a
ValueError deep inside), a bad port a traceback. Here a string is one of the forms below, or it
is refused with what is wrong (:class:`BadEndpoint`); one that is well formed but cannot be
opened (nothing listening, no such serial device, an address in use) is :class:`Unreachable`.
"""

from __future__ import annotations

import os
import re

#: Kinds of endpoint written ``KIND:HOST:PORT``; ``in`` kinds listen (port 0: any free one).
NETWORK_KINDS = {"udpin": "listen", "udp": "listen", "tcpin": "listen", "udpout": "send", "udpbcast": "send", "tcp": "connect"}
FORMS = "udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT, udpbcast:HOST:PORT, or a serial device /dev/ttyACM0[,BAUD]"
_SERIAL = re.compile(r"^(/|COM\d|\\\\\.\\)")  # /dev/ttyUSB0, /dev/serial/by-id/..., COM3, \\.\COM10


class BadEndpoint(ValueError):
    """A connection string that is not one: says what is wrong and the forms that are."""


class Unreachable(OSError):
    """A well-formed endpoint that could not be opened: nothing listening, no such device, the port taken."""


def check_endpoint(url: str) -> None:
    """Raise :class:`BadEndpoint` unless ``url`` is ``KIND:HOST:PORT`` (a kind of NETWORK_KINDS) or a serial device[,BAUD]."""
    if _SERIAL.match(url):
        device, comma, baud = url.partition(",")
        if not device.strip() or device.endswith("/"):
            raise BadEndpoint(f"{url}: no serial device named ({FORMS})")
        if comma and not (baud.isdigit() and int(baud) > 0):
            raise BadEndpoint(f"{url}: baud rate {baud!r} is not a positive whole number (e.g. /dev/ttyACM0,115200)")
        return
    kind, colon, rest = url.partition(":")
    if not colon or kind not in NETWORK_KINDS:
        raise BadEndpoint(f"{url}: unknown kind of endpoint {kind!r}; use {FORMS}")
    host, colon, port = rest.rpartition(":")
    if not colon or not host:
        raise BadEndpoint(f"{url}: {kind} needs HOST:PORT, e.g. {kind}:127.0.0.1:14550")
    lowest = 0 if NETWORK_KINDS[kind] == "listen" else 1
    if not (port.isdigit() and lowest <= int(port) <= 65535):
        raise BadEndpoint(f"{url}: port {port!r} is not a number {lowest}-65535")


def is_serial(url: str) -> bool:
    """``url`` names a serial device (``/dev/ttyACM0[,BAUD]``, ``COM3``), not a network endpoint."""
    return bool(_SERIAL.match(url))


def unreachable(url: str, error: OSError) -> Unreachable:
    """The error to raise when opening ``url`` failed with ``error``, saying what was tried."""
    # pyserial's strerror repeats the device and the errno: the errno's own text is enough
    reason = os.strerror(error.errno) if isinstance(error.errno, int) and error.errno > 0 else error.strerror or str(error)
    if _SERIAL.match(url):
        device = url.partition(",")[0]
        return Unreachable(f"{url}: cannot open the serial device {device}: {reason}")
    kind, _, address = url.partition(":")
    doing = {"listen": "cannot listen on", "send": "cannot send to", "connect": "cannot connect to"}.get(NETWORK_KINDS.get(kind, ""), "cannot open")
    hint = " (is the autopilot, SITL or router listening there?)" if kind == "tcp" else ""
    return Unreachable(f"{url}: {doing} {address}: {reason}{hint}")


__all__ = ["BadEndpoint", "Unreachable", "check_endpoint", "is_serial", "unreachable"]
