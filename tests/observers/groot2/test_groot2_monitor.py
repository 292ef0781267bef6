"""Groot2 watches the executive: what a Groot2-protocol client (btview's) is told, in lock-step and tick by tick."""

from __future__ import annotations

import hashlib
import socket
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import py_trees
import pytest
import zmq
from btview.client import Groot2Client
from btview.model import NodeKind, NodeStatus
from btview.protocol.groot2 import ProtocolError as ClientProtocolError
from btview.protocol.groot2 import RequestType as ClientRequestType

from executive.behaviours.flow import Timeout
from executive.mission.loader import load_mission
from executive.observers.groot2.live import groot2_monitor
from executive.observers.groot2.model import from_tree, to_xml
from executive.observers.groot2.protocol import RequestHeader, RequestType
from executive.observers.groot2.server import Groot2Address, Groot2Server
from executive.observers.groot2.view import MonitorView
from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
from executive.testing.lockstep import Lockstep

ROOT = Path(__file__).parents[3]


def free_port_pair() -> int:
    """A port whose next one is free too (the publisher's)."""
    for _ in range(50):
        with socket.socket() as a:
            a.bind(("127.0.0.1", 0))
            port = a.getsockname()[1]
            if port >= 65535:
                continue
            with socket.socket() as b:
                try:
                    b.bind(("127.0.0.1", port + 1))
                except OSError:
                    continue
        return port
    raise RuntimeError("no two free ports in a row")


@pytest.fixture
def served():
    """A MonitorView served on free ports, and a btview Groot2 client of it."""
    port = free_port_pair()
    view = MonitorView()
    server = Groot2Server(Groot2Address("127.0.0.1", port), view)
    server.start()
    client = Groot2Client("127.0.0.1", port, timeout_ms=5000)
    yield view, client, server
    client.close()
    server.close()


def rover_square(view: MonitorView | None, recorder: SnapshotRecorder | None = None, legs: int = 4) -> Lockstep:
    """rover_square, or its first ``legs`` legs, watched by ``view`` and recorded by ``recorder`` if given."""
    mission = load_mission(ROOT / "missions/rover_square.yaml")
    mission = mission.model_copy(update={"waypoints": mission.waypoints[:legs]})
    plugs = [groot2_monitor(view)] if view is not None else []
    plugs += [snapshot_recorder(recorder)] if recorder is not None else []
    return Lockstep(mission, mission_dir=ROOT / "missions", plugs=plugs)


#: A run with a turn (north, then east): what the recorded-bytes and replay tests need, in half the square's vehicle time (the
#: unwatched run is conftest's ``rover_square_two_legs_jsonl``).
TWO_LEGS = 2


def by_name(tree, name: str):
    return next(node for node in tree.by_uid.values() if node.name == name)


def transitions(raw: bytes) -> list[tuple[int, int, int]]:
    assert len(raw) % 9 == 0
    return [(int.from_bytes(raw[i : i + 6], "little"), *struct.unpack("<HB", raw[i + 6 : i + 9])) for i in range(0, len(raw), 9)]


# -- the running tree, tick by tick ------------------------------------------------------------------------


def test_a_client_sees_the_running_tree_its_statuses_and_the_blackboard(served) -> None:
    view, client, _ = served
    sim = rover_square(view)
    sim.run(300, until=lambda: sim.runtime.mission_state.legs.leg_index >= 1)
    t = sim.clock.now()
    sim.run(300, until=lambda: sim.clock.now() >= t + 1.0)  # a second into the second leg
    assert sim.runtime.tree is not None
    root = sim.runtime.tree.root
    tree = client.fetch_tree()
    nodes = list(root.iterate())
    assert len(tree.by_uid) == len(nodes)  # every node, uids 1.. in pre-order
    assert sorted(tree.by_uid) == list(range(1, len(nodes) + 1))
    go = by_name(tree, "Go to waypoint")
    assert (go.registration, go.kind) == ("go_to", NodeKind.ACTION)
    assert go.ports.get("look_ahead") == "true"  # the port it was built with
    assert by_name(tree, "EKF ok?").kind == NodeKind.CONDITION
    assert {n.registration for n in tree.by_uid.values()} >= {"ReactiveSequence", "Sequence"}  # py_trees' composites as their built-ins

    statuses = client.poll().statuses
    assert statuses[go.uid].status == NodeStatus.RUNNING  # the second leg under way
    assert statuses[1].status == NodeStatus.RUNNING

    client.fetch_blackboard(["MainTree"])  # the first ask (no tick meanwhile: lock-step) starts the copies...
    now = sim.clock.now()
    sim.run(300, until=lambda: sim.clock.now() > now)  # ...which the next tick makes
    board = client.fetch_blackboard(["MainTree", "Other"])["MainTree"]
    assert board["/mission/leg_index"] == 1
    assert board["/vehicle/mode"] == "GUIDED"
    assert set(client.fetch_blackboard(["Other"])) == set()  # no such subtree: left out, as BehaviorTree.CPP does


