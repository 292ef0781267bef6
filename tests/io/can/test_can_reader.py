"""The CAN reader on python-can's virtual bus: switches and the base's state reach the blackboard; a frozen 0x241 counter makes RC stale."""

from __future__ import annotations

import can
import py_trees
import pytest

from executive.io.can.agilex import MotionState, Odometry, RcState, SystemState
from executive.io.can.reader import CanReader
from executive.io.can.state import BaseMotion, BaseOdometry, BaseSystem, RcSticks
from executive.mission.model import RcConfig
from executive.sensing.rc import RcReader
from executive.world.clock import ManualClock
from executive.world.state import RcSwitches, SwitchPosition

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def bb(key: str) -> object:
    return py_trees.blackboard.Blackboard.get(key)


def rc_frame(counter: int, swc: SwitchPosition = MIDDLE, left_lr: int = 0) -> can.Message:
    return RcState(UP, UP, swc, DOWN, 0, 0, left_lr, 0, 0, counter).encode()


def test_switches_sticks_and_the_base_reach_the_blackboard(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader = CanReader(executive, clock)
    base.send(can.Message(arbitration_id=0x241, data=bytes.fromhex("A60000B00000007E"), is_extended_id=False))  # the SPEC's frame
    base.send(SystemState(0, 1, 486, 0x0000, 7).encode())
    base.send(MotionState(500, -100).encode())
    base.send(Odometry(1500, 1520).encode())
    assert reader.drain() == 4
    assert bb("/rc/switches") == RcSwitches(UP, MIDDLE, UP, UP, 0, 100.0)
    assert bb("/rc/sticks") == RcSticks(0, 0, -80, 0, 100.0)
    assert bb("/rc/last_update") == 100.0
    assert bb("/base/system") == BaseSystem("NORMAL", "CAN", 48.6, 0, (), 100.0)
    assert bb("/base/motion") == BaseMotion(0.5, -0.1, 100.0)
    assert bb("/base/odometry") == BaseOdometry(1.5, 1.52, 100.0)
    assert (bb("/base/up"), bb("/base/last_update"), bb("/base/frames"), bb("/base/bad_frames")) == (True, 100.0, 4, 0)


def test_switches_are_rewritten_only_when_they_move(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader = CanReader(executive, clock)
    base.send(rc_frame(1))
    reader.drain()
    first = bb("/rc/switches")
    clock.advance(0.1)
    base.send(rc_frame(2))
    reader.drain()
    assert bb("/rc/switches") is first
    assert bb("/rc/last_update") == pytest.approx(100.1)
    clock.advance(0.1)
    base.send(rc_frame(3, swc=UP))
    reader.drain()
    assert bb("/rc/switches") == RcSwitches(UP, UP, UP, DOWN, 0, pytest.approx(100.2))


def drive_rc(reader: CanReader, rc: RcReader, base: can.BusABC, clock: ManualClock, counters: list[int], dt: float = 0.02) -> list[bool]:
    """One 0x241 frame per ``dt`` with each counter, a tick each (the CAN reader drains, then the RC reader judges); /rc/fresh after each."""
    fresh = []
    for counter in counters:
        clock.advance(dt)
        base.send(rc_frame(counter))
        reader.drain()
        rc.service()
        fresh.append(bb("/rc/fresh"))
    return fresh


def test_a_frozen_counter_makes_rc_stale_within_the_fresh_timeout(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader, rc = CanReader(executive, clock), RcReader(RcConfig(source="can", fresh_timeout_s=0.5), clock)
    assert drive_rc(reader, rc, base, clock, [0xFE, 0xFF, 0x00, 0x01]) == [True] * 4  # the counter wraps: still moving
    frozen_since = clock.now()
    fresh = drive_rc(reader, rc, base, clock, [0x01] * 40)  # the transmitter is gone: the base repeats its last frame
    stale_at = frozen_since + 0.02 * (fresh.index(False) + 1)
    assert all(fresh[: fresh.index(False)]) and not any(fresh[fresh.index(False) :])
    assert stale_at - frozen_since == pytest.approx(0.52)  # the first tick past rc.fresh_timeout_s
    assert bb("/rc/stale_reason") == "no RC report within 0.5 s"
    assert bb("/base/rc_counter_repeats") == 40
    assert bb("/base/up") is True  # the base itself still talks
    assert drive_rc(reader, rc, base, clock, [0x02]) == [True]  # the counter moves again


def test_no_frame_at_all_makes_rc_stale_too(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader, rc = CanReader(executive, clock, base_timeout_s=0.3), RcReader(RcConfig(source="can", fresh_timeout_s=0.5), clock)
    assert drive_rc(reader, rc, base, clock, [1, 2, 3]) == [True] * 3
    for _ in range(14):  # 280 ms without a frame
        clock.advance(0.02)
        reader.drain()
        rc.service()
    assert (bb("/rc/fresh"), bb("/base/up")) == (True, True)
    for _ in range(3):
        clock.advance(0.02)
        reader.drain()
        rc.service()
    assert bb("/base/up") is False  # 340 ms > base_timeout_s
    for _ in range(9):
        clock.advance(0.02)
        reader.drain()
        rc.service()
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (False, "no RC report within 0.5 s")  # 520 ms


def test_a_counting_frame_does_not_count_while_the_base_reports_rc_signal_loss(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader = CanReader(executive, clock)
    base.send(rc_frame(1))
    reader.drain()
    clock.advance(0.1)
    base.send(SystemState(0, 0, 486, 0x0004, 1).encode())
    base.send(rc_frame(2))  # RC mode after a signal loss: the base zeroes the sticks but keeps counting
    reader.drain()
    assert bb("/rc/last_update") == 100.0
    assert bb("/base/faults") == ("RC_SIGNAL_LOSS",)
    clock.advance(0.1)
    base.send(SystemState(0, 0, 486, 0x0000, 2).encode())
    base.send(rc_frame(3))
    reader.drain()
    assert bb("/rc/last_update") == pytest.approx(100.2)
    assert bb("/base/faults") == ()


def test_bad_and_foreign_frames_are_counted_and_never_used(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader = CanReader(executive, clock)
    base.send(can.Message(arbitration_id=0x241, data=b"\xa6\x00", is_extended_id=False))  # too short
    base.send(can.Message(arbitration_id=0x241, data=bytes.fromhex("000000000000007E"), is_extended_id=False))  # no switch positions
    base.send(can.Message(arbitration_id=0x211, data=bytes.fromhex("09000000000000FF"), is_extended_id=False))  # no vehicle state 9
    base.send(can.Message(arbitration_id=0x18FF50E5, data=b"\x01\x02", is_extended_id=True))  # a J1939 device on the same bus
    base.send(can.Message(arbitration_id=0x251, data=bytes(8), is_extended_id=False))  # an AgileX frame the executive does not read
    assert reader.drain() == 5
    assert (bb("/base/frames"), bb("/base/bad_frames"), bb("/base/other_frames")) == (5, 3, 2)
    assert (bb("/rc/switches"), bb("/rc/last_update"), bb("/base/system"), bb("/base/up")) == (None, None, None, False)


def test_without_rc_it_leaves_the_rc_keys_alone(can_buses, clock: ManualClock) -> None:
    base, executive = can_buses
    reader = CanReader(executive, clock, rc=False)
    base.send(rc_frame(1))
    reader.drain()
    assert (bb("/rc/switches"), bb("/rc/last_update"), bb("/base/up")) == (None, None, True)


class BrokenBus(can.BusABC):
    """A bus whose device went away: every receive fails."""

    def __init__(self) -> None:
        super().__init__(channel="broken")

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        raise can.CanOperationError("Network is down [Error Code 100]")

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        raise can.CanOperationError("Network is down [Error Code 100]")


def test_a_bus_error_is_counted_not_raised(clock: ManualClock) -> None:
    with BrokenBus() as broken:
        reader = CanReader(broken, clock)
        assert reader.drain() == 0
        assert reader.drain() == 0
    assert bb("/base/bus_errors") == 2


def test_the_base_found_and_lost_is_said_and_its_state_is_in_the_status(can_buses, clock: ManualClock, caplog) -> None:
    """Issue 43: `run --can` said nothing of the base it found, and the status had nothing of it."""
    import logging

    from executive.operator.status import StatusSource, status_line

    caplog.set_level(logging.INFO, logger="executive.io.can.reader")
    base, executive = can_buses
    reader = CanReader(executive, clock)
    base.send(SystemState(0, 1, 486, 0x0000, 7).encode())
    reader.drain()
    status = StatusSource("test").snapshot()
    assert status["base"] == {"up": True, "state": "NORMAL", "mode": "CAN", "battery_v": 48.6}
    assert "base NORMAL CAN 48.6V" in status_line(status | {"state": "RUNNING", "leg": 1, "legs": 1, "distance_m": None})
    clock.advance(reader.base_timeout_s + 0.5)
    reader.drain()
    said = [r.getMessage() for r in caplog.records]
    assert said[0] == "AgileX base heard on the CAN bus: NORMAL, CAN command mode, 48.6 V"
    assert said[1].startswith("AgileX base not heard on the CAN bus for ")
    assert StatusSource("test").snapshot()["base"]["up"] is False
