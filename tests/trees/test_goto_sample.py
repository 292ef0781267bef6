"""The ASV go-to-and-sample tree, tick by tick, against a scripted boat on a fake link; then the example mission in the simulator."""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from executive.instruments.sampler import SimulatedSampler
from executive.io.mavlink.commander import Commander
from executive.mission.lifecycle import MissionState, MissionStatus, Refused
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.mission.port import MissionPort
from executive.runtime.assembly import build_runtime
from executive.runtime.loop import Runtime, explain_failure
from executive.testing import EKF_READY, ScriptedAutopilot, Vehicle, ack, port_for
from executive.tree import select as mission_tree
from executive.world.clock import ManualClock
from executive.world.geo import destination, distance_bearing
from executive.world.state import EkfFlags, EkfStatus, SampleRecord, SamplerState
from executive.world.vehicles import PROFILES

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
ROOT = Path(__file__).parents[2]
EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 1.2, 1.2, 1.2, 1.2, 0.0, 0.0)
RC_AUTO = (1500,) * 5 + (1000,)  # channel 6 low: the RC leaves the boat to the executive
RC_MANUAL = (1500,) * 5 + (1900,)  # channel 6 high: manual interruption
START = (-35.2960000, 149.1130000)
P0 = destination(*START, 0.0, 30.0)  # a point of the path
S1 = destination(*P0, 90.0, 30.0)  # the first sample point
S2 = destination(*S1, 180.0, 30.0)  # the second sample point
ARM, DISARM = ("arm", 1.0), ("arm", 0.0)


def mode(name: str) -> tuple[str, str]:
    return ("mode", name)


def make_mission(**changes: Any) -> Mission:
    """Path point, sample point, sample point; 2 s samples of two sensors; the seed's limits, recovery within 30 s."""
    fields: dict[str, Any] = {
        "version": 1,
        "name": "go-to and sample",
        "vehicle": "boat",
        "tree": "goto_sample",
        "auto_arm": True,
        "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60, "max_goal_distance_m": 5000, "recovery_timeout_s": 30, "ekf_wait_s": 30},
        "sampling": {"duration_s": 2.0, "rate_hz": 1.0, "sensors": ["temperature", "ph"]},
        "waypoints": [
            {"lat": P0[0], "lon": P0[1], "name": "p0"},
            {"lat": S1[0], "lon": S1[1], "name": "s1", "sample": True},
            {"lat": S2[0], "lon": S2[1], "name": "s2", "sample": True},
        ],
    }
    return Mission.model_validate(fields | changes)


class Boat(ScriptedAutopilot):
    """A scripted ArduRover boat behind the commander: mode and arm commands acked at once, ``step_m`` a tick toward its GUIDED target.

    It drives only armed, in GUIDED, and stops ``short_m`` before the target. What the test sets
    (mode, armed, ekf, rc, link_up, position) is what the autopilot reports on the next tick.
    """

    def __init__(self, at: tuple[float, float], commander: Commander) -> None:
        self.ekf, self.rc, self.link_up = EKF_READY, RC_AUTO, True
        self.short_m = 0.0
        self.setpoints = 0
        self._vehicle = Vehicle()
        super().__init__(None, at, step_m=2.0, commander=commander)

    def facts(self) -> dict[str, object]:
        return {**super().facts(), "link__up": self.link_up, "vehicle__ekf": self.ekf, "rc__channels": self.rc}

    def publish(self) -> None:
        self._vehicle.set(**self.facts())

    def acknowledge(self, command: int, result: int) -> None:
        self.commander.on_ack(ack(command, result))

    def respond(self, sent: list[Any]) -> None:  # type: ignore[override]  # what the tree sent comes from the test's link
        for msg in sent:
            self.answer(msg)
        self.move()
        self.publish()

    def on_setpoint(self, msg: Any) -> None:
        self.setpoints += 1
        super().on_setpoint(msg)

    def move(self) -> None:
        if self.target and self.mode == "GUIDED" and self.armed:
            d, b = distance_bearing(self.lat, self.lon, *self.target)
            self.lat, self.lon = destination(self.lat, self.lon, b, max(0.0, min(d - self.short_m, self.step_m)))

    def distance_to(self, point: tuple[float, float]) -> float:
        return distance_bearing(self.lat, self.lon, *point)[0]


