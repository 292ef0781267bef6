"""Hostile frames on the CAN bus: any id, any length, remote, error, extended and FD frames, a bus that fails.

Through python-can's virtual bus into :class:`CanReader`: it never raises, counts every frame (none is
lost, however many arrive in one tick), and the blackboard never holds a switch position a switch does
not have, nor a stick, knob or state outside the protocol's range.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import can
import py_trees
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.io.can.agilex import CONTROL_MODES, FAULT_BITS, KNOWN_IDS, STICK_MAX, STICK_MIN, VEHICLE_STATES, RcState
from executive.io.can.reader import CanReader
from executive.testing import VirtualCan
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.state import SwitchPosition

FUZZ = settings(derandomize=True, deadline=None, max_examples=100, suppress_health_check=[HealthCheck.too_slow])
UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def bb(key: str) -> Any:
    return py_trees.blackboard.Blackboard.get(key)


def message(arbitration_id: int, data: bytes, extended: bool, remote: bool, error: bool, fd: bool, dlc: int | None) -> can.Message:
    """Any frame, consistent or not (check=False: what a driver or a replayed log may hand over)."""
    return can.Message(
        arbitration_id=arbitration_id,
        data=data,
        is_extended_id=extended,
        is_remote_frame=remote,
        is_error_frame=error,
        is_fd=fd,
        dlc=dlc,
        check=False,
    )


#: An AgileX frame with any 8 bytes: decoded, in range or not.
AGILEX = st.builds(
    lambda i, d: message(i, d, False, False, False, False, None), st.sampled_from(sorted(KNOWN_IDS)), st.binary(min_size=8, max_size=8)
)
#: Anything at all.
ANY = st.builds(
    message,
    st.one_of(st.sampled_from(sorted(KNOWN_IDS)), st.integers(0, 0x7FF), st.integers(0, 0x1FFFFFFF), st.sampled_from([-1, 2**32])),
    st.binary(max_size=64),
    st.booleans(),
    st.booleans(),
    st.booleans(),
    st.booleans(),
    st.none() | st.integers(0, 15),
)
FRAMES = st.lists(st.one_of(AGILEX, AGILEX, ANY), max_size=25)


class ReaderOnBus(VirtualCan):
    """A CAN reader (RC on) on our end of a fresh in-memory bus, on a clean blackboard, ticked by hand; the base's end sends."""

    def __init__(self) -> None:
        super().__init__("hostile-can")
        blackboard.reset()
        self.clock = ManualClock(start=100.0)
        self.reader = CanReader(self.ours, self.clock, rc=True)

    def tick(self, frames: list[can.Message]) -> int:
        for frame in frames:
            self.base.send(frame)
        self.clock.advance(0.1)
        return self.reader.drain()


@pytest.fixture
def reader_on_bus() -> Iterator[ReaderOnBus]:
    with ReaderOnBus() as r:
        yield r


def assert_sane() -> None:
    """Switches only in positions they have, sticks and knob in [-100, 100], states the protocol names, finite numbers."""
    if (switches := bb("/rc/switches")) is not None:
        assert switches.swa in (UP, DOWN) and switches.swd in (UP, DOWN), switches  # two-position switches
        assert switches.swb in (UP, MIDDLE, DOWN) and switches.swc in (UP, MIDDLE, DOWN), switches
        assert isinstance(switches.knob, int) and STICK_MIN <= switches.knob <= STICK_MAX, switches
    if (sticks := bb("/rc/sticks")) is not None:
        assert all(STICK_MIN <= v <= STICK_MAX for v in (sticks.right_lr, sticks.right_ud, sticks.left_lr, sticks.left_ud)), sticks
    if (system := bb("/base/system")) is not None:
        assert system.vehicle_state in VEHICLE_STATES.values() and system.control_mode in CONTROL_MODES.values(), system
        assert math.isfinite(system.battery_v) and system.battery_v >= 0.0 and 0 <= system.fault_code <= 0xFFFF, system
    known_faults = set(FAULT_BITS.values()) | {f"BIT{bit}" for bit in range(16)}
    assert set(bb("/base/faults")) <= known_faults
    for key in ("/base/motion", "/base/odometry"):
        if (value := bb(key)) is not None:
            assert all(math.isfinite(v) for v in (value.time, *(getattr(value, f) for f in value.__slots__))), value
    stats = (bb("/base/frames"), bb("/base/bad_frames"), bb("/base/other_frames"))
    assert all(isinstance(n, int) and n >= 0 for n in stats) and stats[1] + stats[2] <= stats[0], stats


