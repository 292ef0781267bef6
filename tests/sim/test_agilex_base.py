"""The simulated AgileX base on python-can's virtual bus: its frames, RC loss as the thesis found it, and the tracks obeying 0x111 in CAN mode."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import pytest

from executive.io.can.agilex import (
    CONTROL_MODE_CAN,
    CONTROL_MODE_RC,
    ControlModeSelect,
    MotionCommand,
    MotionState,
    Odometry,
    RcState,
    SystemState,
    decode,
)
from executive.io.can.drive import DriveConfig, motion_from_tracks, track_throttle
from executive.sim import SimServer
from executive.sim.agilex_base import SimulatedBase
from executive.sim.faults import FaultInjector, FaultPlan
from executive.testing import VirtualCan
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink as m
from executive.world.state import SwitchPosition

if TYPE_CHECKING:
    from sim_support import Gcs

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN
Command = tuple[float, float] | Callable[[], tuple[float, float]]


class BaseOnBus:
    """A simulated base on the far end of ``buses``, our end of it (:attr:`bus`), the autopilot stepped as the server steps it (100 Hz)."""

    def __init__(self, gcs: Gcs, buses: VirtualCan, faults: FaultInjector | None = None) -> None:
        self.gcs, self.ap, self.clock, self.faults = gcs, gcs.ap, gcs.clock, faults
        self.bus = buses.ours
        if faults is not None:
            faults.attach(self.ap)  # fault times count from here
        self.base = SimulatedBase(buses.base, self.clock, self.ap, faults=faults)
        self.frames: list[tuple[float, Any]] = []  # (time, decoded frame), everything the base sent

    def run(self, seconds: float, *, select: bool = False, command: Command | None = None) -> list[tuple[float, Any]]:
        """``seconds`` in 10 ms steps; after each, the executive sends a 0x421 (``select``) and a 0x111 (``command``). Returns the frames."""
        start = len(self.frames)
        for _ in range(round(seconds / 0.01)):
            self.clock.advance(0.01)
            if self.faults is not None:
                self.faults.update(self.ap)
            self.gcs.update()
            self.base.service()
            while (msg := self.bus.recv(0.0)) is not None:
                self.frames.append((self.clock.now(), decode(msg)))
            if select:
                self.bus.send(ControlModeSelect().encode())
            if command is not None:
                self.bus.send(MotionCommand.from_si(*(command() if callable(command) else command)).encode())
        return self.frames[start:]


def of(frames: list[tuple[float, Any]], kind: type) -> list[Any]:
    return [f for _, f in frames if isinstance(f, kind)]


@pytest.fixture
def base_on_bus(make_gcs: Callable[..., Gcs], can_buses: VirtualCan) -> Callable[..., BaseOnBus]:
    """``base_on_bus(faults)``: a Bunker's autopilot (EKF ready) and its base on :func:`can_buses`, with those faults."""

    def make(faults: list[dict[str, Any]] | None = None, ekf_ready: bool = True) -> BaseOnBus:
        gcs = make_gcs("bunker", ekf_ready=ekf_ready)
        injector = FaultInjector(FaultPlan.model_validate({"version": 1, "faults": faults}), gcs.clock) if faults else None
        return BaseOnBus(gcs, can_buses, injector)

    return make