class Run:
    """The tree ticked by hand at 10 Hz, with the boat answering after each tick and the sampler serviced as the runtime does."""

    def __init__(self, mission: Mission, clock: ManualClock, link, at: tuple[float, float] = START, runtime: Runtime | None = None) -> None:
        self.clock, self.link, self.mission = clock, link, mission
        if runtime is None:
            self.commander = Commander(link, clock, PROFILES[mission.vehicle])
            self.state = MissionState()
            self.state.upload(mission)
            self.sampler = SimulatedSampler(clock, mission.sampling, seed=1)
            self.tree = py_trees.trees.BehaviourTree(mission_tree.build(mission))
            self.tree.setup(clock=clock, autopilot=port_for(self.commander), mission_state=MissionPort(self.state), sampler=self.sampler)
            self.state.start()
        else:
            runtime.mission_state.start()  # builds the tree and its sampler
            assert runtime.tree is not None and runtime.sampler is not None
            self.commander, self.state, self.sampler, self.tree = runtime.link.commander, runtime.mission_state, runtime.sampler, runtime.tree
        self.boat = Boat(at, self.commander)

    @property
    def root(self) -> py_trees.behaviour.Behaviour:
        return self.tree.root

    @property
    def reason(self) -> str:
        return explain_failure(self.root)

    def tick(self, n: int = 1) -> list[Status]:
        """Up to ``n`` ticks, stopping at the first that is not RUNNING; their statuses."""
        statuses = []
        for _ in range(n):
            self.clock.advance(0.1)
            self.boat.publish()  # what the test changed since the last tick arrives now
            self.tree.tick()
            self.sampler.service()
            self.commander.flush()
            self.boat.respond(self.link.take())
            statuses.append(self.root.status)
            if statuses[-1] != R:
                break
        return statuses

    def until(self, condition, limit: int = 1000) -> int:
        """Tick until ``condition()`` holds (every tick RUNNING meanwhile); how many ticks it took."""
        for n in range(1, limit + 1):
            assert self.tick() == [R]
            if condition():
                return n
        raise AssertionError("condition never held")

    def sampling(self) -> bool:
        status = self.sampler.status
        return status is not None and status.state is SamplerState.SAMPLING


@pytest.fixture
def run(clock, link):
    """The go-to of the test mission, auto_arm, from a boat disarmed in MANUAL at START."""
    return Run(make_mission(), clock, link)


# -- pre-flight and the go-to's acceptance -------------------------------------------------------


@pytest.mark.parametrize(("vehicle", "end"), [("boat", []), ("rover", [mode("HOLD")])])
def test_the_path_is_driven_and_every_sample_point_sampled_once(clock, link, vehicle, end):
    run = Run(make_mission(vehicle=vehicle), clock, link)
    hold = PROFILES[vehicle].safe_mode  # a boat's LOITER, a rover's HOLD
    assert run.tick(3) == [R, R, R]
    assert run.boat.commands == [ARM, mode(hold), mode("GUIDED")]  # armed, ready in its hold, accepted: GUIDED
    statuses = run.tick(400)
    assert statuses[-1] == S
    assert run.boat.commands == [ARM, mode(hold), mode("GUIDED"), mode("LOITER"), mode("GUIDED"), mode("LOITER"), *end]  # held at the end
    assert [s.leg_index for s in run.state.sample_log.taken] == [1, 2]  # the sample points, not the path point
    for sample in run.state.sample_log.taken:
        assert sorted(r.sensor for r in sample.reads) == ["ph", "ph", "temperature", "temperature"]  # 2 s at 1 Hz, both sensors
    assert run.state.legs.leg_index == 3
    assert (run.boat.mode, run.boat.armed) == (PROFILES[vehicle].safe_mode, True)
    assert run.boat.distance_to(S2) <= 1.5


