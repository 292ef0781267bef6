"""``replay --web``: a recorded run on the live view's page, any tick on request."""

from __future__ import annotations

import asyncio
import json

import pytest

from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.observers.snapshots import Recording, SnapshotRecorder, replay, snapshot_recorder
from executive.observers.web.feed import Seen
from executive.observers.web.replay import ReplaySource
from executive.observers.web.server import WebAddress, WebServer
from tests_support import line_mission


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A whole line mission recorded tick by tick (keyframes every 50 ticks, as a long run has them every 100)."""
    from executive.testing import Lockstep
    from executive.world import blackboard

    blackboard.reset()
    path = tmp_path_factory.mktemp("replay") / "run.snap"
    recorder = SnapshotRecorder(path, keyframe_every=50)
    sim = Lockstep(line_mission("replayed"), plugs=[snapshot_recorder(recorder)])
    try:
        outcome = sim.run_to_end(300.0)
    finally:
        sim.close()
        recorder.close()
    return path, outcome


@pytest.mark.xdist_group("replay_web_recorded")
def test_the_index_gives_every_tick_as_a_replay_from_the_start_does(recorded):
    path, _ = recorded
    recording = Recording(path)
    for tick in (recording.first, recording.first + 49, recording.first + 50, 123, recording.last):
        indexed, whole = recording.state_at(tick), replay(path, tick)
        assert (indexed.tick, indexed.t, indexed.status, indexed.feedback, indexed.blackboard) == (
            whole.tick,
            whole.t,
            whole.status,
            whole.feedback,
            whole.blackboard,
        )
    with pytest.raises(LookupError, match=f"ticks {recording.first} to {recording.last}"):
        recording.state_at(recording.last + 1)


@pytest.mark.xdist_group("replay_web_recorded")
def test_a_frame_shows_that_tick_the_track_so_far_and_the_targets(recorded):
    path, outcome = recorded
    assert outcome.status is MissionStatus.COMPLETED
    source = ReplaySource(str(path))
    end = source.frame(None)
    # the last tick as the run ended (issue 28: RUNNING, the state before the end was declared after the tick)
    assert end.tick == source.recording.last and (end.status["state"], end.status["reason"]) == ("COMPLETED", "every waypoint reached")
    names = [node["name"] for node in end.tree.to_json()["nodes"]]
    assert end.statuses[names.index("For each leg")] == "S"
    plan = end.plan.to_json()
    assert [round(n) for _, n in plan["route"]] == [25, 50, 75, 100]  # relative to where the vehicle was first seen: home
    middle = source.frame(200)
    assert middle.tick == 200 and 0 < middle.track.length < end.track.length
    assert middle.here == middle.track.points[middle.track.length - 1]
    assert middle.status["mode"] == "GUIDED" and middle.status["armed"] and middle.status["link_up"]
    waiting = middle.status["waiting"]  # as the run published it (executive.tree.waiting; the recorded text is cut at 160 characters)
    assert (waiting["node"], waiting["path"]) == ("Go to waypoint", "Mission/Run/Guarded route or hold/Guarded route/For each leg/Leg/Go to waypoint")
    assert waiting["feedback"].startswith("leg 2/4: ")
    seen = Seen()
    first, back = end.message(seen), middle.message(seen)
    assert first["track"]["restart"] and back["track"]["restart"]  # going back sends the shorter track whole
    assert len(back["track"]["points"]) == middle.track.length


@pytest.mark.xdist_group("replay_web_recorded")
def test_the_slider_asks_for_ticks_over_the_websocket(recorded):
    from aiohttp import ClientSession

    path, _ = recorded
    server = WebServer(WebAddress("127.0.0.1", 0))
    server.start(ReplaySource(str(path)))

    async def browse() -> list[dict]:
        async with ClientSession() as session, session.ws_connect(f"{server.url}ws") as ws:
            got = [json.loads((await ws.receive()).data) for _ in range(2)]  # hello, the last tick
            await ws.send_str(json.dumps({"tick": 100}))
            got.append(json.loads((await ws.receive()).data))
            return got

    try:
        hello, last, asked = asyncio.run(asyncio.wait_for(browse(), 30))
    finally:
        server.close()
    assert hello["hello"] == "replay" and hello["requests"] == [] and hello["first"] == 0
    assert last["tick"] == hello["last"] and "tree" in last
    assert asked["tick"] == 100 and "tree" not in asked  # the same tree: not sent again


def test_replay_web_errors(tmp_path, capsys):
    assert main(["replay", str(tmp_path / "none.snap"), "--web", "0"]) == 2
    assert "no such snapshot file" in capsys.readouterr().err
    empty = tmp_path / "empty.snap"
    empty.write_text('{"tree": []}\n')
    assert main(["replay", str(empty), "--web", "0"]) == 2
    assert "no tick recorded" in capsys.readouterr().err
    assert main(["replay", str(empty), "--web", "localhost:port"]) == 2
    assert "not a number" in capsys.readouterr().err


def test_replay_web_names_a_journal_as_replay_does(tmp_path, capsys):
    journal = tmp_path / "run.db"
    journal.write_bytes(b"SQLite format 3\x00" + bytes(100))
    assert main(["replay", str(journal), "--web", "0"]) == 2
    assert f"{journal}:1:1: (snapshot): this is a journal (SQLite), not a snapshot file" in capsys.readouterr().err
