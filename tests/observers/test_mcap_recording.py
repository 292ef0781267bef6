"""`run --snapshots FILE.mcap`: the rover's square driven lock-step, recorded as MCAP, read back with the `mcap` library's reader."""

from __future__ import annotations

import collections
import json
import math
import subprocess
import threading
from pathlib import Path
from typing import Any

import py_trees
import pytest
from mcap.reader import make_reader

from executive.behaviours import LinkAlive
from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.observers.mcap.reading import tick_lines
from executive.observers.snapshots import Recording, SnapshotRecorder, render, replay
from executive.world.frames import global_to_local
from tests_support import Ticks, foxglove_js

MISSIONS = Path(__file__).resolve().parents[2] / "missions"


def messages(path: Path, topic: str, **window: int) -> list[tuple[int, dict[str, Any]]]:
    """(log time in ns, message) of ``topic``, through the file's index (``starting_at``/``ending_before`` seek)."""
    with path.open("rb") as f:
        return [(m.log_time, json.loads(m.data)) for _, _, m in make_reader(f).iter_messages(topics=[topic], **window)]


@pytest.fixture(scope="module")
def square(rover_square_mcap: tuple[Path, Path, Ticks, MissionStatus]) -> tuple[Path, Path, Ticks, MissionStatus]:
    """rover_square to its end, recorded twice from the same ticks: as MCAP and as JSON lines (conftest's, made once a worker)."""
    return rover_square_mcap


@pytest.mark.xdist_group("mcap_square")
def test_the_file_is_chunked_compressed_and_indexed_with_a_schema_per_channel(square) -> None:
    path, _, _, status = square
    assert status is MissionStatus.COMPLETED
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.chunk_indexes and {c.compression for c in summary.chunk_indexes} == {"zstd"}
    schemas = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
    mavlink = {topic: schema.name for topic, schema in schemas.items() if topic.startswith("/mavlink/")}
    assert {"/mavlink/in/HEARTBEAT", "/mavlink/in/GLOBAL_POSITION_INT", "/mavlink/out/HEARTBEAT", "/mavlink/out/COMMAND_LONG"} <= set(mavlink)
    assert all(name == "mavlink." + topic.rsplit("/", 1)[1] for topic, name in mavlink.items())
    assert {topic: schema.name for topic, schema in schemas.items() if topic not in mavlink} == {
        "/tree": "executive.Tree",
        "/tree/tick": "executive.TreeTick",
        "/blackboard": "executive.Blackboard",
        "/mission/run": "executive.Run",
        "/mission/state": "executive.MissionState",
        "/mission/events": "executive.MissionEvent",
        "/mission/route": "foxglove.GeoJSON",
        "/vehicle/location": "foxglove.LocationFix",
        "/vehicle/pose": "foxglove.PoseInFrame",
        "/tf": "foxglove.FrameTransforms",
        "/log": "foxglove.Log",
    }
    assert all(s.encoding == "jsonschema" and json.loads(s.data)["type"] == "object" for s in schemas.values())
    assert all(c.message_encoding == "json" for c in summary.channels.values())


@pytest.mark.xdist_group("mcap_square")
def test_every_tick_is_there_at_its_vehicle_time(square) -> None:
    path, _, ticks, _ = square
    recorded = messages(path, "/tree/tick")
    assert [(m["tick"], t) for t, m in recorded if not m.get("end")] == [(tick, round(round(now, 3) * 1e9)) for tick, now in ticks.times]
    assert recorded[-1][1]["end"] is True


@pytest.mark.xdist_group("mcap_square")
def test_the_mcap_file_holds_what_the_json_lines_file_holds(square) -> None:
    path, jsonl, _, _ = square
    lines = [json.loads(line) for line in jsonl.read_text().splitlines()]
    trees, ticked = [line["tree"] for line in lines if "tree" in line], [line for line in lines if "tree" not in line]
    assert [m["nodes"] for _, m in messages(path, "/tree")] == trees
    boards = {m["tick"] if not m.get("end") else "end": m["bb"] for _, m in messages(path, "/blackboard")}
    for line, (_, tick) in zip(ticked, messages(path, "/tree/tick"), strict=True):
        assert {k: v for k, v in tick.items() if k in "sf"} == {k: {str(i): x for i, x in line[k].items()} for k in "sf" if k in line}
        assert boards.get("end" if line.get("end") else line["tick"]) == line.get("bb")