def test_without_auto_arm_the_operator_readies_the_boat_and_arming_requests_the_go_to(clock, link):
    run = Run(make_mission(auto_arm=False), clock, link)
    assert run.tick(20) == [R] * 20  # waiting for the operator: nothing sent
    run.boat.mode = "LOITER"  # the operator sets LOITER...
    assert run.tick(5) == [R] * 5
    run.boat.armed = True  # ...then arms
    assert run.tick(2) == [R, R]
    assert run.boat.commands == [mode("GUIDED")]
    assert run.state.legs.leg_index == 0 and run.boat.setpoints == 1


def test_rc_channel_5_high_arms_the_boat(clock, link):
    """Issue 13: the ASV seed's RC rule, channel 5 high = armed, was missing: the operator's arm switch arms the boat."""
    run = Run(make_mission(auto_arm=False), clock, link)
    run.boat.mode = "LOITER"  # the operator readies the boat...
    assert run.tick(10) == [R] * 10
    assert run.boat.commands == []  # channel 5 low: nothing armed
    run.boat.rc = (1500,) * 4 + (1900, 1000)  # ...and puts the arm switch (channel 5) up
    assert run.tick(3) == [R] * 3
    assert run.boat.commands == [ARM, mode("GUIDED")]  # armed by the executive, then the go-to accepted


@pytest.mark.parametrize(
    ("auto_arm", "at", "between_ticks", "ticks", "commands", "reason"),
    [
        pytest.param(
            True,
            START,
            lambda boat: setattr(boat, "armed", False),  # the RC's arm switch goes down while LOITER is set
            [R, R, F],
            [ARM, mode("LOITER")],
            "Armed?: vehicle is disarmed",
            id="disarmed",
        ),
        pytest.param(
            False,
            START,
            lambda boat: setattr(boat, "armed", True),  # the operator arms in MANUAL
            [R, R, F],
            [],
            "Mode is LOITER?: mode is MANUAL, not LOITER",
            id="not in LOITER",
        ),
    ],
)
def test_the_go_to_is_rejected(clock, link, auto_arm, at, between_ticks, ticks, commands, reason):
    run = Run(make_mission(auto_arm=auto_arm), clock, link, at=at)
    statuses = run.tick(2)
    between_ticks(run.boat)
    statuses += run.tick(10)
    assert statuses == ticks
    assert run.boat.commands == commands  # no GUIDED...
    assert run.boat.setpoints == 0 and run.link.take() == []  # ...no target: nothing that moves the boat
    assert run.reason == reason


@pytest.mark.parametrize("auto_arm", [True, False])
def test_a_point_over_5_km_away_is_rejected_before_arming_or_any_mode_change(clock, link, auto_arm):
    """Issue 13: the ASV armed and set LOITER before rejecting a point over 5 km away."""
    run = Run(make_mission(auto_arm=auto_arm), clock, link, at=destination(*START, 180.0, 5200.0))
    run.boat.mode, run.boat.armed = ("MANUAL", False) if auto_arm else ("LOITER", True)  # without auto_arm, the operator had readied it
    assert run.tick(10) == [F]
    assert run.boat.commands == [] and run.boat.setpoints == 0 and run.link.take() == []
    assert run.reason == "Every point within 5000 m?: waypoint 1 'p0' is 5230 m away, over 5000 m"


def test_a_go_to_in_progress_refuses_another(run):
    run.until(lambda: run.state.legs.leg_index == 1)
    with pytest.raises(Refused, match="cannot start while RUNNING"):
        run.state.start()
    run.state.pause("operator: pause")
    with pytest.raises(Refused, match="cannot start while PAUSED"):
        run.state.start()
    run.state.resume()
    assert run.state.legs.leg_index == 1 and run.state.status is MissionStatus.RUNNING
    assert run.tick(400)[-1] == S


# -- the checks of every tick ---------------------------------------------------------------------


