"""`run --foxglove PORT`: the run served live to Foxglove's own WebSocket client (@foxglove/ws-protocol, driven by node).

The client is Foxglove's npm package, installed by `.ci/run` (`npm ci --prefix tests/observers/foxglove`): these tests fail, not skip,
without it. The mission runs lock-step; the client reads on its own (node's) time.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.observers.foxglove.live import FoxgloveSink
from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
from executive.testing import Lockstep
from executive.world.clock import Clock
from tests_support import foxglove_js, line_mission


class NodeClient:
    """``node client.js URL``: Foxglove's client subscribed to every channel; its JSON lines read back."""

    def __init__(self, url: str, *flags: str) -> None:
        self.proc = subprocess.Popen(foxglove_js("client.js", url, *flags), stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.proc.stdout is not None
        self.first = json.loads(self.proc.stdout.readline())  # subscribed to what the server advertised when it connected

    def done(self) -> list[dict[str, Any]]:
        """Every line it printed, once it ended (at the mission's end, or now)."""
        out, _ = self.proc.communicate(timeout=60)  # stdin closed: it ends at once if it has not already
        return [self.first, *(json.loads(line) for line in out.splitlines())]

    def kill(self) -> None:
        self.proc.kill()
        self.proc.wait()


def run(path: Path | None, live: FoxgloveSink | None, waypoints: int = 4, served_by: FoxgloveSink | None = None) -> MissionStatus:
    """The line mission, lock-step, recorded to ``path`` (and served on ``live``); ``served_by``: also served by a recorder of its
    own, as ``run --snapshots FILE.jsonl --foxglove PORT`` serves it beside a JSON-lines file."""
    recorders: list[SnapshotRecorder] = []

    def plugs(clock: Clock) -> dict[str, Any]:
        recorders.append(SnapshotRecorder(path, clock=clock, live=live))
        if served_by is not None:
            recorders.append(SnapshotRecorder(None, clock=clock, live=served_by))
        return {"plugs": [snapshot_recorder(recorder) for recorder in recorders]}

    mission = line_mission("live")
    with Lockstep(line_mission("live", waypoints=mission.waypoints[:waypoints]), options_for_clock=plugs) as sim:
        status = sim.run_to_end(300.0).status
    for recorder in recorders:
        recorder.close()
    return status


def test_foxglove_s_own_client_reads_the_channels_of_the_file_live(tmp_path: Path) -> None:
    # a backlog that holds the whole lock-step run: the run goes far faster than node reads on a busy machine, and what is
    # checked here is what the client gets, not what the SDK drops for a slow one (the next test is about that)
    live = FoxgloveSink("127.0.0.1", 0, backlog=1_000_000)
    client = NodeClient(live.url)
    try:
        assert run(tmp_path / "run.mcap", live) is MissionStatus.COMPLETED
        lines = client.done()
    finally:
        client.kill()
        live.close()
    (done,) = [line for line in lines if line["event"] == "done"]
    advertised = {topic for line in lines if line["event"] == "subscribed" for topic in line["topics"]}
    with (tmp_path / "run.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert advertised == {c.topic for c in summary.channels.values()}  # the same channels as the file
    received = done["received"]
    assert done["serverName"] == "executive"
    assert received["/vehicle/location"]["schemaName"] == "foxglove.LocationFix" and received["/vehicle/location"]["count"] > 100
    ticks = received["/tree/tick"]
    assert ticks["encoding"] == "json" and ticks["count"] > 300 and ticks["last"]["body"].get("end") is True
    assert ticks["last"]["timestamp"] == round(ticks["last"]["body"]["tick"] * 0.1 * 1e9, -6) or ticks["last"]["timestamp"] > 0
    assert received["/mission/state"]["last"]["body"]["state"] == "COMPLETED"
    assert received["/tree"]["first"]["body"]["nodes"][0]["name"] == "Mission"
    assert received["/mavlink/in/GLOBAL_POSITION_INT"]["count"] > 100


def test_a_client_that_never_reads_changes_no_recording_byte(tmp_path: Path) -> None:
    """The same run recorded alone, then recorded while served (as ``run --snapshots FILE.jsonl --foxglove PORT`` does) to
    Foxglove's client stalled after subscribing to everything: the same bytes."""
    assert run(tmp_path / "alone.jsonl", None) is MissionStatus.COMPLETED
    live = FoxgloveSink("127.0.0.1", 0)
    served: list[str] = []
    put = live.put
    live.put = lambda topic, *rest: (served.append(topic), put(topic, *rest))[1]  # type: ignore[method-assign]
    stalled = NodeClient(live.url, "--stall")
    try:
        assert run(tmp_path / "served.jsonl", None, served_by=live) is MissionStatus.COMPLETED  # recorded and served
        assert stalled.proc.poll() is None  # still connected, never reading
    finally:
        stalled.kill()
        live.close()
    assert served.count("/tree/tick") > 300 and "/mavlink/in/GLOBAL_POSITION_INT" in served  # the whole run was served
    digests = {hashlib.sha256((tmp_path / name).read_bytes()).hexdigest() for name in ("alone.jsonl", "served.jsonl")}
    assert len(digests) == 1


def test_run_foxglove_refuses_a_bad_address(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "missions/rover_square.yaml", "--foxglove", "127.0.0.1:http", "--socket", "none"]) == 2
    assert "--foxglove: '127.0.0.1:http' is not [HOST:]PORT" in capsys.readouterr().err
