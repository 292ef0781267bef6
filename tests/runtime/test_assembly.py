"""The runtime as a loop over services: a plug's readers run before the tree, its writers after, its paced service between ticks."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from executive.mission.lifecycle import MissionStatus
from executive.runtime.assembly import Wiring, build_runtime
from executive.runtime.loop import RunOutcome
from executive.runtime.services import FunctionService, service_name
from executive.testing import ObedientAutopilot
from executive.world.dialect import mavlink


class Paced:
    """A paced service every 1/32 s of clock time (exact in binary), that notes when it was stopped."""

    def __init__(self, clock, events: list[str]) -> None:
        self.clock, self.events = clock, events
        self.next_due = 0.0
        self.times: list[float] = []

    def pace(self) -> None:
        if self.clock.now() >= self.next_due:
            self.times.append(self.clock.now())
            self.next_due = self.clock.now() + 0.03125

    def stop(self) -> None:
        self.events.append("stopped")


class Observer:
    def __init__(self, events: list[str]) -> None:
        self.events = events

    def begin(self, mission, root, resumed_from) -> None:
        self.events.append(f"begin {root.name} resumed_from={resumed_from}")

    def ticked(self, tick: int, now: float) -> None:
        self.events.append(f"ticked {tick}")

    def end(self, status: str, reason: str) -> None:
        self.events.append(f"end {status}")


def test_a_plug_adds_services_run_around_the_tree(square_mission, link, clock):
    events: list[str] = []
    paced: list[Paced] = []

    class Probe(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            events.append("tree")
            return Status.SUCCESS

    def sensor(w: Wiring) -> None:
        w.readers.append(FunctionService("sensor", lambda: events.append("read")))
        w.writers.append(FunctionService("viewer", lambda: events.append("write")))
        w.observers.append(Observer(events))
        paced.append(Paced(w.clock, events))
        w.paced.append(paced[0])
        w.closers.append(lambda: events.append("closed"))

    runtime = build_runtime(square_mission, link, clock, plugs=[sensor], root=Probe("probe"), safe_timeout_s=0.0)
    runtime.tick()
    assert events == ["read", "write"]  # no mission running: no tree, the services still run
    events.clear()
    first = square_mission.waypoints[0]
    ObedientAutopilot(link, start=(first.lat, first.lon)).beat()  # where the vehicle is: no tree runs before it is known
    runtime.run()
    assert events[:5] == ["begin probe resumed_from=None", "read", "tree", "ticked 1", "write"]
    assert events[5:] == ["end COMPLETED"]  # the mission ended at its first tick, nothing waited between ticks
    events.clear()
    runtime.make_safe()
    assert events == ["stopped"]
    runtime.close()
    assert events == ["stopped", "closed"]


def test_paced_services_run_between_ticks(square_mission, link, clock):
    paced: list[Paced] = []

    def drive(w: Wiring) -> None:
        paced.append(Paced(w.clock, []))
        w.paced.append(paced[0])

    runtime = build_runtime(square_mission, link, clock, plugs=[drive], root=py_trees.behaviours.Running("idle"))
    start = clock.now()
    runtime._wait_until(start + 0.125)
    assert [t - start for t in paced[0].times] == [0.0, 0.03125, 0.0625, 0.09375]  # at its own rate until the next tick
    assert clock.now() == start + 0.125


def test_the_operator_side_and_the_estimators_are_services_in_order(square_mission, link, clock):
    runtime = build_runtime(square_mission, link, clock)
    names = [service_name(s) for s in runtime.readers]
    assert names == ["ground-station commands", "HeadingFilter", "RcReader", "PersonsCommands", "InterventionWatch", "EnergyWatch"]
    names = [service_name(s) for s in runtime.writers]
    assert names == ["GroundStationControl"]


def test_the_link_is_pumped_before_the_readers_and_flushed_after_the_writers(square_mission, link, clock):
    seen: list[tuple[str, object, int]] = []

    def probe(w: Wiring) -> None:
        def read() -> None:
            seen.append(("read", w.link.get("/vehicle/mode"), len(link.take("COMMAND_LONG"))))
            w.link.commander.set_mode("HOLD")  # asked during the tick: sent when the link is flushed

        w.readers.append(FunctionService("probe reader", read))
        w.writers.append(FunctionService("probe writer", lambda: seen.append(("write", None, len(link.take("COMMAND_LONG"))))))

    runtime = build_runtime(square_mission, link, clock, plugs=[probe])
    ObedientAutopilot(link, mode="MANUAL").beat()
    runtime.tick()
    assert seen == [("read", "MANUAL", 0), ("write", None, 0)]  # the heartbeat pumped in before the readers; nothing sent yet
    sent = [m.command for m in link.take("COMMAND_LONG")]
    assert sent == [mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL]  # sent after the writers, with the first stream's request


def test_two_runtimes_in_one_process_each_have_their_own_blackboard_and_both_complete(lockstep, square_mission) -> None:
    east = square_mission.model_copy(  # another rover 750 m east, on a two-leg route
        update={"name": "east", "waypoints": [wp.model_copy(update={"lon": wp.lon + 0.01}) for wp in square_mission.waypoints[:2]]}
    )
    square, other = lockstep(square_mission, ekf_ready_after_s=1.0), lockstep(east, ekf_ready_after_s=1.0)
    assert square.runtime.board is not other.runtime.board
    outcomes: dict[str, RunOutcome] = {}
    while len(outcomes) < 2:  # lock-step, interleaved: a second of vehicle time each in turn
        for sim in (s for s in (square, other) if s.mission.name not in outcomes):
            stop_at = sim.clock.now() + 1.0
            outcome = sim.run(limit_s=300, until=lambda sim=sim, stop_at=stop_at: sim.clock.now() >= stop_at)
            if outcome is not None:
                outcomes[sim.mission.name] = outcome
            for each, them in ((square, other), (other, square)):
                board = each.runtime.board
                assert board.value("/mission/leg_count") == len(each.mission.waypoints)  # its own mission, never the other's
                position = board.value("/vehicle/position")
                if position is not None:  # where its own vehicle is, 750 m from the other
                    assert abs(position.lon - each.autopilot.vehicle.lon) < 1e-4 and abs(position.lon - them.autopilot.vehicle.lon) > 5e-3
    assert {name: outcome.status for name, outcome in outcomes.items()} == {"square": MissionStatus.COMPLETED, "east": MissionStatus.COMPLETED}


def test_a_closed_runtime_leaves_its_board_to_the_next_and_its_tree_built_before(lockstep, square_mission) -> None:
    from executive.tree import select as mission_tree

    first = lockstep(square_mission, ekf_ready_after_s=1.0)
    first.close()
    tree = mission_tree.build(square_mission)  # as a test builds its own tree, before its simulation
    second = lockstep(square_mission, ekf_ready_after_s=1.0, root=tree)
    assert second.runtime.board is first.runtime.board
    assert second.run_to_end(limit_s=300).status is MissionStatus.COMPLETED


def test_a_plugin_key_documented_after_a_second_board_was_made_is_on_that_board_when_its_node_is_made(lockstep, square_mission) -> None:
    from executive.world import blackboard

    first = lockstep(square_mission, ekf_ready_after_s=1.0)
    second = lockstep(square_mission, ekf_ready_after_s=1.0)  # a board of its own, made before the key is known
    key = blackboard.Key("/plugin/test_two_boards/count", 7, "test", "a count")
    try:
        first.runtime.board.install()
        blackboard.declare(key)  # as a node of the first runtime's tree does
        second.runtime.board.install()
        blackboard.declare(key)  # as a node of the second's does
        assert blackboard.reader("test", [key.name]).get(key.name) == 7
    finally:
        del blackboard.KEYS[key.name]