def under_way(run: Run) -> None:
    """Ticks until the boat is on its way to the first point, a few metres out."""
    run.until(lambda: run.boat.setpoints >= 1)
    assert run.tick(2) == [R, R]
    run.boat.commands.clear()


@pytest.mark.parametrize("phase", ["on the way", "sampling"])
def test_the_rc_leaving_auto_ends_the_go_to(run, phase):
    if phase == "on the way":
        under_way(run)
    else:
        run.until(run.sampling)
        run.boat.commands.clear()
    run.boat.rc = RC_MANUAL  # the pilot's manual interruption switch
    run.boat.mode = "MANUAL"
    assert run.tick(5) == [F]
    assert run.reason == "RC in auto? (else leave): RC channel 6 high (1900 µs): manual take-over"
    assert run.boat.commands == [] and run.link.take() == []  # the tree leaves the boat to the pilot
    assert run.state.sample_log.taken == ()
    if phase == "sampling":
        assert (run.sampler.status.state, run.sampler.status.reason) == (SamplerState.FAILED, "cancelled")


def test_a_bad_ekf_waits_in_manual_disarmed_then_re_arms_and_continues_the_same_leg(run):
    under_way(run)
    setpoints = run.boat.setpoints
    run.boat.ekf = EKF_LOST
    assert run.tick(3) == [R, R, R]
    assert run.boat.commands == [mode("MANUAL"), DISARM]
    assert run.tick(100) == [R] * 100  # waiting, hands off, no target sent
    assert run.boat.commands == [mode("MANUAL"), DISARM] and run.boat.setpoints == setpoints
    run.boat.ekf = EKF_READY
    assert run.tick(29) == [R] * 29 and run.boat.commands == [mode("MANUAL"), DISARM]  # the EKF sane for 3 s first
    assert run.tick(3) == [R, R, R]
    assert run.boat.commands == [mode("MANUAL"), DISARM, ARM, mode("GUIDED")]
    assert run.tick() == [R]
    assert run.state.legs.leg_index == 0 and run.boat.setpoints == setpoints + 1  # the same leg, its target again
    assert run.tick(400)[-1] == S
    assert len(run.state.sample_log.taken) == 2


def test_an_ekf_that_never_recovers_fails_the_go_to(run):
    under_way(run)
    run.boat.ekf = EKF_LOST
    statuses = run.tick(400)
    assert statuses == [R] * (len(statuses) - 1) + [F]
    assert len(statuses) == pytest.approx(30 * 10 + 3, abs=2)  # MANUAL, disarm, then recovery_timeout_s
    assert run.reason.startswith("Wait until the EKF recovers: gave up after 30 s: EKF has no position estimate")
    assert run.boat.commands == [mode("MANUAL"), DISARM]


def test_a_bad_ekf_on_a_boat_the_pilot_disarmed_is_left_to_the_pilot(run):
    under_way(run)
    run.boat.armed, run.boat.ekf = False, EKF_LOST
    assert run.tick(50) == [R] * 50
    run.boat.ekf = EKF_READY
    assert run.tick(50) == [R] * 50
    assert run.boat.commands == []  # no MANUAL, no disarm, and above all no arming: the pilot has the boat
    run.boat.armed = True  # the RC returns to normal
    assert run.tick(2) == [R, R]
    assert run.boat.commands == [] and run.state.legs.leg_index == 0  # still GUIDED: the same leg goes on
    assert run.tick(400)[-1] == S


@pytest.mark.parametrize("other", ["HOLD", "LOITER", "MANUAL"])
def test_a_mode_other_than_guided_is_set_back_to_guided(run, other):
    under_way(run)
    run.boat.mode = other  # a ground station changed it; the RC is still in auto
    assert run.tick(2) == [R, R]
    assert run.boat.commands == [mode("GUIDED")]
    assert run.state.legs.leg_index == 0
    assert run.tick(400)[-1] == S


