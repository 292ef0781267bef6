"""The thesis's closed loop in one process: the simulated Bunker's base and the executive's runtime on one CAN bus, in the lock-step simulation.

The autopilot's skid-steer outputs reach the tracks only through the executive: SERVO_OUTPUT_RAW over
MAVLink -> the drive bridge -> 0x111 over CAN -> the base's controller. RC comes from 0x241 (rc.source can).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import can
import py_trees
import pytest

from executive.cli import main
from executive.io.can.agilex import RC_STATE_ID, SYSTEM_STATE_ID, MotionCommand
from executive.io.can.drive import DriveBridge
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.runtime.loop import RunOutcome, Runtime
from executive.sim.faults import FaultPlan
from executive.testing import Lockstep
from executive.world import geo

START = (-35.363261, 149.165230)
TARGET = geo.destination(*geo.destination(*START, 0.0, 6.0), 90.0, 3.0)  # 6 m north, 3 m east: a turn and a drive
_channels = itertools.count()


def bb(key: str) -> object:
    return py_trees.blackboard.Blackboard.storage.get(key)


@dataclass
class Tick:
    t: float  # seconds since the simulated vehicle booted
    fresh: Any
    stale_reason: Any
    system: Any
    drive: Any
    counter_repeats: int


@dataclass
class Watch:
    """Stands in for the runtime's status line: records every tick; stops the run once the autopilot has tried to drive for ``stop_after_s``."""

    sim: Lockstep | None = None  # the simulation, once made
    stop_after_s: float | None = None
    runtime: Runtime | None = None
    ticks: list[Tick] = field(default_factory=list)
    max_track_pwm: int = 0
    _driving_since: float | None = None

    def update(self, force: bool = False) -> None:
        assert self.sim is not None
        ap = self.sim.autopilot
        t, pwm, trying = ap.elapsed_s, max(ap.track_pwm), ap.armed and ap.mode == "GUIDED" and max(ap.track_pwm) > 1600
        self.ticks.append(
            Tick(t, bb("/rc/fresh"), bb("/rc/stale_reason"), bb("/base/system"), bb("/base/drive"), bb("/base/rc_counter_repeats") or 0)
        )
        self.max_track_pwm = max(self.max_track_pwm, pwm)
        self._driving_since = (self._driving_since or t) if trying else None
        if self.stop_after_s is not None and self._driving_since is not None and t - self._driving_since >= self.stop_after_s and self.runtime:
            self.runtime.request_stop("the autopilot has tried long enough")

    def close(self) -> None:
        pass


class Run(NamedTuple):
    outcome: RunOutcome
    sim: Lockstep
    watch: Watch


@pytest.fixture
def channel() -> str:
    return f"test-can-closed-loop-{next(_channels)}"


def mission() -> Mission:
    return Mission.model_validate({
        "version": 1, "name": "can-loop", "vehicle": "rover", "tree": "waypoints", "auto_arm": True,
        "home": {"lat": START[0], "lon": START[1]}, "rc": {"source": "can", "fresh_timeout_s": 1.0},
        "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60.0, "ekf_wait_s": 30.0},
        "waypoints": [{"lat": TARGET[0], "lon": TARGET[1]}],
    })  # fmt: skip


def run_against_the_base(faults: list[dict[str, object]] | None = None, stop_after_s: float | None = None) -> Run:
    """The runtime against a simulated bunker, both on one CAN bus (in-process), on the lock-step simulation's clock."""
    events = FaultPlan.model_validate({"version": 1, "faults": faults}).faults if faults else ()
    watch = Watch(stop_after_s=stop_after_s)
    with Lockstep(mission(), model="bunker", home=(*START, 0.0), ekf_ready_after_s=1.0, events=events, can=True, progress=watch) as sim:
        watch.sim, watch.runtime = sim, sim.runtime
        outcome = sim.run_to_end(limit_s=300)
    return Run(outcome, sim, watch)


@pytest.fixture(scope="module")
def rc_loss_run() -> Run:
    """One mission, the transmitter lost from 4 s to 7 s after boot while the vehicle drives."""
    return run_against_the_base(faults=[{"kind": "rc_loss", "at_s": 4.0, "for_s": 3.0}])


