"""The drive bridge: PWM -> motion command numbers, 50 Hz cadence on a manual clock, zero motion when it must not drive, exact bytes."""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator

import can
import py_trees
import pytest

from executive.io.can.agilex import ControlModeSelect, MotionCommand, decode
from executive.io.can.drive import DriveBridge, DriveConfig, motion_from_tracks, track_throttle
from executive.io.can.state import DriveStatus
from executive.testing import Vehicle
from executive.world.clock import ManualClock, ScaledClock
from tests_support import runqueue_wait_s


class RecordingBus(can.BusABC):
    """Keeps what is sent, with the clock time it was sent at."""

    def __init__(self, clock: ManualClock) -> None:
        super().__init__(channel="recording")
        self.clock = clock
        self.sent: list[tuple[float, can.Message]] = []

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self.sent.append((self.clock.now(), msg))

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        return None, False

    def commands(self) -> list[MotionCommand]:
        return [decode(m) for _, m in self.sent if m.arbitration_id == 0x111]  # type: ignore[misc]


def servos(left_us: int, right_us: int) -> dict[str, object]:
    """The servo output tuple the MAVLink reader writes per SERVO_OUTPUT_RAW: the tracks on SERVO1 and SERVO3."""
    return {"vehicle__servo_outputs": tuple([left_us, 0, right_us] + [0] * 13)}


@pytest.fixture
def bus(clock: ManualClock) -> Iterator[RecordingBus]:
    with RecordingBus(clock) as recording:
        yield recording


@pytest.mark.parametrize(
    ("pwm", "throttle"),
    [(1500, 0.0), (2100, 1.0), (900, -1.0), (1800, 0.5), (1200, -0.5), (2300, 1.0), (700, -1.0), (0, None), (None, None), (3000, None)],
)
def test_track_throttle(pwm: int | None, throttle: float | None) -> None:
    assert track_throttle(pwm) == (pytest.approx(throttle) if throttle is not None else None)


@pytest.mark.parametrize(
    ("left", "right", "linear_mm_s", "angular_mrad_s"),
    [
        (0.0, 0.0, 0, 0),
        (1.0, 1.0, 1000, 0),  # full ahead on both tracks: 1 m/s
        (-0.5, -0.5, -500, 0),
        (-1.0, 1.0, 0, 2000),  # pivot left (right track forward): +2 rad/s, counter-clockwise
        (0.5, 1.0, 750, 500),
        (1.0, 0.5, 750, -500),
    ],
)
def test_mapping_with_the_default_speed_factors(left: float, right: float, linear_mm_s: int, angular_mrad_s: int) -> None:
    assert motion_from_tracks(left, right, DriveConfig()) == MotionCommand(linear_mm_s, angular_mrad_s)


def test_speed_factors_scale_each_part() -> None:
    config = DriveConfig(linear_m_s=1.5, angular_rad_s=0.8)
    assert motion_from_tracks(0.5, 1.0, config) == MotionCommand(1125, 400)


@pytest.mark.parametrize("bad", [{"linear_m_s": -1.0}, {"linear_m_s": 40.0}, {"angular_rad_s": 20.0}, {"rate_hz": 0.0}, {"servo_timeout_s": 0.0}])
def test_configs_it_cannot_send_are_refused(bad: dict[str, float]) -> None:
    with pytest.raises(ValueError):
        DriveConfig(**bad)


def test_it_forwards_the_autopilot_outputs_with_exact_bytes(bus: RecordingBus, clock: ManualClock, vehicle: Vehicle) -> None:
    bridge = DriveBridge(bus, clock)
    bridge.in_control = True
    vehicle.set(vehicle__armed=True)
    vehicle.set(**servos(1800, 2100))  # left 0.5, right 1.0
    assert bridge.service()
    (t1, select), (t2, command) = bus.sent
    assert (t1, t2) == (100.0, 100.0)
    assert (select.arbitration_id, select.is_extended_id, bytes(select.data)) == (0x421, False, bytes.fromhex("01 00 00 00 00 00 00 00"))
    assert (command.arbitration_id, command.is_extended_id, bytes(command.data)) == (0x111, False, bytes.fromhex("02 EE 01 F4 00 00 00 00"))
    assert py_trees.blackboard.Blackboard.get("/base/drive") == DriveStatus(0.75, 0.5, "", 100.0)


def test_50_hz_on_the_injected_clock(bus: RecordingBus, clock: ManualClock, vehicle: Vehicle) -> None:
    bridge = DriveBridge(bus, clock)
    for _ in range(1000):  # called every millisecond for one second
        bridge.service()
        clock.advance(0.001)
    times = [t for t, m in bus.sent if m.arbitration_id == 0x111]
    assert len(times) == 50
    assert [round(b - a, 6) for a, b in itertools.pairwise(times)] == [0.02] * 49
    assert [m.arbitration_id for _, m in bus.sent][:4] == [0x421, 0x111, 0x421, 0x111]  # a mode select before every command


def test_a_caller_off_the_beat_still_gets_50_per_second(bus: RecordingBus, clock: ManualClock) -> None:
    bridge = DriveBridge(bus, clock)
    for _ in range(143):  # every 7 ms for 1 s: each command goes up to 7 ms late, the cadence does not drift
        bridge.service()
        clock.advance(0.007)
    assert len(bus.commands()) == 50