@pytest.mark.xdist_group("mcap_square")
def test_the_mission_s_transitions_and_state(square) -> None:
    path, _, _, _ = square
    events = [(m["before"], m["after"]) for _, m in messages(path, "/mission/events")]
    assert events == [("IDLE", "READY"), ("READY", "RUNNING"), ("RUNNING", "COMPLETED")]
    states = [(m["state"], m["leg_index"]) for _, m in messages(path, "/mission/state")]
    assert states[0] == ("RUNNING", 0) and states[-1] == ("COMPLETED", 4)  # as each tick found it: READY was before the first
    assert [leg for state, leg in states if state == "RUNNING"] == [0, 1, 2, 3, 4]  # 4: the last waypoint reached, ending


@pytest.mark.xdist_group("mcap_square")
def test_the_track_is_a_location_fix_at_the_time_it_was_received(square) -> None:
    path, _, _, _ = square
    fixes = messages(path, "/vehicle/location")
    assert len(fixes) > 100
    times = [t for t, _ in fixes]
    assert times == sorted(times) and len(set(times)) == len(times)  # each GLOBAL_POSITION_INT once
    for t, fix in fixes:
        assert fix["timestamp"]["sec"] * 10**9 + fix["timestamp"]["nsec"] == t
        assert -35.37 < fix["latitude"] < -35.35 and 149.15 < fix["longitude"] < 149.18 and len(fix["position_covariance"]) == 9


@pytest.mark.xdist_group("mcap_square")
def test_each_mavlink_message_on_its_own_channel_with_its_fields(square) -> None:
    path, _, _, _ = square
    received, fixes = messages(path, "/mavlink/in/GLOBAL_POSITION_INT"), messages(path, "/vehicle/location")
    by_time = dict(received)
    assert len(received) >= len(fixes) and all(by_time[t]["lat"] / 1e7 == pytest.approx(f["latitude"]) for t, f in fixes)  # as received
    sent = [m for _, m in messages(path, "/mavlink/out/COMMAND_LONG")]
    assert any(m["command"] == 400 and m["param1"] == 1 for m in sent)  # MAV_CMD_COMPONENT_ARM_DISARM: the arming we asked
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    schema = next(summary.schemas[c.schema_id] for c in summary.channels.values() if c.topic == "/mavlink/in/GLOBAL_POSITION_INT")
    assert json.loads(schema.data)["properties"]["lat"] == {"type": "integer"} and json.loads(schema.data)["properties"]["hdg"]


@pytest.mark.xdist_group("mcap_square")
def test_the_pose_is_in_the_home_frame_east_north_up(square) -> None:
    path, _, _, _ = square
    poses, transforms = messages(path, "/vehicle/pose"), messages(path, "/tf")
    assert len(poses) > 100 and [t for t, _ in poses] == [t for t, _ in transforms]
    attitude = {round(t, -8): m for t, m in messages(path, "/mavlink/in/ATTITUDE")}
    fixes = {round(t, -8): m for t, m in messages(path, "/vehicle/location")}
    home = load_mission(MISSIONS / "rover_square.yaml").home
    for t, message in poses[::50]:
        (tf,) = dict(transforms)[t]["transforms"]
        assert message["frame_id"] == tf["parent_frame_id"] == "home" and tf["child_frame_id"] == "vehicle"
        assert message["pose"]["position"] == tf["translation"] and message["pose"]["orientation"] == tf["rotation"]
        q = message["pose"]["orientation"]
        yaw_enu = math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))
        heading = attitude[max(k for k in attitude if k <= t)]["yaw"]  # ATTITUDE's yaw: from north, clockwise
        assert math.cos(yaw_enu - (math.pi / 2 - heading)) == pytest.approx(1.0)
        fix = fixes[max(k for k in fixes if k <= t)]
        north, east = global_to_local(home.lat, home.lon, fix["latitude"], fix["longitude"])
        assert (message["pose"]["position"]["x"], message["pose"]["position"]["y"]) == (pytest.approx(east, abs=0.05), pytest.approx(north, abs=0.05))


@pytest.mark.xdist_group("mcap_square")
def test_the_route_is_geojson_for_the_map(square) -> None:
    path, _, _, _ = square
    ((_, message),) = messages(path, "/mission/route")
    route, *points = json.loads(message["geojson"])["features"]
    waypoints = load_mission(MISSIONS / "rover_square.yaml").waypoints
    assert route["geometry"] == {"type": "LineString", "coordinates": [[w.lon, w.lat] for w in waypoints]}
    assert [p["geometry"]["coordinates"] for p in points] == [[w.lon, w.lat] for w in waypoints]