@pytest.mark.xdist_group("can_rc_loss_run")
def test_the_vehicle_reaches_its_waypoint_because_the_bridge_forwards_the_outputs(rc_loss_run: Run) -> None:
    outcome, sim, watch = rc_loss_run
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert sim.autopilot.vehicle.distance_to(*TARGET) < 1.5
    assert sim.base is not None and sim.base.received[0x111] > 200 and sim.base.received[0x421] > 200
    assert any(tick.drive and tick.drive.linear_m_s > 0.3 and not tick.drive.reason for tick in watch.ticks)
    assert {tick.system.control_mode for tick in watch.ticks if tick.system} == {"RC", "CAN"}  # RC until the bridge's first 0x421


@pytest.mark.xdist_group("can_rc_loss_run")
def test_the_base_gets_50_motion_commands_per_second_of_vehicle_time(rc_loss_run: Run) -> None:
    _, sim, watch = rc_loss_run
    assert sim.base is not None
    expected = 50 * (watch.ticks[-1].t - watch.ticks[0].t)  # from the runtime's first tick to its last, between ticks too
    assert abs(sim.base.received[0x111] - expected) <= 5  # a tick's worth at either end


@pytest.mark.xdist_group("can_rc_loss_run")
def test_during_the_rc_loss_the_base_repeats_its_last_frame_and_reports_nothing(rc_loss_run: Run) -> None:
    lost = [tick for tick in rc_loss_run.watch.ticks if 4.1 < tick.t < 6.9]
    assert lost and {(tick.system.control_mode, tick.system.faults) for tick in lost} == {("CAN", ())}
    repeats_per_s = (lost[-1].counter_repeats - lost[0].counter_repeats) / (lost[-1].t - lost[0].t)
    assert repeats_per_s > 20.0  # the 0x241 frames keep coming (50 Hz at most; the loop is slower at this speed-up), every one a repeat


@pytest.mark.xdist_group("can_rc_loss_run")
def test_a_frozen_counter_makes_rc_stale(rc_loss_run: Run) -> None:
    ticks = rc_loss_run.watch.ticks
    stale = [tick for tick in ticks if tick.fresh is False]
    assert stale and all(4.9 < tick.t < 7.5 for tick in stale), [round(tick.t, 2) for tick in stale]
    assert {tick.stale_reason for tick in stale} == {"no RC report within 1 s"}
    assert any(tick.fresh is True and tick.t < 4.0 for tick in ticks) and any(tick.fresh is True and tick.t > 7.5 for tick in ticks)


def test_without_the_bridge_forwarding_the_vehicle_does_not_move(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(DriveBridge, "in_control", property(lambda self: False, lambda self, value: None), raising=False)
    outcome, sim, watch = run_against_the_base(stop_after_s=3.0)
    assert outcome.status is MissionStatus.ABORTED and outcome.reason == "stopped: the autopilot has tried long enough"
    assert watch.max_track_pwm > 1700  # armed in GUIDED, the autopilot drove its outputs for 3 s ...
    assert sim.autopilot.vehicle.distance_to(*START) < 0.01  # ... and the tracks did not turn
    assert sim.base is not None and sim.base.received[0x111] > 100 and sim.base.command == MotionCommand(0, 0)
    assert {tick.drive.reason for tick in watch.ticks if tick.drive} == {"executive not in control"}


# -- executive sim --can ---------------------------------------------------------------------------


def test_sim_puts_the_base_on_the_bus(channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    with can.Bus(interface="virtual", channel=channel) as bus:
        args = ["sim", "--vehicle", "bunker", "--can", f"virtual:{channel}", "--mavlink", "udpin:127.0.0.1:0", "--duration", "0.5", "--speedup", "2"]
        assert main(args) == 0
        ids = [msg.arbitration_id for msg in iter(lambda: bus.recv(0.0), None)]
    assert ids.count(RC_STATE_ID) >= 5 and ids.count(SYSTEM_STATE_ID) >= 1
    assert f"AgileX base on CAN virtual:{channel}" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--vehicle", "rover", "--can", "virtual:x"], "use it with --vehicle bunker, not rover"),
        (["--vehicle", "bunker", "--can", "can0"], "expected IFACE:CHANNEL"),
    ],
)
def test_sim_refuses_a_bad_can_request(args: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim", *args]) == 2
    assert message in capsys.readouterr().err
