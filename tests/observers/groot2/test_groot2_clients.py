"""Real clients and a real publisher: btview against BehaviorTree.CPP's own Groot2Publisher and ours; `run --groot2`, `replay --groot2`.

behaviortreepy 0.1.4's Groot2Publisher answers FULLTREE, STATUS and BLACKBOARD and refuses the hooks and
recording requests ("Request not recognized"), which later BehaviorTree.CPP answers: those are
compared with BehaviorTree.CPP's source in test_groot2_monitor.py, not with this build.
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import py_trees
import pytest
from btview.client import ConnectionError_, Groot2Client
from btview.model import NodeStatus
from btview.protocol.groot2 import ProtocolError as ClientProtocolError
from btview.protocol.groot2 import RequestType as ClientRequestType
from test_groot2_monitor import free_port_pair

from executive.cli import main
from executive.observers.groot2.model import CODES, behaviours_in_order, from_tree
from executive.observers.groot2.server import Groot2Address, Groot2Server
from executive.observers.groot2.view import MonitorView
from executive.sim import SimServer
from tests_support import executive_process

bt = pytest.importorskip("behaviortreepy", reason="BehaviorTree.CPP's Python bindings are a test dependency ('.[test]')")
ROOT = Path(__file__).parents[3]

# The same shape on both sides: a reactive sequence of a fallback (a failing and a running action) and an action never reached.
BTCPP_XML = """<root BTCPP_format="4" main_tree_to_execute="MainTree"><BehaviorTree ID="MainTree">
<ReactiveSequence name="root"><Fallback name="either"><Fails name="first"/><Runs name="second"/></Fallback><Succeeds name="then"/></ReactiveSequence>
</BehaviorTree></root>"""


def our_tree() -> py_trees.behaviour.Behaviour:
    either = py_trees.composites.Selector(
        "either", memory=True, children=[py_trees.behaviours.Failure(name="first"), py_trees.behaviours.Running(name="second")]
    )
    return py_trees.composites.Sequence("root", memory=False, children=[either, py_trees.behaviours.Success(name="then")])


def answers(client: Groot2Client) -> dict[str, object]:
    """What a client reads: the tree's shape and kinds, the statuses by node name, the blackboard's form, a recording's form."""
    tree = client.fetch_tree()
    names = {uid: node.name for uid, node in tree.by_uid.items()}
    statuses = {names[uid]: state.status for uid, state in client.poll().statuses.items()}
    board = client.fetch_blackboard(["MainTree", "NoSuchTree"])
    return {
        "shape": [(node.name, node.kind, len(node.children)) for node in tree.walk()],
        "statuses": statuses,
        "blackboards": sorted(board) if isinstance(board, dict) else board,
        "uuid": len(client.tree_uuid) == 32,
    }


def test_btview_reads_the_same_kinds_of_answers_from_behaviortree_cpp_and_from_us() -> None:
    factory = bt.BehaviorTreeFactory()
    factory.register_simple_action("Fails", lambda node: bt.NodeStatus.FAILURE)
    factory.register_simple_stateful_action("Runs", lambda node: bt.NodeStatus.RUNNING, lambda node: bt.NodeStatus.RUNNING)
    factory.register_simple_action("Succeeds", lambda node: bt.NodeStatus.SUCCESS)
    theirs_port, ours_port = free_port_pair(), None
    tree = factory.create_tree_from_text(BTCPP_XML)
    publisher = bt.Groot2Publisher(tree, theirs_port)
    tree.tick_once()

    ours_port = free_port_pair()
    while ours_port in (theirs_port, theirs_port + 1):
        ours_port = free_port_pair()
    root = our_tree()
    root.tick_once()
    view = MonitorView()
    view.show_tree(from_tree(root))
    view.ticked([CODES.get(node.status) for node in behaviours_in_order(root)], 0.0)
    server = Groot2Server(Groot2Address("127.0.0.1", ours_port), view)
    server.start()
    theirs, ours = Groot2Client("127.0.0.1", theirs_port, timeout_ms=5000), Groot2Client("127.0.0.1", ours_port, timeout_ms=5000)
    try:
        a, b = answers(theirs), answers(ours)
    finally:
        theirs.close()
        ours.close()
        server.close()
        del publisher
    assert a == b
    assert a["blackboards"] == ["MainTree"]  # the subtree asked for, the unknown one left out
    assert a["statuses"] == {
        "root": NodeStatus.RUNNING,
        "either": NodeStatus.RUNNING,
        "first": NodeStatus.FAILURE,
        "second": NodeStatus.RUNNING,
        "then": NodeStatus.IDLE,
    }


