"""goto_sample written in YAML (missions/asv_sampling_yaml_tree.yaml) behaves exactly as the Python builder: tick by tick, command by command.

Both trees run the same mission on the simulated boat (Lockstep: vehicle time, deterministic); each
tick's every node (name, type, status, feedback) and every message sent to the vehicle are traced,
and the two traces must be equal, whatever happens: an EKF dropout, a link loss, an RC take-over.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import py_trees
import pytest

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.observers.journal import Journal, journal_recorder
from executive.observers.snapshots import SnapshotRecorder, render, replay, snapshot_recorder
from executive.runtime.assembly import Wiring
from executive.runtime.loop import behaviour_path
from executive.sim.faults import Fault, LinkLoss, RcTakeover
from executive.testing import Lockstep
from executive.world.clock import Clock, ManualClock

MISSIONS = Path(__file__).parents[2] / "missions"
EXAMPLE = MISSIONS / "asv_sampling_yaml_tree.yaml"


class Trace:
    """The tree's nodes (path, type), each tick's statuses and feedback, and every message the runtime sends, with the vehicle time."""

    def __init__(self) -> None:
        self.nodes: list[py_trees.behaviour.Behaviour] = []
        self.shape: list[tuple[str, str]] = []
        self.ticks: list[tuple[float, tuple[tuple[str, str], ...]]] = []
        self.sent: list[tuple[float, str, bytes]] = []

    def plug(self, wiring: Wiring) -> None:
        wiring.observers.append(self)

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        self.nodes = list(root.iterate())
        self.shape = [(behaviour_path(n), type(n).__name__) for n in self.nodes]

    def ticked(self, tick: int, now: float) -> None:
        self.ticks.append((now, tuple((n.status.name, n.feedback_message) for n in self.nodes)))

    def end(self, status: str, reason: str) -> None:
        pass


def run(mission: Mission, events: Sequence[Fault], keep: Path | None = None) -> tuple[Trace, MissionStatus, str]:
    """The mission to its end on the simulated boat, traced; with ``keep``, journalled and snapshotted there too."""
    trace = Trace()

    def plugs(clock: Clock) -> dict[str, Any]:
        if keep is None:
            return {"plugs": [trace.plug]}
        recorder = SnapshotRecorder(keep / "snapshots.jsonl")
        return {"plugs": [trace.plug, journal_recorder(Journal(keep / "journal.db", clock)), snapshot_recorder(recorder)]}

    with Lockstep(mission, mission_dir=MISSIONS, events=events, options_for_clock=plugs) as ls:
        ls.uplink.packed = True
        carry = ls.uplink.carry

        def recorded(messages: Any) -> Any:
            carried = carry(messages)
            trace.sent += [(ls.clock.now(), m.get_type(), bytes(m.get_msgbuf())) for m in carried]  # packed: every field, as sent
            return carried

        ls.uplink.carry = recorded  # type: ignore[method-assign]
        outcome = ls.run_to_end(limit_s=400)
    return trace, outcome.status, outcome.reason


@pytest.fixture(scope="module")
def composed() -> Mission:
    mission = load_mission(EXAMPLE)
    assert isinstance(mission.tree, dict)
    return mission


SCENARIOS = {
    "the example: an EKF dropout waited out in MANUAL": ([], MissionStatus.COMPLETED),
    "a link loss held, then an RC take-over ends the go-to": (
        [LinkLoss(kind="link_loss", at_s=58, for_s=5), RcTakeover(kind="rc_takeover", at_s=95, for_s=10, channel=6, pwm=1900)],
        MissionStatus.ABORTED,
    ),
}


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_the_yaml_tree_and_the_python_builder_tick_and_command_alike(composed: Mission, scenario: str, tmp_path: Path) -> None:
    events, expected = SCENARIOS[scenario]
    named = composed.model_copy(update={"tree": "goto_sample"})
    (tmp_path / "yaml").mkdir(), (tmp_path / "python").mkdir()
    yaml_trace, yaml_status, yaml_reason = run(composed, events, tmp_path / "yaml")
    python_trace, python_status, python_reason = run(named, events, tmp_path / "python")
    assert (yaml_status, python_status) == (expected, expected)
    assert yaml_reason == python_reason
    assert yaml_trace.shape == python_trace.shape
    assert len(yaml_trace.ticks) == len(python_trace.ticks) > 500
    for (t, yaml_nodes), (_, python_nodes) in zip(yaml_trace.ticks, python_trace.ticks, strict=True):
        assert yaml_nodes == python_nodes, f"the trees differ at {t:.1f} s"
    assert yaml_trace.sent == python_trace.sent
    kinds = {kind for _, kind, _ in yaml_trace.sent}
    assert {"COMMAND_LONG", "SET_POSITION_TARGET_GLOBAL_INT"} <= kinds  # modes, arming and the path itself were compared
    # the journal and the snapshots (executive report, executive replay) see the same run
    snapshots = [(tmp_path / tree / "snapshots.jsonl").read_text() for tree in ("yaml", "python")]
    assert snapshots[0] == snapshots[1] and snapshots[0].count("\n") > 500  # every tick's statuses, feedback and blackboard
    same = ("outcome", "reason", "transitions", "legs", "samples", "events", "routes")
    reports = [{k: v for k, v in Journal(tmp_path / tree / "journal.db", ManualClock()).report().items() if k in same} for tree in ("yaml", "python")]
    assert reports[0] == reports[1] and reports[0]["outcome"] == expected.value
    shown = "\n".join(render(replay(tmp_path / "yaml" / "snapshots.jsonl", 500)))  # executive replay, mid-run
    assert "Wait in MANUAL" in shown and "Guarded path or hold" in shown


def test_the_example_s_tree_is_the_python_builder_s_node_for_node(composed: Mission) -> None:
    from executive.tree import select as mission_tree

    def shape(node: py_trees.behaviour.Behaviour) -> list[tuple[str, str, Any]]:
        return [(behaviour_path(n), type(n).__name__, getattr(n, "memory", None)) for n in node.iterate()]

    assert shape(mission_tree.build(composed)) == shape(mission_tree.build(composed.model_copy(update={"tree": "goto_sample"})))