def test_a_slow_caller_gets_one_command_per_call_and_no_burst(bus: RecordingBus, clock: ManualClock) -> None:
    bridge = DriveBridge(bus, clock)
    assert bridge.service()
    assert not bridge.service()  # not due yet
    assert bridge.next_due == pytest.approx(100.02)
    clock.advance(0.1)  # a 100 ms stall
    assert bridge.service()
    assert not bridge.service()
    assert bridge.next_due == pytest.approx(100.12)
    assert len(bus.commands()) == 2


def drive(bridge: DriveBridge, clock: ManualClock, seconds: float) -> None:
    for _ in range(round(seconds / 0.02)):
        bridge.service()
        clock.advance(0.02)


def test_zero_when_not_in_control_disarmed_or_stale(bus: RecordingBus, clock: ManualClock, vehicle: Vehicle) -> None:
    bridge = DriveBridge(bus, clock, DriveConfig(servo_timeout_s=0.5))
    vehicle.set(vehicle__armed=True)
    vehicle.set(**servos(2100, 2100))
    bridge.service()
    assert bus.commands()[-1] == MotionCommand(0, 0)
    assert py_trees.blackboard.Blackboard.get("/base/drive").reason == "executive not in control"

    bridge.in_control = True
    clock.advance(0.02)
    vehicle.set(**servos(2100, 2100))
    bridge.service()
    assert bus.commands()[-1] == MotionCommand(1000, 0)

    vehicle.set(vehicle__armed=False)
    clock.advance(0.02)
    bridge.service()
    assert bus.commands()[-1] == MotionCommand(0, 0)
    assert py_trees.blackboard.Blackboard.get("/base/drive").reason == "disarmed"

    vehicle.set(vehicle__armed=True)
    vehicle.set(**servos(2100, 2100))  # a report every 0.2 s (5 Hz) keeps it driving
    for _ in range(5):
        drive(bridge, clock, 0.2)
        vehicle.set(**servos(2100, 2100))
    assert set(bus.commands()[-45:]) == {MotionCommand(1000, 0)}

    drive(bridge, clock, 0.5)  # the same report for 0.5 s: still within servo_timeout_s
    assert bus.commands()[-1] == MotionCommand(1000, 0)
    drive(bridge, clock, 0.04)  # the reports stopped: zero
    assert bus.commands()[-1] == MotionCommand(0, 0)
    assert py_trees.blackboard.Blackboard.get("/base/drive").reason == "servo outputs older than 0.5 s"


def test_zero_without_servo_outputs_or_with_an_unused_output(bus: RecordingBus, clock: ManualClock, vehicle: Vehicle) -> None:
    bridge = DriveBridge(bus, clock)
    bridge.in_control = True
    vehicle.set(vehicle__armed=True)
    bridge.service()
    assert py_trees.blackboard.Blackboard.get("/base/drive") == DriveStatus(0.0, 0.0, "no servo outputs yet", 100.0)
    clock.advance(0.02)
    vehicle.set(**servos(1700, 0))  # SERVO3 not configured
    bridge.service()
    assert bus.commands()[-1] == MotionCommand(0, 0)
    assert py_trees.blackboard.Blackboard.get("/base/drive").reason == "no usable servo 3 output"


def test_send_errors_are_counted_not_raised(clock: ManualClock) -> None:
    class FullBus(RecordingBus):
        def send(self, msg: can.Message, timeout: float | None = None) -> None:
            raise can.CanOperationError("No buffer space available [Error Code 105]")

    with FullBus(clock) as full:
        bridge = DriveBridge(full, clock)
        assert bridge.service()
        clock.advance(0.02)
        assert bridge.service()
    assert py_trees.blackboard.Blackboard.get("/base/send_errors") == 2
    assert bridge.sent == 0


def test_a_bridge_thread_on_a_virtual_bus_sends_at_about_50_hz(can_buses, vehicle: Vehicle) -> None:
    base, ours = can_buses
    clock = ScaledClock()
    bridge = DriveBridge(ours, clock)
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop,), daemon=True)
    thread.start()
    assert thread.native_id is not None
    waited = runqueue_wait_s(thread.native_id)
    received: list[can.Message] = []
    deadline = time.monotonic() + 30.0  # a hang guard
    while time.monotonic() < deadline and sum(m.arbitration_id == 0x111 for m in received) < 26:
        msg = base.recv(0.1)
        if msg is not None:
            received.append(msg)
    waited = runqueue_wait_s(thread.native_id) - waited  # what a busy machine delayed the bridge by (its cadence restarts after a stall)
    stop.set()
    thread.join(timeout=2.0)
    commands = [m for m in received if m.arbitration_id == 0x111]
    assert len(commands) >= 26
    assert decode(received[0]) == ControlModeSelect(1)
    span = commands[25].timestamp - commands[0].timestamp
    assert 0.4 <= span <= 0.75 + waited  # 25 periods of 20 ms (never a burst), plus what the bridge waited for a CPU
    assert not thread.is_alive()
