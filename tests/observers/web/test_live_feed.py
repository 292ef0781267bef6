"""The live view's tick side: frames as the page shows them, made only when asked, and a browser that stops reading costs the loop nothing."""

from __future__ import annotations

import itertools
import math
import socket
import time

from executive.mission.lifecycle import MissionStatus
from executive.observers.web.feed import TRACK_SPACING_M, Frame, Seen
from executive.observers.web.plug import live_view
from executive.observers.web.server import LiveSource, WebAddress, WebServer
from executive.world import frames
from tests_support import LINE_HOME, line_mission


def stalled_client(port: int) -> socket.socket:
    """A WebSocket client with a tiny receive buffer that never reads what it is sent."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 2048)
    sock.connect(("127.0.0.1", port))
    sock.sendall(
        b"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    return sock


class Frames:
    """A live view's feed in a lockstep run, asked for a frame after every step of the world (as a browser would, at the web side's pace)."""

    def __init__(self, sim, source: LiveSource) -> None:
        self.source = source
        self.seen = Seen()
        self.messages: list[dict] = []
        sim.observers.append(self.ask)

    def ask(self, _sim) -> None:
        frame = self.source.frame(None)
        if frame is not None and (not self.messages or frame.tick != self.messages[-1]["tick"]):
            self.messages.append(frame.message(self.seen))


def test_frames_show_the_tree_the_status_and_the_plan_in_local_metres(lockstep):
    server = WebServer(WebAddress("127.0.0.1", 0))
    sim = lockstep(line_mission("web"), plugs=[live_view(server)])
    try:
        watch = Frames(sim, server.source)
        assert sim.run(300.0, until=lambda: sim.runtime.mission_state.legs.leg_index == 2) is None
        leg_started = sim.runtime.ticks
        assert sim.run(60.0, until=lambda: sim.runtime.ticks >= leg_started + 5) is None
        first_with_tree = next(m for m in watch.messages if m.get("tree"))
        last = watch.messages[-1]
    finally:
        server.close()
    names = [node["name"] for node in first_with_tree["tree"]["nodes"]]
    assert names[0] == "Mission" and "Go to waypoint" in names and "EKF ok?" in names
    assert sum("tree" in m for m in watch.messages) == 1  # the shape once; then statuses only
    go = names.index("Go to waypoint")
    assert last["s"][go] == "R" and "leg 3/4" in last["f"][go]
    assert (last["status"]["state"], last["status"]["leg"], last["status"]["mode"]) == ("RUNNING", 3, "GUIDED")
    # the route 25 m apart due north of home (the origin), the vehicle between waypoints 2 and 3
    route = last["plan"]["route"]
    assert [round(n) for _, n in route] == [25, 50, 75, 100] and all(abs(e) < 0.01 for e, _ in route)
    assert last["plan"]["current"] == 2 and last["plan"]["home"] == (0.0, 0.0)
    east, north = last["here"]
    assert 40 < north < 76 and abs(east) < 2.0  # a waypoint straight on is driven through early (no corner to cut)
    points = [p for m in watch.messages for p in m.get("track", {}).get("points", [])]
    assert len(points) == len(set(points))  # each point sent once
    assert math.dist(points[-1], last["here"]) < TRACK_SPACING_M
    assert all(TRACK_SPACING_M <= math.dist(p, q) < 5.0 for p, q in itertools.pairwise(points))
    lat, lon = frames.local_to_global(*LINE_HOME, north, east)
    position = sim.runtime.status.snapshot()
    assert abs(lat - position["lat"]) < 1e-6 and abs(lon - position["lon"]) < 1e-6
    assert "/vehicle/mode" in first_with_tree["bb"] and all(len(m.get("bb", {})) < len(first_with_tree["bb"]) for m in watch.messages[1:])


def test_no_frame_is_made_unless_the_web_side_asks(lockstep):
    server = WebServer(WebAddress("127.0.0.1", 0))
    sim = lockstep(line_mission("web"), plugs=[live_view(server)])
    try:
        feed = server.source.feed
        sim.run(60.0, until=lambda: sim.runtime.ticks >= 50)
        assert (feed.frames, feed.latest) == (0, None)
        feed.wanted = True
        sim.run(60.0, until=lambda: sim.runtime.ticks >= 52)
        assert feed.frames == 1 and isinstance(feed.latest, Frame) and not feed.wanted
    finally:
        server.close()


def test_a_browser_that_never_reads_costs_the_loop_nothing(lockstep):
    """Ticks and vehicle time of a whole mission are the same with a stalled client as with none, and frames were dropped for it meanwhile."""
    two_legs = line_mission("web").waypoints[:2]  # the first two of the line: a whole mission, half the vehicle time
    quiet = lockstep(line_mission("web", waypoints=two_legs))
    baseline = quiet.run_to_end(300.0)
    server = WebServer(WebAddress("127.0.0.1", 0), frames_per_s=500.0, send_buffer_bytes=4096)
    server.bind()
    sim = lockstep(line_mission("web", waypoints=two_legs), plugs=[live_view(server)])
    stalled = stalled_client(server.port)

    def between_ticks(_sim) -> None:  # the server's thread runs between steps, as it would between real ticks, until it has stalled
        if server.superseded < 3:
            time.sleep(0.003)

    sim.observers.append(between_ticks)
    try:
        assert sim.run(300.0, until=lambda: server.superseded >= 3) is None  # the server could not send: it dropped frames for the latest
        outcome = sim.run_to_end(300.0)
        stalled_end = sim.clock.now()
    finally:
        stalled.close()
        server.close()
    assert outcome.status is MissionStatus.COMPLETED
    assert (outcome.status, outcome.reason, outcome.ticks) == (baseline.status, baseline.reason, baseline.ticks)
    assert stalled_end == quiet.clock.now()
    assert server.source.feed.frames > 3


def test_the_buttons_go_through_the_operator_on_the_tick_thread(lockstep):
    server = WebServer(WebAddress("127.0.0.1", 0))
    sim = lockstep(line_mission("web"), plugs=[live_view(server)])
    replies: list[dict] = []
    try:
        feed = server.source.feed
        sim.run(300.0, until=lambda: sim.runtime.mission_state.legs.leg_index == 1)
        feed.ask("pause", replies.append)
        feed.ask("delete", replies.append)  # not a button: stays with `executive ctl`
        assert replies == [] and sim.status is MissionStatus.RUNNING  # nothing happens off the tick thread
        ticks = sim.runtime.ticks
        sim.run(60.0, until=lambda: sim.runtime.ticks > ticks)
        assert replies[0] == {"ok": True, "reason": "web: pause", "state": "PAUSED"}
        assert replies[1]["ok"] is False and "only pause, resume, abort" in replies[1]["reason"]
        sim.run(10.0, until=lambda: sim.runtime.status.snapshot()["mode"] == "HOLD")
        feed.ask("resume", replies.append)
        sim.run(60.0, until=lambda: sim.runtime.status.snapshot()["mode"] == "GUIDED")
        assert replies[2]["state"] == "RUNNING" and sim.runtime.mission_state.legs.leg_index == 1
    finally:
        server.close()