def test_frame_rates_and_the_rolling_counter(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus()
    frames = r.run(1.0)
    rc, system = of(frames, RcState), of(frames, SystemState)
    assert (len(rc), len(system), len(of(frames, MotionState)), len(of(frames, Odometry))) == (50, 10, 50, 50)
    assert [f.counter for f in rc] == list(range(50))
    assert [f.counter for f in system] == list(range(10))
    assert {(f.vehicle_state, f.control_mode, f.fault_code) for f in system} == {(0, CONTROL_MODE_RC, 0)}
    assert system[-1].battery_v == pytest.approx(r.ap.battery_v, abs=0.06)  # the sim's battery, in 0.1 V
    r.run(2.56)  # 128 more: the counter wraps at 256
    r.run(2.6)
    assert [f.counter for f in of(r.frames, RcState)][254:258] == [254, 255, 0, 1]


def test_the_thesis_frame_byte_for_byte(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus()
    r.ap.rc_channels[3] = 1100  # left stick 80 % left
    r.ap.rc_channels[4:9] = [1000, 1500, 1000, 1000, 1500]  # SWA up, SWB middle, SWC up, SWD up, VRA centred
    r.run(2.54)  # frames 0..126
    frame = next(f for f in of(r.frames, RcState) if f.counter == 0x7E)
    assert bytes(frame.encode().data) == bytes.fromhex("A6 00 00 B0 00 00 00 7E")


def test_switches_sticks_and_knob_follow_the_transmitter(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus()
    r.ap.rc_channels[0:4] = [2000, 1250, 1500, 1900]  # right L/R, right U/D, left U/D (throttle), left L/R
    r.ap.rc_channels[4:9] = [2000, 2000, 1500, 1600, 1250]  # SWD at 1600 us: a two-way switch is up until 1700
    frame = of(r.run(0.02), RcState)[-1]
    assert (frame.swa, frame.swb, frame.swc, frame.swd) == (DOWN, DOWN, MIDDLE, UP)
    assert (frame.right_lr, frame.right_ud, frame.left_ud, frame.left_lr, frame.knob) == (100, -50, 0, 80, -50)


def test_rc_loss_repeats_the_last_frame_with_a_frozen_counter_and_no_fault_in_can_mode(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus([{"kind": "rc_loss", "at_s": 1.0, "for_s": 1.0}, {"kind": "rc_input", "at_s": 1.5, "channels": {7: 2000, 3: 2000}}])
    before = r.run(1.0, select=True)
    frozen = of(before, RcState)[-1]
    during = r.run(1.0, select=True)
    assert len(of(during, RcState)) == 50 and set(of(during, RcState)) == {frozen}  # SWC and the throttle moved meanwhile
    assert {(f.control_mode, f.fault_code) for f in of(during, SystemState)} == {(CONTROL_MODE_CAN, 0)}
    after = of(r.run(0.1, select=True), RcState)
    assert after[0].counter == (frozen.counter + 1) % 256 and (after[0].swc, after[0].left_ud) == (DOWN, 100)


def test_in_rc_mode_the_base_reports_the_rc_loss(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus([{"kind": "rc_loss", "at_s": 0.0, "for_s": 1.0}, {"kind": "battery_sag", "at_s": 0.0, "drop_v": 2.0}])
    system = of(r.run(1.0), SystemState)
    assert {(f.control_mode, f.fault_code) for f in system} == {(CONTROL_MODE_RC, 0x0004)}
    assert system[-1].battery_v == pytest.approx(r.ap.battery_v - 2.0, abs=0.06)


def test_motion_commands_drive_the_tracks_only_in_can_mode(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus()  # disarmed: the autopilot's outputs are neutral
    assert r.ap.armed is False
    frames = r.run(1.0, command=(0.5, 0.3))  # no 0x421: RC mode ignores them
    assert r.ap.vehicle.north_east_m == (0.0, 0.0) and r.base.drive_command is None
    assert of(frames, SystemState)[-1].control_mode == CONTROL_MODE_RC
    frames = r.run(2.0, select=True, command=(0.5, 0.3))
    assert r.base.control_mode == CONTROL_MODE_CAN and of(frames, SystemState)[-1].control_mode == CONTROL_MODE_CAN
    assert (r.ap.vehicle.speed_m_s, r.ap.vehicle.yaw_rate_rad_s) == pytest.approx((0.5, -0.3))  # counter-clockwise: heading decreases
    assert 300.0 < r.ap.vehicle.heading_deg < 340.0
    motion, odometry = of(frames, MotionState)[-1], of(frames, Odometry)[-1]
    assert (motion.linear_mm_s, motion.angular_mrad_s) == (500, 300)
    left, right = r.ap.vehicle.odometry_m
    assert right > left > 0.0 and (odometry.left_mm, odometry.right_mm) == pytest.approx((left * 1000, right * 1000), abs=30)
    assert r.ap.track_pwm == (1500, 1500)  # the autopilot has no part in it


def test_in_can_mode_the_autopilot_outputs_alone_move_nothing(base_on_bus: Callable[..., BaseOnBus]) -> None:
    """Armed in GUIDED with a target: the autopilot drives its outputs, but the tracks obey the base, told to stand still ..."""
    r = base_on_bus()
    r.run(0.1, select=True, command=(0.0, 0.0))
    assert r.gcs.arm() == m.MAV_RESULT_ACCEPTED and r.gcs.set_mode("GUIDED") == m.MAV_RESULT_ACCEPTED
    target = r.gcs.north(10.0)
    r.gcs.goto(*target)
    r.run(3.0, select=True, command=(0.0, 0.0))
    assert min(r.ap.track_pwm) > 1700
    assert r.ap.vehicle.distance_to(*r.ap.start) < 1e-6

    def bridge() -> tuple[float, float]:  # ... until they are forwarded as the drive bridge does
        left, right = (track_throttle(pwm) for pwm in r.ap.track_pwm)
        command = motion_from_tracks(left or 0.0, right or 0.0, DriveConfig())
        return command.linear_m_s, command.angular_rad_s

    r.run(20.0, select=True, command=bridge)
    # the shaped target ran ahead while the base stood still; the autopilot stops once it is within WP_RADIUS of it
    assert r.ap.vehicle.distance_to(*target) < r.ap.motion.radius_m


def test_the_base_stops_500_ms_after_the_last_command(base_on_bus: Callable[..., BaseOnBus]) -> None:
    r = base_on_bus()
    r.run(2.0, select=True, command=(0.5, 0.0))
    r.run(0.45, select=True)
    assert r.base.drive_command == (0.5, 0.0) and r.ap.vehicle.speed_m_s == pytest.approx(0.5)
    r.run(0.1, select=True)
    assert r.base.drive_command == (0.0, 0.0)
    r.run(0.5, select=True)
    assert r.ap.vehicle.speed_m_s == 0.0 and r.base.control_mode == CONTROL_MODE_CAN
    r.run(0.6)  # no 0x421 either: back to RC mode
    assert r.base.control_mode == CONTROL_MODE_RC and r.base.drive_command is None and r.ap.vehicle.base_command is None


def test_the_sim_server_services_a_base_for_the_bunker_only(can_buses: VirtualCan) -> None:
    clock = ManualClock()
    base_bus, bus = can_buses
    with pytest.raises(ValueError, match="needs the bunker"):
        SimServer("rover", clock=clock, can_bus=base_bus)
    server = SimServer("bunker", clock=clock, can_bus=base_bus)
    try:
        for _ in range(10):
            clock.advance(0.01)
            server.step()
        ids = [msg.arbitration_id for msg in iter(lambda: bus.recv(0.0), None)]
    finally:
        server.stop()
    assert server.base is not None and ids.count(0x241) == 5 and ids.count(0x211) == 1
