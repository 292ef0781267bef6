"""Opening a bus from IFACE:CHANNEL: what is a usage error, what is a bus that will not open."""

from __future__ import annotations

import pytest

from executive.io.can.bus import CanOpenError, CanSpecError, open_can, parse_spec


@pytest.mark.parametrize(
    ("spec", "parsed"),
    [
        ("socketcan:can0", ("socketcan", "can0")),
        ("virtual:test", ("virtual", "test")),
        ("slcan:/dev/ttyACM0@115200", ("slcan", "/dev/ttyACM0@115200")),
        ("PCAN:PCAN_USBBUS1", ("pcan", "PCAN_USBBUS1")),
        ("udp_multicast:239.74.163.2", ("udp_multicast", "239.74.163.2")),
    ],
)
def test_parse_spec(spec: str, parsed: tuple[str, str]) -> None:
    assert parse_spec(spec) == parsed


@pytest.mark.parametrize(
    ("spec", "why"),
    [("can0", "expected IFACE:CHANNEL"), (":can0", "expected"), ("socketcan:", "expected"), ("cann:can0", "unknown CAN interface 'cann'")],
)
def test_bad_specs_are_usage_errors(spec: str, why: str) -> None:
    with pytest.raises(CanSpecError, match=why):
        open_can(spec)


def test_a_bus_that_will_not_open_names_the_interface() -> None:
    with pytest.raises(CanOpenError, match=r"^cannot open CAN bus slcan:/nonexistent/tty0: "):
        open_can("slcan:/nonexistent/tty0")


def test_a_virtual_bus_opens() -> None:
    bus = open_can("virtual:test-bus-opens")
    try:
        assert bus.channel_info == "Virtual bus channel test-bus-opens"
    finally:
        bus.shutdown()