@FUZZ
@given(ticks=st.lists(FRAMES, min_size=1, max_size=5))
def test_random_frames_never_raise_nor_become_out_of_range_facts(ticks: list[list[can.Message]]) -> None:
    """Any mixture of AgileX frames with random payloads and frames of any kind at all; every frame counted."""
    with ReaderOnBus() as rig:
        sent = 0
        for frames in ticks:
            assert rig.tick(frames) == len(frames)
            sent += len(frames)
            assert_sane()
        assert rig.reader.stats.frames == sent
        assert bb("/base/frames") == sent or sent == 0


@FUZZ
@given(data=st.binary(min_size=8, max_size=8), junk=st.lists(ANY, max_size=5))
def test_an_out_of_range_rc_frame_never_moves_a_switch(data: bytes, junk: list[can.Message]) -> None:
    """A valid 0x241 sets the switches; any 0x241 whose content is out of range (and any junk) leaves them as they were."""
    with ReaderOnBus() as rig:
        rig.tick([RcState(UP, MIDDLE, DOWN, DOWN, 10, -10, 20, -20, 50, 1).encode()])
        before = (bb("/rc/switches"), bb("/rc/sticks"))
        frame = RcState.from_data(data)
        assert frame is not None
        rig.tick([message(0x241, data, False, False, False, False, None), *junk])
        assert_sane()
        if not frame.valid and all(RcState.from_data(bytes(m.data)) is None or m.arbitration_id != 0x241 or m.is_extended_id for m in junk):
            assert (bb("/rc/switches"), bb("/rc/sticks")) == before


class FlakyBus(can.BusABC):
    """A bus whose ``recv`` fails (each way a driver can) on the calls listed, and otherwise reads the virtual bus."""

    def __init__(self, inner: can.BusABC, failures: dict[int, Exception]) -> None:
        self._inner = inner
        self._failures = failures
        self._calls = 0
        self.channel_info = "flaky"

    def recv(self, timeout: float | None = None) -> can.Message | None:
        self._calls += 1
        if self._calls in self._failures:
            raise self._failures[self._calls]
        return self._inner.recv(timeout)

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._inner.send(msg, timeout)

    def shutdown(self) -> None:
        self._inner.shutdown()


FAILURES = st.sampled_from([can.CanOperationError("bus off"), OSError(100, "Network is down"), ValueError("bad frame"), RuntimeError("driver")])


@FUZZ
@given(frames=st.lists(AGILEX, min_size=1, max_size=20), failures=st.dictionaries(st.integers(1, 25), FAILURES, max_size=5))
def test_a_failing_bus_loses_no_frame(frames: list[can.Message], failures: dict[int, Exception]) -> None:
    """recv raising now and then: counted as bus errors, never raised; every frame still arrives on a later tick."""
    with ReaderOnBus() as rig:
        rig.reader = CanReader(FlakyBus(rig.ours, failures), rig.clock, rc=True)
        for frame in frames:
            rig.base.send(frame)
        received = 0
        for _ in range(len(failures) + 1):
            rig.clock.advance(0.1)
            received += rig.reader.drain()
            assert_sane()
        assert (received, rig.reader.stats.frames, rig.reader.bus_errors) == (len(frames), len(frames), bb("/base/bus_errors"))
        assert rig.reader.bus_errors <= len(failures)


def test_a_storm_of_frames_is_read_over_several_ticks(reader_on_bus: ReaderOnBus) -> None:
    """More frames in one tick than a drain takes: the rest are read on the next tick, none is lost."""
    rig = reader_on_bus
    frames = [RcState(UP, MIDDLE, DOWN, UP, 0, 0, 0, 0, 0, i % 256).encode() for i in range(10_050)]
    assert rig.tick(frames) == 10_000
    assert rig.tick([]) == 50
    assert (bb("/base/frames"), bb("/base/bad_frames"), bb("/base/other_frames")) == (10_050, 0, 0)