@pytest.mark.xdist_group("mcap_square")
def test_log_lines_are_foxglove_logs(square) -> None:
    path, _, _, _ = square
    logs = {m["message"]: m for _, m in messages(path, "/log")}
    done = logs["mission RUNNING -> COMPLETED: every waypoint reached"]
    assert (done["level"], done["name"]) == (2, "executive.mission.lifecycle")  # foxglove.Log: INFO is 2


@pytest.mark.xdist_group("mcap_square")
def test_a_time_window_is_read_through_the_index(square) -> None:
    path, _, ticks, _ = square
    middle = round(ticks.times[len(ticks.times) // 2][1], 3)
    window = messages(path, "/tree/tick", starting_at=round(middle * 1e9), ending_before=round((middle + 1) * 1e9))
    assert [round(t / 1e9, 3) for t, _ in window] == [round(now, 3) for _, now in ticks.times if middle <= round(now, 3) < middle + 1]


def test_a_long_run_is_rotated_and_each_file_stands_alone(tmp_path: Path, vehicle) -> None:
    root = py_trees.composites.Sequence("Mission", memory=False, children=[LinkAlive()])
    tree = py_trees.trees.BehaviourTree(root)
    path = tmp_path / "run.mcap"
    recorder = SnapshotRecorder(path, max_bytes=300_000, keyframe_every=10)
    recorder.attach(root)
    for tick in range(6000):
        vehicle.set(link__up=tick % 3 != 0, link__messages=tick)
        tree.tick()
        recorder.record(tick, tick * 0.1)
    recorder.close()
    for part in (tmp_path / "run.mcap.1", path):
        assert part.stat().st_size < 300_000 + 300_000  # at most a chunk past the limit
        trees, ticked = messages(part, "/tree"), messages(part, "/tree/tick")
        assert len(trees) == 1 and trees[0][0] <= ticked[0][0]  # the tree first, then ticks
        assert ticked[0][1].get("key") is True  # a file starts with a keyframe: readable alone
    assert messages(path, "/tree/tick")[-1][1]["tick"] == 5999


def test_a_rotated_file_starts_with_the_state_so_far_whatever_the_recorder_s_keyframes(tmp_path: Path, vehicle) -> None:
    root = py_trees.composites.Sequence("Mission", memory=False, children=[LinkAlive()])
    tree = py_trees.trees.BehaviourTree(root)
    mcap, jsonl = tmp_path / "run.mcap", tmp_path / "run.jsonl"
    recorders = [SnapshotRecorder(mcap, max_bytes=4096, keyframe_every=10_000), SnapshotRecorder(jsonl, keyframe_every=10_000)]
    for recorder in recorders:
        recorder.attach(root)
    for tick in range(400):
        vehicle.set(link__up=tick % 3 != 0, link__messages=tick)
        tree.tick()
        for recorder in recorders:
            recorder.record(tick, tick * 0.1)
    for recorder in recorders:
        recorder.close()
    (_, first), (_, board) = messages(mcap, "/tree/tick")[0], messages(mcap, "/blackboard")[0]
    assert first["tick"] > 0 and first.get("key") is True  # made by the encoder thread: the recorder's next is tick 10000
    whole = replay(jsonl, first["tick"])
    assert {int(i): s for i, s in first["s"].items()} == whole.status and board["bb"] == whole.blackboard


@pytest.mark.xdist_group("mcap_square")
@pytest.mark.parametrize("tick", [0, 1, 99, 100, 101, 102, 500, 987, None])
def test_replay_shows_the_same_tick_from_either_file(square, tick: int | None) -> None:
    path, jsonl, _, _ = square
    assert list(render(replay(path, tick))) == list(render(replay(jsonl, tick)))  # None: the last tick, as the run's end left it


@pytest.mark.xdist_group("mcap_square")
def test_cli_replay_of_an_mcap_file(square, capsys: pytest.CaptureFixture[str]) -> None:
    path, _, _, _ = square
    assert main(["replay", str(path)]) == 0
    last = capsys.readouterr().out.splitlines()
    assert last[1] == "✓ Mission" and "  /mission/state: 'COMPLETED'" in last and "  /mission/reason: 'every waypoint reached'" in last


@pytest.mark.xdist_group("mcap_square")
def test_a_replay_of_a_tick_seeks_to_the_keyframe_before_it(square) -> None:
    path, _, _, _ = square
    tree, first, *_ = tick_lines(path, near=500)
    assert "tree" in tree and first.get("key") is True and 400 <= first["tick"] < 500  # keyframes every 100 ticks


@pytest.mark.xdist_group("mcap_square")
def test_the_slider_s_index_of_an_mcap_file_is_the_json_lines_file_s(square) -> None:
    path, jsonl, _, _ = square
    mcap, lines = Recording(path), Recording(jsonl)
    assert (mcap.trees, mcap.ticks) == (lines.trees, lines.ticks)
    for tick in (mcap.first, 99, 100, 101, 555, mcap.last):
        a, b = mcap.state_at(tick), lines.state_at(tick)
        assert (a.tick, a.status, a.feedback, a.blackboard, a.changed) == (b.tick, b.status, b.feedback, b.blackboard, b.changed)
        assert a.t == round(b.t, 3)  # the JSON-lines end line keeps the clock's unrounded time


@pytest.mark.xdist_group("mcap_square")
def test_replay_web_shows_an_mcap_file_as_the_json_lines_file(square) -> None:
    from executive.observers.web.feed import Seen
    from executive.observers.web.replay import ReplaySource

    path, jsonl, _, _ = square
    mcap, lines = ReplaySource(str(path)), ReplaySource(str(jsonl))
    assert mcap.hello() == lines.hello()
    for tick in (300, None):
        shown, expected = mcap.frame(tick).message(Seen()), lines.frame(tick).message(Seen())
        assert shown["tree"]["nodes"] == expected["tree"]["nodes"]  # its id is the page's, new for each source
        assert {k: v for k, v in shown.items() if k not in ("tree", "t")} == {k: v for k, v in expected.items() if k not in ("tree", "t")}


@pytest.mark.xdist_group("mcap_square")
def test_replay_groot2_plays_an_mcap_file(square) -> None:
    from executive.observers.groot2.replay import ReplayFeed
    from executive.observers.groot2.view import MonitorView

    path, _, _, _ = square
    view = MonitorView()
    feed = ReplayFeed(Recording(path), view, start=500)
    waits: list[float] = []
    feed._play(lambda seconds: waits.append(seconds) or len(waits) >= 3)  # three ticks played, no wall clock
    assert feed.position == 502 and waits[:2] == [pytest.approx(0.1, abs=0.002)] * 2


@pytest.mark.xdist_group("mcap_square")
def test_convert_writes_an_old_snapshot_file_as_mcap(square, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, jsonl, _, _ = square
    new = tmp_path / "old.mcap"
    assert main(["convert", str(jsonl), str(new)]) == 0
    assert "tick lines written" in capsys.readouterr().err
    for tick in (0, 101, 555, None):
        assert list(render(replay(new, tick))) == list(render(replay(jsonl, tick)))
    assert [m["nodes"] for _, m in messages(new, "/tree")] == [m["nodes"] for _, m in messages(path, "/tree")]
    events = [(m["before"], m["after"], m["reason"]) for _, m in messages(new, "/mission/events")]
    assert events == [("RUNNING", "COMPLETED", "every waypoint reached")]  # the recorded blackboard's: READY was before the first tick
    assert [m["state"] for _, m in messages(new, "/mission/state")] == [m["state"] for _, m in messages(path, "/mission/state")]
    fixes, recorded = messages(new, "/vehicle/location"), messages(path, "/vehicle/location")
    assert len(fixes) > 100 and all(-35.37 < m["latitude"] < -35.35 for _, m in fixes)
    assert fixes[-1][1]["latitude"] == pytest.approx(recorded[-1][1]["latitude"], abs=1e-7)


@pytest.mark.xdist_group("mcap_square")
def test_convert_refuses_what_it_cannot_convert(square, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, jsonl, _, _ = square
    assert main(["convert", str(path), str(tmp_path / "again.mcap")]) == 2
    assert "already an MCAP recording" in capsys.readouterr().err
    assert main(["convert", str(jsonl), str(tmp_path / "new.jsonl")]) == 2
    assert main(["convert", str(tmp_path / "none"), str(tmp_path / "new.mcap")]) == 2
    assert "no such snapshot file" in capsys.readouterr().err


@pytest.mark.xdist_group("mcap_square")
def test_report_from_the_mcap_file_tells_what_the_journal_tells(square, capsys: pytest.CaptureFixture[str]) -> None:
    path, _, _, _ = square
    journal = path.with_name("journal.db")
    assert main(["report", str(journal), "--json"]) == 0
    expected = json.loads(capsys.readouterr().out)
    assert main(["report", str(path), "--json"]) == 0
    told = json.loads(capsys.readouterr().out)
    for row in (*expected["transitions"], *expected["legs"], *expected["events"]):
        row["t"] = round(row["t"], 3)  # vehicle time, as MCAP keeps it (ns)
    same = ("mission", "vehicle", "outcome", "reason", "resumed_from", "transitions")
    assert {k: told[k] for k in same} == {k: expected[k] for k in same}
    assert told["started"] == pytest.approx(expected["started"], abs=5.0) and told["ended"] is None  # wall clock: the journal's alone
    strip = ("lat", "lon")
    assert [{k: v for k, v in leg.items() if k not in strip} for leg in told["legs"]] == [
        {k: v for k, v in leg.items() if k not in strip} for leg in expected["legs"]
    ]
    assert all(a["lat"] == pytest.approx(b["lat"], abs=1e-5) for a, b in zip(told["legs"], expected["legs"], strict=True))
    assert told["events"] == expected["events"]
    assert main(["report", str(path)]) == 0
    text = capsys.readouterr().out
    assert text.startswith("run 1: mission 'rover-square' (rover)") and "RUNNING -> COMPLETED: every waypoint reached" in text
    assert main(["report", str(path), "--run", "2"]) == 2
    assert "no run 2 (runs 1 to 1)" in capsys.readouterr().err


@pytest.mark.xdist_group("mcap_square")
def test_every_message_is_strict_json_of_the_type_its_schema_says(square) -> None:
    path, _, _, _ = square
    kinds = {"integer": int, "number": (int, float), "string": str, "array": list, "object": dict, "boolean": bool}

    def no_constant(name: str) -> None:
        raise AssertionError(f"{name} is not JSON")

    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            body = json.loads(message.data, parse_constant=no_constant)
            for field, spec in json.loads(schema.data)["properties"].items():
                allowed = spec["type"] if isinstance(spec["type"], list) else [spec["type"]]
                value = body.get(field)
                assert value is None or any(isinstance(value, kinds[k]) for k in allowed if k != "null"), (channel.topic, field, value)


@pytest.mark.xdist_group("mcap_square")
def test_foxglove_s_own_mcap_reader_reads_the_file(square) -> None:
    """@mcap/core (TypeScript, another implementation than the `mcap` library's) reads every message, CRCs checked, and seeks."""
    path, _, ticks, _ = square
    middle = round(ticks.times[len(ticks.times) // 2][1], 3)
    told = json.loads(subprocess.run(foxglove_js("read_mcap.js", str(path), str(round(middle * 1e9))), capture_output=True, text=True,
                                     check=True, timeout=120).stdout)  # fmt: skip
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    counts = summary.statistics.channel_message_counts
    assert {topic: c["count"] for topic, c in told["channels"].items()} == {c.topic: counts[i] for i, c in summary.channels.items()}
    assert told["messageCount"] == summary.statistics.message_count and told["compression"] == ["zstd"]
    assert told["library"] == "executive" and told["metadata"] == ["executive.keyframes"]
    assert told["channels"]["/vehicle/location"]["schema"] == "foxglove.LocationFix"
    assert told["channels"]["/tree"]["first"]["nodes"][0]["name"] == "Mission"
    assert told["seek"] == [tick for tick, now in ticks.times if middle <= round(now, 3) < middle + 1]


@pytest.mark.xdist_group("mcap_square")
def test_the_shipped_foxglove_layout_reads_only_what_the_recording_holds(square, tmp_path: Path) -> None:
    from executive.observers.foxglove.layout import paths

    path, _, _, _ = square
    assert main(["foxglove-layout", "-o", str(tmp_path / "layout.json")]) == 0
    layout = json.loads((tmp_path / "layout.json").read_text())
    assert {"map!route", "RosOut!log", "RawMessages!tree"} <= set(layout["configById"])
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    schemas = {c.topic: json.loads(summary.schemas[c.schema_id].data) for c in summary.channels.values()}
    for wanted in paths(layout):
        topic, _, field = wanted.partition(".")
        if topic == "vehicle":  # the 3D panel's frame, not a topic
            continue
        assert topic in schemas, wanted
        name = field.split("[", 1)[0]
        assert not name or name in schemas[topic]["properties"], wanted


class ThreadedSink:
    """A sink noting which thread put each message, and telling when a topic has come."""

    def __init__(self) -> None:
        self.put_by: list[tuple[str, str, bytes]] = []
        self.came: dict[str, threading.Event] = collections.defaultdict(threading.Event)

    def put(self, topic: str, schema: tuple[str, bytes], log_ns: int, data: bytes) -> None:
        self.put_by.append((topic, threading.current_thread().name, data))
        self.came[topic].set()

    def keyframe(self, tick: int, log_ns: int) -> None:
        pass

    def ticked(self) -> bool:
        return True

    def close(self) -> None:
        pass


def test_the_tick_leaves_its_line_and_the_mavlink_messages_to_the_encoder_thread_with_their_source_as_heard() -> None:
    from executive.observers.mcap.recording import ENCODE_EVERY, ChannelFeed
    from executive.world.dialect import mavlink

    sink = ThreadedSink()
    feed = ChannelFeed([sink], None, values=lambda key: None)
    sent = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3)
    feed.mavlink("out", sent)  # heard before the link packed it: no source yet
    sent.get_header().srcSystem, sent.get_header().srcComponent = 1, 191  # packed afterwards, before the encoder ran
    feed.write_tick({"tick": ENCODE_EVERY, "t": 1.0})
    assert sink.came["/mavlink/out/HEARTBEAT"].wait(30)  # a deadline for a thread to run, not a timing assumption
    feed.mavlink("in", mavlink.MAVLink_heartbeat_message(10, 3, 0, 0, 4, 3))
    feed.close()  # what the thread had not taken yet: written at close
    by = {topic: thread for topic, thread, _ in sink.put_by}
    assert by["/tree/tick"] == "mcap-encoder"  # the tick line too: the tick only queues it
    assert by["/mavlink/out/HEARTBEAT"] == "mcap-encoder"
    assert "/mavlink/in/HEARTBEAT" in by
    data = next(d for topic, _, d in sink.put_by if topic == "/mavlink/out/HEARTBEAT")
    assert json.loads(data)["sysid"] == 0 and json.loads(data)["compid"] == 0  # as heard, whatever happened to it later


def test_the_same_lock_step_run_makes_the_same_file_byte_for_byte_however_late_the_encoder_thread_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Twice the first 20 s of a run, rotated on the way: once as the encoder thread runs when woken, once with it held off to
    the end (every round written at close). The rounds are cut at ticks, not when the thread runs: the same bytes."""
    from executive.observers.mcap.recording import ChannelFeed
    from executive.observers.snapshots import snapshot_recorder
    from executive.testing import Lockstep

    def record(name: str) -> list[bytes]:
        recorders: list[SnapshotRecorder] = []

        def plugs(clock: Any) -> dict[str, Any]:
            recorders.append(SnapshotRecorder(tmp_path / name / "run.mcap", clock=clock, max_bytes=25_000, wall=lambda: 1_796_000_000.5))
            return {"plugs": [snapshot_recorder(recorders[0])]}

        (tmp_path / name).mkdir()
        mission = load_mission(Path(__file__).resolve().parents[1] / "data" / "minimal_mission.yaml")
        with Lockstep(mission, options_for_clock=plugs) as sim:
            assert sim.run(limit_s=60, until=lambda: sim.clock.now() >= 20.0) is None
        recorders[0].close()
        return [(tmp_path / name / f).read_bytes() for f in ("run.mcap.1", "run.mcap")]

    when_woken = record("when woken")

    def held_off(feed: ChannelFeed) -> None:
        while not feed._closing:
            feed._work.wait()
            feed._work.clear()

    monkeypatch.setattr(ChannelFeed, "_encode_forever", held_off)
    at_the_end = record("at the end")
    assert when_woken == at_the_end
    with (tmp_path / "at the end" / "run.mcap").open("rb") as f:
        run = [json.loads(m.data) for _, _, m in make_reader(f).iter_messages(topics=["/mission/run"])]
    assert [r["started"] for r in run] == [1_796_000_000.5]  # the latched run, in the second file too: the wall time given
