"""Opening a CAN bus from an ``IFACE:CHANNEL`` text, as ``--can`` and ``executive can monitor`` take it.

Examples: ``socketcan:can0``, ``virtual:test``, ``slcan:/dev/ttyACM0@115200`` (python-can's slcan
channel: the serial port, ``@`` its baud rate), ``pcan:PCAN_USBBUS1``. The CAN bit rate is 500 kbit/s
(AgileX) unless told otherwise; socketcan takes it from ``ip link set can0 up type can bitrate 500000``
instead.
"""

from __future__ import annotations

import can

DEFAULT_BITRATE = 500_000


class CanSpecError(ValueError):
    """An ``IFACE:CHANNEL`` text that does not name a bus (a usage error)."""


class CanOpenError(OSError):
    """python-can could not open the bus (no such device, driver missing, ...)."""


def parse_spec(spec: str) -> tuple[str, str]:
    """(interface, channel) of ``IFACE:CHANNEL``; CanSpecError for anything else or an interface python-can does not know."""
    interface, sep, channel = spec.partition(":")
    interface = interface.strip().lower()
    if not sep or not interface or not channel:
        raise CanSpecError(f"{spec!r}: expected IFACE:CHANNEL, e.g. socketcan:can0, virtual:test, slcan:/dev/ttyACM0@115200")
    if interface not in can.VALID_INTERFACES:
        known = ", ".join(sorted(can.VALID_INTERFACES))
        raise CanSpecError(f"{spec!r}: unknown CAN interface {interface!r} (python-can knows: {known})")
    return interface, channel


def open_can(spec: str, *, bitrate: int = DEFAULT_BITRATE) -> can.BusABC:
    """The bus ``spec`` names, opened; CanSpecError for a bad text, CanOpenError when python-can refuses."""
    interface, channel = parse_spec(spec)
    try:
        return can.Bus(interface=interface, channel=channel, bitrate=bitrate)
    except can.CanInterfaceNotImplementedError as exc:
        raise CanOpenError(f"CAN interface {interface} is not available here: {exc}") from exc
    except Exception as exc:  # drivers raise anything (OSError, CanError, even NameError when a vendor library is missing)
        raise CanOpenError(f"cannot open CAN bus {interface}:{channel}: {exc}") from exc