def poll_until(client: Groot2Client, predicate, timeout_s: float = 120.0):
    """Ask again until ``predicate(answer)`` holds (wall time bounds only a hung process; what is waited for is what the client reads)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            answer = predicate()
        except (ConnectionError_, ClientProtocolError):
            answer = None
        if answer:
            return answer
        time.sleep(0.05)
    pytest.fail("the publisher never gave the expected answer")


def test_btview_watches_a_real_run_of_executive_run_groot2(tmp_path) -> None:
    port = free_port_pair()
    run = executive_process("run", "missions/rover_square.yaml", "--speedup", "20", "--socket", "none", "--groot2", str(port))
    client = Groot2Client("127.0.0.1", port, timeout_ms=2000)
    try:
        tree = poll_until(client, client.fetch_tree)
        go = next(node.uid for node in tree.by_uid.values() if node.registration == "go_to")
        assert client._exchange(ClientRequestType.TOGGLE_RECORDING, b"start")[1].isdigit()
        poll_until(client, lambda: client.poll().statuses[go].status == NodeStatus.RUNNING)  # live statuses: a leg under way...
        kept: list[tuple[int, int]] = []

        def go_to_reached() -> bool:  # ...then reached: a tick's SUCCESS, kept among the transitions however late the client asks
            raw = client._exchange(ClientRequestType.GET_TRANSITIONS)[1]
            kept.extend((raw[i + 6] | raw[i + 7] << 8, raw[i + 8]) for i in range(0, len(raw), 9))
            return (go, 2) in kept

        poll_until(client, go_to_reached)
    finally:
        client.close()
        run.send_signal(signal.SIGINT)
        _, err = run.communicate(timeout=120)
    assert f"Groot2 can connect to 127.0.0.1 port {port} (publisher {port + 1})" in err


@pytest.mark.xdist_group("groot2_unmonitored")
def test_replay_groot2_plays_a_recording_to_btview(rover_square_two_legs_jsonl: Path) -> None:
    path = rover_square_two_legs_jsonl  # rover_square's first two legs: a recording long enough to play
    port = free_port_pair()
    replay = executive_process("replay", str(path), "--groot2", str(port), "--speed", "20")
    client = Groot2Client("127.0.0.1", port, timeout_ms=2000)
    try:
        tree = poll_until(client, client.fetch_tree)
        assert len(tree.by_uid) > 10 and tree.by_uid[1].name
        seen: list[list[NodeStatus]] = []

        def statuses_change() -> bool:
            now = [state.status for state in client.poll().statuses.values()]
            if not seen or seen[-1] != now:
                seen.append(now)
            return len(seen) >= 3

        poll_until(client, statuses_change)
    finally:
        client.close()
        replay.send_signal(signal.SIGTERM)
        _, err = replay.communicate(timeout=60)
    assert replay.returncode == 0, err
    assert f"for Groot2 on 127.0.0.1 port {port}" in err


@pytest.mark.parametrize(("value", "why"), [("x:y", "'y' is not a port number"), ("65535", "the port must be 1 to 65534")])
def test_a_bad_groot2_address_is_refused_before_anything_starts(
    value: str, why: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # in this process, as test_web_server.py's --web errors (the exit code is main's: test_mission_files.py runs the real command)
    monkeypatch.setattr(SimServer, "start", lambda server: pytest.fail("the simulator started"))
    assert main(["run", str(ROOT / "missions" / "rover_square.yaml"), "--groot2", value, "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert why in err and "--groot2" in err