def test_a_recording_client_gets_each_transition_in_vehicle_time(served) -> None:
    view, client, server = served
    sim = rover_square(view)
    sim.run(300, until=lambda: sim.runtime.mission_state.legs.leg_index >= 1)
    started = client._exchange(ClientRequestType.TOGGLE_RECORDING, b"start")[1]
    assert started.isdigit()  # the wall time in µs the client counts from
    t0 = sim.clock.now()
    sim.run(300, until=lambda: sim.runtime.mission_state.legs.leg_index >= 2)
    elapsed_us = (sim.clock.now() - t0) * 1e6
    kept = transitions(client._exchange(ClientRequestType.GET_TRANSITIONS)[1])
    go = by_name(client.fetch_tree(), "Go to waypoint").uid
    assert (go, 2) in [(uid, status) for _, uid, status in kept]  # leg 2 reached: SUCCESS
    assert (go, 1) in [(uid, status) for _, uid, status in kept]  # and the next leg's go-to RUNNING again
    times = [us for us, _, _ in kept]
    assert times == sorted(times) and 0 < times[-1] <= elapsed_us + 1
    assert all(abs(us / 100_000 - round(us / 100_000)) < 1e-3 for us in times)  # on the 10 Hz ticks of vehicle time
    assert transitions(client._exchange(ClientRequestType.GET_TRANSITIONS)[1]) == []  # taken once
    stop = RequestHeader(2, RequestType.TOGGLE_RECORDING, 5)
    assert server.answer([stop.encode(), b"stop"]) == [stop.encode() + view.tree_uuid]  # the header alone, as BehaviorTree.CPP answers
    assert view.recording is False


@pytest.mark.xdist_group("groot2_unmonitored")
def test_a_stalled_client_changes_nothing(tmp_path: Path, rover_square_two_legs_jsonl: Path) -> None:
    """The same run with a monitor whose clients never read their replies, or send garbage, records the same bytes."""
    port = free_port_pair()
    path = tmp_path / "monitored.jsonl"
    recorder = SnapshotRecorder(path)
    view = MonitorView()
    server = Groot2Server(Groot2Address("127.0.0.1", port), view)
    context = zmq.Context()
    try:
        server.start()
        stalled = context.socket(zmq.REQ)
        stalled.connect(f"tcp://127.0.0.1:{port}")
        stalled.send(RequestHeader(2, RequestType.STATUS, 7).encode())  # ...and never reads the answer
        garbage = socket.create_connection(("127.0.0.1", port))
        garbage.sendall(b"\xff" * 4096)  # not ZeroMQ at all
        view.start_recording()  # transitions pile up, never taken
        with rover_square(view, recorder, legs=TWO_LEGS) as sim:
            outcome = sim.run_to_end(600)
        assert outcome.status.name == "COMPLETED"
    finally:
        recorder.close()
        garbage.close()
        server.close()
        context.destroy(linger=0)
    assert hashlib.sha256(path.read_bytes()).hexdigest() == hashlib.sha256(rover_square_two_legs_jsonl.read_bytes()).hexdigest()


# -- the protocol's edges ----------------------------------------------------------------------------------


def test_requests_outside_what_we_serve_get_an_error_reply_and_the_server_goes_on(served) -> None:
    view, client, server = served
    with pytest.raises(ClientProtocolError, match="no tree is running yet"):
        client.fetch_tree()
    assert server.answer([b"12345"]) == [b"error", b"wrong request header"]
    assert server.answer([RequestHeader(3, RequestType.STATUS, 1).encode()])[0] == b"error"
    assert server.answer([RequestHeader(2, RequestType.HOOK_INSERT, 1).encode(), b"{}"])[1].startswith(b"breakpoints are not supported")
    assert server.answer([RequestHeader(2, RequestType.BLACKBOARD, 1).encode()]) == [b"error", b"must be 2 parts message"]
    assert server.answer([RequestHeader(2, ord("Z"), 1).encode()]) == [b"error", b"Request not recognized"]
    head, hooks = server.answer([RequestHeader(2, RequestType.HOOKS_DUMP, 9).encode()])
    assert (head[:6], hooks) == (RequestHeader(2, RequestType.HOOKS_DUMP, 9).encode(), b"[]")  # the request echoed, then the UUID
    assert len(head) == 22
    view.show_tree(from_tree(py_trees.behaviours.Success(name="only")))
    assert [n.name for n in client.fetch_tree().by_uid.values()] == ["only"]  # still serving