@pytest.mark.parametrize(
    ("fact", "hold", "back"),
    [
        pytest.param("armed", [], [], id="disarmed: the RC took over"),  # hands off; still GUIDED when re-armed
        pytest.param("link_up", [mode("LOITER")], [mode("GUIDED")], id="link lost"),
    ],
)
def test_a_failing_guard_is_waited_out_then_the_same_leg_continues(run, fact, hold, back):
    under_way(run)
    setattr(run.boat, fact, False)
    assert run.tick(100) == [R] * 100
    assert run.boat.commands == hold  # hold in LOITER, unless a person has the boat
    setattr(run.boat, fact, True)
    ticks = 22 if fact == "link_up" else 2  # the link back for LinkAlive's 2 s first; re-armed: at once
    assert run.tick(ticks) == [R] * ticks
    assert run.boat.commands == hold + back
    assert run.state.legs.leg_index == 0
    assert run.tick(400)[-1] == S


def test_a_disarm_that_lasts_fails_the_go_to(run):
    under_way(run)
    run.boat.armed = False
    statuses = run.tick(400)
    assert statuses == [R] * (len(statuses) - 1) + [F]
    assert len(statuses) == pytest.approx(30 * 10, abs=2)
    assert run.reason == "Wait for guards: not recovered after 30 s: Armed? vehicle is disarmed"
    assert run.boat.commands == []


def test_a_leg_over_a_minute_is_abandoned(run):
    run.boat.step_m = 0.04  # 0.4 m/s: the 30 m leg would take 75 s
    run.until(lambda: run.boat.setpoints >= 1)
    started = run.clock.now()
    statuses = run.tick(1000)
    assert statuses[-1] == F
    assert 60.0 < run.clock.now() - started <= 60.2
    assert "leg 1/3: timed out after 60 s" in run.reason
    assert run.state.legs.leg_index == 0 and run.state.sample_log.taken == ()


@pytest.mark.parametrize(("short_m", "reached"), [(1.4, True), (1.6, False)])
def test_a_point_counts_as_reached_within_the_acceptance_radius(run, short_m, reached):
    run.boat.short_m = short_m  # the boat stops this far from each point
    run.until(lambda: run.boat.distance_to(P0) < short_m + 0.01)
    assert run.tick(2) == [R, R]
    assert run.state.legs.leg_index == (1 if reached else 0)
    if not reached:
        assert run.tick(100) == [R] * 100 and run.state.legs.leg_index == 0  # until the leg times out


# -- sampling ------------------------------------------------------------------------------------


def test_at_a_sample_point_the_boat_loiters_while_the_sampler_reads(run):
    run.until(lambda: run.state.legs.leg_index == 1)
    run.boat.commands.clear()
    run.until(run.sampling)
    assert run.boat.commands == [mode("LOITER")]
    assert run.boat.mode == "LOITER" and run.boat.distance_to(S1) <= 1.5
    run.until(lambda: run.state.sample_log.taken != ())
    (sample,) = run.state.sample_log.taken
    assert sample.leg_index == 1 and {r.sensor for r in sample.reads} == {"temperature", "ph"}
    assert sample.finished - sample.started == pytest.approx(2.0)


def test_a_disarm_during_a_sample_cancels_it_and_the_sample_is_taken_again(run):
    run.until(run.sampling)
    first = run.sampler.status.ticket
    run.boat.armed = False  # the RC took over mid-sample
    assert run.tick(10) == [R] * 10
    assert (run.sampler.status.state, run.sampler.status.reason) == (SamplerState.FAILED, "cancelled")
    assert run.state.sample_log.taken == ()  # nothing recorded
    run.boat.armed = True
    run.boat.commands.clear()
    run.until(lambda: run.state.sample_log.taken != ())
    assert run.boat.commands == [mode("GUIDED"), mode("LOITER")]  # the leg again: already there, held, sampled
    assert run.sampler.status.ticket == first + 1
    assert [s.leg_index for s in run.state.sample_log.taken] == [1]
    assert run.tick(400)[-1] == S
    assert [s.leg_index for s in run.state.sample_log.taken] == [1, 2]


