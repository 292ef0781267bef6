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

from executive.assembly import Wiring
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.runtime import behaviour_path
from executive.sim.faults import Fault, LinkLoss, RcTakeover
from executive.testing import Lockstep

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


def run(mission: Mission, events: Sequence[Fault]) -> tuple[Trace, MissionStatus, str]:
    trace = Trace()
    with Lockstep(mission, mission_dir=MISSIONS, events=events, plugs=[trace.plug]) as ls:
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
def test_the_yaml_tree_and_the_python_builder_tick_and_command_alike(composed: Mission, scenario: str) -> None:
    events, expected = SCENARIOS[scenario]
    named = composed.model_copy(update={"tree": "goto_sample"})
    yaml_trace, yaml_status, yaml_reason = run(composed, events)
    python_trace, python_status, python_reason = run(named, events)
    assert (yaml_status, python_status) == (expected, expected)
    assert yaml_reason == python_reason
    assert yaml_trace.shape == python_trace.shape
    assert len(yaml_trace.ticks) == len(python_trace.ticks) > 500
    for (t, yaml_nodes), (_, python_nodes) in zip(yaml_trace.ticks, python_trace.ticks, strict=True):
        assert yaml_nodes == python_nodes, f"the trees differ at {t:.1f} s"
    assert yaml_trace.sent == python_trace.sent
    kinds = {kind for _, kind, _ in yaml_trace.sent}
    assert {"COMMAND_LONG", "SET_POSITION_TARGET_GLOBAL_INT"} <= kinds  # modes, arming and the path itself were compared


def test_the_example_s_tree_is_the_python_builder_s_node_for_node(composed: Mission) -> None:
    import trees

    def shape(node: py_trees.behaviour.Behaviour) -> list[tuple[str, str, Any]]:
        return [(behaviour_path(n), type(n).__name__, getattr(n, "memory", None)) for n in node.iterate()]

    assert shape(trees.build(composed)) == shape(trees.build(composed.model_copy(update={"tree": "goto_sample"})))
