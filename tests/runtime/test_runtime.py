"""The runtime: tick order, the fixed rate, and safety when things go wrong."""

from __future__ import annotations

import itertools
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.runtime.assembly import build_runtime
from executive.runtime.loop import BehaviourCrashed, RunOutcome, Runtime, explain_failure
from executive.testing import ObedientAutopilot
from executive.world.dialect import mavlink

HOLD, GUIDED = 4, 15


class Explodes(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        raise ZeroDivisionError("boom")


def make_runtime(square_mission, link, clock, root=None) -> Runtime:
    """The runtime of a mission under way: the vehicle (in GUIDED, armed) stands as this run left it, and its make-safe acts."""
    runtime = build_runtime(square_mission, link, clock, root=root, safe_timeout_s=2.0)
    runtime.link.watch.commanded = "the run before the test"
    return runtime


def autopilot_at(mission, link, vehicle: str = "rover") -> ObedientAutopilot:
    """The obedient autopilot at the mission's first waypoint: its position comes with its heartbeat (no tree runs before it is known)."""
    first = mission.waypoints[0]
    return ObedientAutopilot(link, vehicle, start=(first.lat, first.lon))


def test_a_tick_drains_then_ticks_then_sends(square_mission, link, clock):
    seen = []

    class Probe(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            seen.append(py_trees.blackboard.Blackboard.get("/vehicle/mode"))
            runtime.link.commander.set_mode("HOLD")
            assert link.take("COMMAND_LONG") == []  # not sent during the tick
            return Status.RUNNING

    runtime = make_runtime(square_mission, link, clock, root=Probe("probe"))
    autopilot_at(square_mission, link).beat()
    runtime.mission_state.start()
    runtime.tick()
    assert seen == ["GUIDED"]
    assert [m.param2 for m in link.take("COMMAND_LONG") if m.command == mavlink.MAV_CMD_DO_SET_MODE] == [HOLD]


def test_every_behaviour_of_a_tick_sees_the_time_the_tick_started(square_mission, link, clock):
    """A guard judged by the tree and again by its failsafe in one tick must see one time, even when time runs during the tick."""
    seen = []

    class SlowReader(py_trees.behaviour.Behaviour):
        def setup(self, **services) -> None:
            self.tree_clock = services["clock"]

        def update(self) -> Status:
            seen.append(self.tree_clock.now())
            clock.advance(0.05)  # the clock the runtime runs on moves on while the tick runs (a ScaledClock does)
            return Status.SUCCESS

    root = py_trees.composites.Sequence("Mission", memory=False, children=[SlowReader("first"), SlowReader("second")])
    runtime = make_runtime(square_mission, link, clock, root=root)
    autopilot_at(square_mission, link).beat()
    runtime.mission_state.start()
    started = clock.now()
    runtime.tick()
    assert seen == [started, started]
    runtime.tick()
    assert seen[2:] == [started + 0.1, started + 0.1]


def test_a_crashing_behaviour_makes_the_vehicle_safe_and_names_itself(square_mission, link, clock):
    root = py_trees.composites.Sequence("Mission", memory=True, children=[py_trees.behaviours.Success("ok"), Explodes("Divide")])
    runtime = make_runtime(square_mission, link, clock, root=root)
    autopilot = autopilot_at(square_mission, link)
    autopilot.beat()
    assert runtime.link.connect(1.0)
    runtime.mission_state.start()
    with pytest.raises(BehaviourCrashed) as crash:
        runtime.tick()
    assert crash.value.path == "Mission/Divide"
    outcome = runtime.run(start=False)
    assert outcome.status is MissionStatus.ABORTED
    # a behaviour not of ours (here, this file's): named by its file and line
    assert "behaviour crashed: Mission/Divide: tests/runtime/test_runtime.py:24: ZeroDivisionError: boom" in outcome.reason
    assert autopilot.mode == "HOLD"
    assert runtime.mission_state.status is MissionStatus.ABORTED


def test_a_crash_is_told_of_the_node_ticked_even_when_another_node_s_method_raised_it(square_mission, link, clock):
    """Named by the node whose update the error came out of (a traceback's innermost ``self`` was the other node)."""

    class Asks(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            return elsewhere.update()

    elsewhere = Explodes("Elsewhere")
    runtime = make_runtime(square_mission, link, clock, root=py_trees.composites.Sequence("Mission", memory=True, children=[Asks("Ask")]))
    autopilot_at(square_mission, link).beat()
    assert runtime.link.connect(1.0)
    runtime.mission_state.start()
    with pytest.raises(BehaviourCrashed) as crash:
        runtime.tick()
    assert crash.value.path == "Mission/Ask"


def test_a_stop_request_makes_the_vehicle_safe(square_mission, link, clock):
    runtime = make_runtime(square_mission, link, clock, root=py_trees.behaviours.Running("forever"))
    autopilot = ObedientAutopilot(link)
    autopilot.beat()
    runtime.request_stop("SIGTERM")
    outcome = runtime.run()
    assert (outcome.status, outcome.reason) == (MissionStatus.ABORTED, "stopped: SIGTERM")
    assert autopilot.mode == "HOLD"


def test_make_safe_gives_up_when_the_vehicle_does_not_answer(square_mission, link, clock):
    runtime = make_runtime(square_mission, link, clock)
    start = clock.now()
    assert runtime.make_safe() is False
    assert clock.now() - start == pytest.approx(2.0, abs=0.1)
    assert any(m.get_type() == "COMMAND_LONG" and m.param2 == HOLD for m in link.sent)


def test_success_completes_the_mission(square_mission, link, clock):
    runtime = make_runtime(square_mission, link, clock, root=py_trees.behaviours.Success("done"))
    autopilot_at(square_mission, link).beat()
    outcome = runtime.run()
    assert outcome.status is MissionStatus.COMPLETED and outcome.ticks == 1


def test_ticks_at_the_fixed_rate(square_mission, link, clock):
    times = []

    class Stamp(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            times.append(clock.now())
            return Status.SUCCESS if len(times) == 5 else Status.RUNNING

    runtime = make_runtime(square_mission, link, clock, root=Stamp("stamp"))
    autopilot_at(square_mission, link).beat()
    runtime.run()
    assert [round(b - a, 6) for a, b in itertools.pairwise(times)] == [0.1] * 4


def test_explain_failure_prefers_the_shallowest_reason():
    class Fails(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            self.feedback_message = "deep reason"
            return Status.FAILURE

    leaf = Fails("leaf")
    mid = py_trees.composites.Sequence("mid", memory=True, children=[leaf])
    root = py_trees.composites.Sequence("root", memory=True, children=[mid])
    py_trees.trees.BehaviourTree(root).tick()
    assert explain_failure(root) == "leaf: deep reason"
    mid.feedback_message = "shallow reason"
    assert explain_failure(root) == "mid: shallow reason"


def test_an_operator_abort_ends_the_run_with_the_vehicle_safe(square_mission, link, clock):
    class AbortOnThirdTick(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            self.ticks = getattr(self, "ticks", 0) + 1
            if self.ticks == 3:
                runtime.mission_state.abort("operator: abort")
            return Status.RUNNING

    runtime = make_runtime(square_mission, link, clock, root=AbortOnThirdTick("busy"))
    autopilot = autopilot_at(square_mission, link)
    autopilot.beat()
    outcome = runtime.run()
    assert (outcome.status, outcome.reason, outcome.ticks) == (MissionStatus.ABORTED, "operator: abort", 3)
    assert autopilot.mode == "HOLD"


def test_hands_off_when_a_person_has_the_vehicle(square_mission, link, clock, vehicle):
    """Ending a mission must not take the vehicle back from a pilot who flipped the take-over switch."""
    runtime = make_runtime(square_mission, link, clock, root=py_trees.behaviours.Running("forever"))
    autopilot = ObedientAutopilot(link)
    autopilot.mode = "MANUAL"  # the pilot drives
    autopilot.beat()
    vehicle.set(rc__channels=(1500,) * 5 + (1900,))
    runtime.request_stop("SIGTERM")
    outcome = runtime.run()
    assert outcome.status is MissionStatus.ABORTED
    assert autopilot.mode == "MANUAL"
    assert not [m for m in link.sent if m.get_type() == "COMMAND_LONG" and m.command == mavlink.MAV_CMD_DO_SET_MODE]


def test_a_tree_that_ends_with_a_sample_point_unsampled_does_not_complete(link, clock):
    """No fake success: a tree that returns SUCCESS with a sample not taken (a refused sample skipped) ends ABORTED, saying which."""
    mission = load_mission(Path(__file__).parents[2] / "missions" / "asv_sampling.yaml")
    runtime = build_runtime(mission, link, clock, root=py_trees.behaviours.Success("done"), safe_timeout_s=0.5, simulated_vehicle=True)
    autopilot_at(mission, link, "boat").beat()
    outcome = runtime.run()
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason.startswith("the tree ended, but no sample was recorded at leg ")


def test_a_run_s_outcome_is_a_run_outcome_and_its_old_name_still_imports_with_a_warning():
    """Two things were called Outcome: how a run ended (RunOutcome) and what an acked command asks (executive.world.state.Outcome)."""
    from executive.runtime import loop

    with pytest.warns(DeprecationWarning, match="executive.runtime.loop.Outcome moved to executive.runtime.loop.RunOutcome"):
        assert loop.Outcome is RunOutcome
