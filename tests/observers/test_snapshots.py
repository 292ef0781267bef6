"""Per-tick snapshots: compact deltas, bounded files, and a replay that shows the tree as it was."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours import LinkAlive
from executive.cli import main
from executive.observers.snapshots import SnapshotRecorder, render, replay


class Counter(py_trees.behaviour.Behaviour):
    """RUNNING for three ticks, then SUCCESS; says how far it got."""

    def initialise(self) -> None:
        self.n = 0

    def update(self) -> Status:
        self.n += 1
        self.feedback_message = f"step {self.n}"
        return Status.SUCCESS if self.n == 3 else Status.RUNNING


@pytest.fixture
def recorded(tmp_path, vehicle):
    """Ten ticks of a small tree, recorded; returns (path, what each tick looked like)."""
    root = py_trees.composites.Sequence("Mission", memory=False, children=[LinkAlive(), Counter("Count")])
    tree = py_trees.trees.BehaviourTree(root)
    path = tmp_path / "run.snap"
    recorder = SnapshotRecorder(path, keyframe_every=4)
    recorder.attach(root)
    seen = []
    for tick in range(10):
        vehicle.set(link__up=tick not in (4, 5))
        tree.tick()
        recorder.record(tick, tick * 0.1)
        seen.append([(n.name, n.status) for n in (root, *root.children)])
    recorder.close()
    return path, seen


def test_replay_reproduces_every_tick(recorded):
    path, seen = recorded
    symbol = {Status.SUCCESS: "S", Status.FAILURE: "F", Status.RUNNING: "R", Status.INVALID: "-"}
    for tick, expected in enumerate(seen):
        state = replay(path, tick)
        got = [(node["name"], state.status[node["id"]]) for node in state.nodes]
        assert got == [(name, symbol[status]) for name, status in expected], tick


def test_replay_shows_feedback_and_the_blackboard_changes_of_that_tick(recorded):
    path, _ = recorded
    text = "\n".join(render(replay(path, 4)))
    assert "✕ Link alive? -- no heartbeat from the autopilot" in text
    assert "/link/up: False" in text.split("blackboard")[1]
    assert "/link/up" not in "\n".join(render(replay(path, 5))).split("blackboard")[1]  # unchanged at tick 5


def test_lines_hold_only_what_changed(recorded):
    path, _ = recorded
    lines = path.read_text().splitlines()
    assert lines[0].startswith('{"tree"')
    quiet = [line for line in lines[1:] if '"key"' not in line]
    assert all(len(line) < len(lines[1]) for line in quiet)  # deltas are smaller than a keyframe


def test_files_are_bounded_by_rotation(tmp_path, vehicle):
    root = py_trees.composites.Sequence("Mission", memory=False, children=[LinkAlive(), Counter("Count")])
    tree = py_trees.trees.BehaviourTree(root)
    path = tmp_path / "run.snap"
    recorder = SnapshotRecorder(path, max_bytes=20_000, keyframe_every=10)
    recorder.attach(root)
    for tick in range(2000):
        vehicle.set(link__up=tick % 3 != 0)
        tree.tick()
        recorder.record(tick, tick * 0.1)
    recorder.close()
    rotated = tmp_path / "run.snap.1"
    assert rotated.exists()
    assert path.stat().st_size <= 20_000 + 5_000 and rotated.stat().st_size <= 20_000 + 5_000
    assert replay(path).tick == 1999
    with pytest.raises(LookupError):
        replay(path, 3)  # rotated away long ago


def test_cli_replay(recorded, capsys, tmp_path):
    path, _ = recorded
    assert main(["replay", str(path), "--tick", "1"]) == 0
    assert capsys.readouterr().out.startswith("tick 1 at 0.1 s\n* Mission\n    ✓ Link alive? -- ok\n    * Count -- step 2\n")
    assert main(["replay", str(path), "--tick", "99"]) == 2
    assert main(["replay", str(tmp_path / "nothing.snap")]) == 2
    broken = tmp_path / "broken.snap"
    broken.write_text('{"tree": []}\n{"tick": 0, \n')
    assert main(["replay", str(broken)]) == 2
    assert f"{broken}:2:" in capsys.readouterr().err