def test_a_pause_during_a_sample_cancels_it_and_the_resumed_go_to_takes_it_again(run):
    run.until(run.sampling)
    run.boat.commands.clear()
    run.state.pause("operator: pause")
    assert run.tick(20) == [R] * 20
    assert (run.sampler.status.state, run.sampler.status.reason) == (SamplerState.FAILED, "cancelled")
    assert run.boat.commands == [mode("LOITER")] and run.state.sample_log.taken == ()  # held, asked once
    run.state.resume()  # the go-to is accepted again (armed, in LOITER), then the same leg
    run.until(lambda: run.state.sample_log.taken != ())
    assert run.boat.commands == [mode("LOITER"), mode("GUIDED"), mode("LOITER")]
    assert run.tick(400)[-1] == S
    assert [s.leg_index for s in run.state.sample_log.taken] == [1, 2]


def test_a_sample_point_already_sampled_is_not_sampled_again(run):
    run.state.restore_samples([SampleRecord(1, *S1, (), 0.0, 1.0)])  # a restarted executive got it back from its journal
    assert run.tick(400)[-1] == S
    assert run.boat.commands == [ARM, mode("LOITER"), mode("GUIDED"), mode("LOITER")]  # no LOITER at s1: only at s2
    assert run.sampler.status.ticket == 1
    assert [s.leg_index for s in run.state.sample_log.taken] == [1, 2]


def test_a_cancel_during_a_sample_cancels_the_sampler_and_records_nothing(clock, link):
    runtime = build_runtime(make_mission(), link, clock, safe_timeout_s=0.5)
    run = Run(make_mission(), clock, link, runtime=runtime)
    run.until(run.sampling)
    run.state.abort("operator: cancel")  # what `executive ctl abort` does; the runtime then makes the boat safe
    runtime.make_safe()
    assert (run.sampler.status.state, run.sampler.status.reason) == (SamplerState.FAILED, "cancelled")
    assert run.state.sample_log.taken == ()


def test_a_goto_sample_mission_without_a_sampling_section_gets_the_default_sampler(clock, link):
    fields = make_mission().model_dump(exclude_none=True, exclude={"sampling"})
    runtime = build_runtime(Mission.model_validate(fields), link, clock)
    runtime.mission_state.start()
    assert runtime.sampler is not None and runtime.sampler.options.sensors == ["temperature", "conductivity", "ph", "dissolved_oxygen"]


# -- the example mission in the simulator ---------------------------------------------------------


def test_the_example_mission_samples_every_sample_point_once_in_the_simulator(caplog, lockstep):
    """missions/asv_sampling.yaml with its event file (an EKF dropout on the way), in the lock-step simulation."""
    path = ROOT / "missions/asv_sampling.yaml"
    mission = load_mission(path)
    assert mission.home is not None and mission.sampling is not None and mission.simulator is not None and mission.simulator.events
    caplog.set_level(logging.INFO, logger="executive.io.mavlink.reader")
    sim = lockstep(mission, mission_dir=path.parent)
    outcome = sim.run_to_end(limit_s=900)
    runtime, final_mode, armed = sim.runtime, sim.autopilot.mode, sim.autopilot.armed
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert (final_mode, armed) == ("LOITER", True)
    sample_points = [i for i, wp in enumerate(mission.waypoints) if wp.sample]
    samples = runtime.mission_state.sample_log.taken
    assert sorted(s.leg_index for s in samples) == sample_points  # exactly one Sample per sample point
    rounds = math.floor(mission.sampling.duration_s * mission.sampling.rate_hz)
    for sample in samples:
        assert sorted(r.sensor for r in sample.reads) == sorted(mission.sampling.sensors * rounds)
        wp = mission.waypoints[sample.leg_index]
        assert distance_bearing(sample.lat, sample.lon, wp.lat, wp.lon)[0] <= mission.limits.acceptance_radius_m + 1.0  # held in LOITER there
    texts = [r.getMessage() for r in caplog.records]
    assert any("Throttle disarmed" in t for t in texts)  # the EKF dropout was waited out disarmed...
    assert [t for t in texts if "Throttle armed" in t][1:]  # ...and the boat re-armed after it