def test_py_trees_composites_are_shown_as_the_built_ins_that_mean_the_same() -> None:
    leaf = py_trees.behaviours.Running
    root = py_trees.composites.Sequence(
        "root",
        memory=False,
        children=[
            py_trees.composites.Sequence("steps", memory=True, children=[leaf("a")]),
            py_trees.composites.Selector("either", memory=False, children=[leaf("b")]),
            py_trees.composites.Selector("in turn", memory=True, children=[leaf("c")]),
            py_trees.composites.Parallel("both", policy=py_trees.common.ParallelPolicy.SuccessOnOne(), children=[leaf("d")]),
            py_trees.decorators.Inverter("not", child=leaf("e")),
            py_trees.decorators.Retry("again", child=leaf("f"), num_failures=3),
            py_trees.decorators.Repeat("repeat", child=leaf("g"), num_success=2),
            Timeout(leaf("h"), 2.5, name="within"),
            py_trees.decorators.OneShot("first time", child=leaf("i"), policy=py_trees.common.OneShotPolicy.ON_SUCCESSFUL_COMPLETION),
        ],
    )
    doc = ET.fromstring(to_xml(from_tree(root)))
    tags = {e.get("name"): (e.tag, {k: v for k, v in e.attrib.items() if not k.startswith("_") and k != "name"}) for e in doc.iter() if e.get("_uid")}
    assert tags["root"] == ("ReactiveSequence", {})
    assert tags["steps"] == ("Sequence", {})
    assert tags["either"] == ("ReactiveFallback", {})
    assert tags["in turn"] == ("Fallback", {})
    assert tags["both"] == ("Parallel", {"success_count": "1", "failure_count": "1"})
    assert tags["not"] == ("Inverter", {})
    assert tags["again"] == ("RetryUntilSuccessful", {"num_attempts": "3"})
    assert tags["repeat"] == ("Repeat", {"num_cycles": "2"})
    assert tags["within"] == ("Timeout", {"msec": "2500"})
    assert tags["a"] == ("Running", {})
    model = doc.find("TreeNodesModel")
    assert tags["first time"] == ("OneShot", {})  # not RunOnce: BehaviorTree.CPP's keeps a first FAILURE, ours ticks again
    assert model is not None and [(e.tag, e.get("ID")) for e in model] == [("Decorator", "OneShot"), ("Action", "Running")]  # built-ins: not declared


def test_a_node_no_longer_ticked_is_idle_after_what_it_was(served) -> None:
    view, client, _ = served
    root = py_trees.composites.Selector("root", memory=False, children=[py_trees.behaviours.Success(name="first")])
    view.show_tree(from_tree(root))
    view.ticked([2, 2], 0.0)
    assert [s.status for s in client.poll().statuses.values()] == [NodeStatus.SUCCESS, NodeStatus.SUCCESS]
    view.ticked([None, None], 0.1)
    states = list(client.poll().statuses.values())
    assert [(s.status, s.previous) for s in states] == [(NodeStatus.IDLE, NodeStatus.SUCCESS)] * 2


@pytest.mark.xdist_group("groot2_unmonitored")
def test_a_replay_shows_each_tick_once_its_recorded_time_has_passed(rover_square_two_legs_jsonl: Path) -> None:
    """The pace of replay --groot2, on an injected wait (no wall clock): the tick before is shown during each gap."""
    from executive.observers.groot2.replay import ReplayFeed
    from executive.observers.snapshots import Recording

    recording = Recording(rover_square_two_legs_jsonl)
    feed = ReplayFeed(recording, MonitorView(), speed=2.0)
    waits: list[tuple[float, int | None]] = []
    feed._play(wait=lambda s: waits.append((s, feed.position)) is not None)
    first, second, third = recording.ticks[:3]
    times = [recording.state_at(t).t for t in (first, second, third)]
    assert waits[:2] == [((times[1] - times[0]) / 2.0, first), ((times[2] - times[1]) / 2.0, second)]
    assert feed.position == recording.last and len(waits) == len(recording.ticks) - 1
