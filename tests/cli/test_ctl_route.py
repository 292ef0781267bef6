"""`executive ctl route ...`: the requests it sends, and what the runtime makes of them on the lock-step simulator.

The route is edited (the operator requests ctl sends) while the rover drives its long leg: the reply, the status and the
route on the autopilot (uploaded and read back: ``route show`` compares the mission state's route
with what the read-back found) follow the edit, the rover drives to the edited waypoint (the
journal records where each leg ended) and the mission completes.
"""

from __future__ import annotations

import json
import logging
import sqlite3
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from executive.cli import main
from executive.io.control import ControlServer
from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission_text
from executive.observers.journal import Journal, journal_recorder
from executive.world import geo
from executive.world.clock import Clock

HOME = (-35.363261, 149.165230)
WP1 = geo.destination(*HOME, 0.0, 30.0)
WP2 = geo.destination(*WP1, 90.0, 120.0)  # a long leg: time to edit the route while the rover drives it
MISSION = f"""\
version: 1
name: route-edits
vehicle: rover
auto_arm: true
home: {{lat: {HOME[0]}, lon: {HOME[1]}}}
simulator: {{ekf_ready_after_s: 2}}
limits: {{acceptance_radius_m: 1.5}}
waypoints:
  - {{lat: {WP1[0]:.9f}, lon: {WP1[1]:.9f}}}
  - {{lat: {WP2[0]:.9f}, lon: {WP2[1]:.9f}}}
"""


# -- what ctl sends ------------------------------------------------------------------------------


@contextmanager
def serving(sock: Path, reply: dict[str, Any]) -> Iterator[list[dict[str, Any]]]:
    """A control socket answering ``reply`` to everything; yields the requests it got."""
    seen: list[dict[str, Any]] = []
    control = ControlServer(str(sock), lambda req: seen.append(req) or reply)
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            control.service()
            stop.wait(0.005)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield seen
    finally:
        stop.set()
        thread.join(5)
        control.close()


@pytest.fixture
def server(tmp_path) -> Iterator[tuple[Path, list[dict[str, Any]]]]:
    """A control socket answering ok with a one-waypoint route."""
    route = {"waypoints": [[1.0, 2.0, 0.0]], "current": 1, "home": None, "on_autopilot": False, "upload": None}
    with serving(tmp_path / "ctl.sock", {"ok": True, "reason": "done", "state": "RUNNING", "route": route}) as seen:
        yield tmp_path / "ctl.sock", seen


@pytest.mark.parametrize(
    ("argv", "sent"),
    [
        (["show"], {"operation": "show"}),
        (["add"], {"operation": "add", "after": "end"}),
        (["add", "--after", "current", "--lat", "-35.1", "--lon", "149.2"], {"operation": "add", "after": "current", "lat": -35.1, "lon": 149.2}),
        (["add", "--after", "0", "--alt", "30"], {"operation": "add", "after": 0, "alt_m": 30.0}),
        (["remove", "last"], {"operation": "remove", "waypoint": "last"}),
        (["remove", "3"], {"operation": "remove", "waypoint": 3}),
        (["clear"], {"operation": "clear"}),
        (["backwards"], {"operation": "backwards"}),
        (["offset", "5", "90"], {"operation": "offset", "distance_m": 5.0, "bearing_deg": 90.0}),
        (["offset", "-2.5", "270", "--index", "2"], {"operation": "offset", "distance_m": -2.5, "bearing_deg": 270.0, "waypoint": 2}),
        (["scale-rotate", "1.5", "-30"], {"operation": "scale_rotate", "scale": 1.5, "angle_deg": -30.0}),
        (["mirror", "45", "--centre", "-35.3", "149.1"], {"operation": "mirror", "bearing_deg": 45.0, "centre": [-35.3, 149.1]}),
        (["set-home"], {"operation": "set_home"}),
    ],
)
def test_each_route_command_sends_its_request(server, capsys, argv: list[str], sent: dict[str, Any]) -> None:
    sock, seen = server
    assert main(["ctl", "--socket", str(sock), "route", *argv]) == 0
    assert seen == [{"op": "route", **sent}]
    out = capsys.readouterr().out
    assert out.startswith("RUNNING: done\n1 waypoint; on the autopilot: no\n>   1  1.0000000, 2.0000000")


def test_options_may_follow_the_request(server, capsys) -> None:
    sock, seen = server
    assert main(["ctl", "route", "clear", "--socket", str(sock), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["reason"] == "done"
    assert seen == [{"op": "route", "operation": "clear"}]


@pytest.mark.parametrize(
    ("argv", "error"),
    [
        (["route"], "the following arguments are required: OPERATION"),
        (["route", "warp"], "invalid choice: 'warp'"),
        (["route", "remove", "-1"], "'-1' is not a waypoint number"),
        (["route", "remove", "first"], "'first' is not a waypoint number"),
        (["route", "offset", "5"], "the following arguments are required: BEARING_DEG"),
        (["route", "offset", "five", "90"], "invalid float value: 'five'"),
        (["route", "add", "--lat", "1"], "--lat and --lon go together"),
        (["route", "add", "--after", "last"], "'last' is not a waypoint number"),
        (["status", "now"], "unrecognized arguments: now"),
    ],
)
def test_bad_route_commands_exit_2_without_asking(server, capsys, argv: list[str], error: str) -> None:
    sock, seen = server
    assert main(["ctl", "--socket", str(sock), *argv]) == 2
    assert error in capsys.readouterr().err
    assert seen == []


def test_a_refused_edit_exits_1_with_the_reason(tmp_path, capsys) -> None:
    sock = tmp_path / "ctl.sock"
    with serving(sock, {"ok": False, "reason": "cannot change the route while IDLE", "state": "IDLE"}):
        assert main(["ctl", "--socket", str(sock), "route", "clear"]) == 1
    assert capsys.readouterr().err == "executive: ctl: route clear refused (IDLE): cannot change the route while IDLE\n"


# -- end to end ----------------------------------------------------------------------------------


def test_route_edits_while_driving_reach_the_status_the_autopilot_and_the_vehicle(tmp_path, lockstep, caplog) -> None:
    caplog.set_level(logging.INFO)
    journal = tmp_path / "journal.db"
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(journal, clock))
        return {"plugs": [journal_recorder(journals[0])]}

    sim = lockstep(load_mission_text(MISSION, "route.yaml"), options_for_clock=journal_plug)

    def ctl(op: str, **args: Any) -> dict[str, Any]:
        return sim.runtime.operator.request(op, source="ctl", **args).to_dict()

    def wait_for(op: str, predicate, **args: Any) -> dict[str, Any]:
        """Run the simulation (at most 60 s of vehicle time) until ``predicate(reply)``."""
        replies = [ctl(op, **args)]

        def reached() -> bool:
            replies.append(ctl(op, **args))
            return replies[-1].get("ok") and predicate(replies[-1])

        if not (replies[0].get("ok") and predicate(replies[0])):
            assert sim.run(limit_s=60, until=reached) is None, f"the mission ended first; last reply: {replies[-1]}"
        return replies[-1]

    status = wait_for("status", lambda r: r["status"]["leg"] == 2 and r["status"]["mode"] == "GUIDED")["status"]
    assert geo.distance(status["lat"], status["lon"], *WP2) > 60.0  # far from the end of the leg: time to edit it

    moved = ctl("route", operation="offset", distance_m=5.0, bearing_deg=90.0)
    assert (moved["ok"], moved["state"], moved["reason"]) == (True, "RUNNING", "ctl: 2 waypoints offset 5 m toward 090.0°")
    new_wp1, new_wp2 = (tuple(wp[:2]) for wp in moved["route"]["waypoints"])
    for old, new in ((WP1, new_wp1), (WP2, new_wp2)):
        distance, bearing = geo.distance_bearing(*old, *new)
        assert distance == pytest.approx(5.0, abs=1e-3) and bearing == pytest.approx(90.0, abs=0.01)
    # the status shows the new target: its distance is the vehicle's to the moved waypoint, ~5 m more than to the old one
    status = ctl("status")["status"]
    to_new, to_old = geo.distance(status["lat"], status["lon"], *new_wp2), geo.distance(status["lat"], status["lon"], *WP2)
    assert status["distance_m"] == pytest.approx(to_new, abs=0.05) and to_new - to_old > 4.0
    # on the autopilot: uploaded, read back, and what was read back is the route
    shown = wait_for("route", lambda r: r["route"]["upload"]["state"] == "DONE", operation="show")["route"]
    assert shown["on_autopilot"] is True
    assert (shown["upload"]["edit"], shown["upload"]["detail"]) == ("ctl: 2 waypoints offset 5 m toward 090.0°", "2 waypoints, read back")

    wp3 = geo.destination(*new_wp2, 180.0, 20.0)
    added = ctl("route", operation="add", after="end", lat=round(wp3[0], 9), lon=round(wp3[1], 9))
    assert added["ok"] and added["reason"].startswith("ctl: waypoint 3/3 added at")
    assert ctl("status")["status"]["legs"] == 3
    shown = wait_for("route", lambda r: r["route"]["upload"]["state"] == "DONE", operation="show")["route"]
    assert shown["on_autopilot"] is True and shown["upload"]["detail"] == "3 waypoints, read back"
    assert ctl("route", operation="remove", waypoint=7) == {
        "ok": False,
        "reason": "route remove: no waypoint 7 to remove: the route has 3",
        "state": "RUNNING",
    }
    homed = ctl("route", operation="set_home")
    assert homed["ok"] and homed["reason"].startswith("ctl: home set to") and homed["reason"].endswith("(the vehicle's position)")
    shown = wait_for("route", lambda r: r["route"]["upload"]["state"] != "UPLOADING", operation="show")["route"]
    assert shown["upload"]["detail"] == "3 waypoints, already held; home set"  # DO_SET_HOME accepted; the waypoints did not change
    assert geo.distance(*shown["home"], *HOME) > 10.0

    outcome = sim.run(limit_s=300)
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED
    journals[0].close()
    assert "route on the autopilot: 2 waypoints, read back (ctl: 2 waypoints offset 5 m toward 090.0°)" in caplog.text
    assert "route on the autopilot: 3 waypoints, read back (ctl: waypoint 3/3 added at" in caplog.text
    with sqlite3.connect(journal) as db:
        ended = {leg: (lat, lon) for leg, lat, lon in db.execute("SELECT leg, lat, lon FROM legs")}
    # where legs 2 and 3 ended (the journal notes the position when the next leg starts): at the edited waypoints. Leg 2 is
    # driven through toward waypoint 3 (a 90° turn: left within 2 x 1.5 m / sin 45° = 4.2 m of it, past the old waypoint 5 m
    # before it on the way; heading for the old one it would have ended ~8 m short of the new), the last one ends in a stop
    assert geo.distance(*ended[2], *new_wp2) < 4.3
    assert geo.distance(*ended[3], *wp3) < 2.0


def test_route_show_names_each_waypoint_it_has_a_name_for() -> None:
    """Issue 43: `ctl route show` gave numbers and coordinates only; status and report say `waypoint 7 'far'`."""
    from executive.cli.ctl import route_lines

    route = {"waypoints": [[1.0, 2.0, 0.0], [1.5, 2.0, 0.0]], "names": ["gate", None], "current": 2, "home": None, "on_autopilot": True}
    assert route_lines(route).splitlines() == [
        "2 waypoints; on the autopilot: yes",
        "    1  1.0000000, 2.0000000  'gate'",
        ">   2  1.5000000, 2.0000000",
    ]


def test_tree_watch_ends_on_the_runs_last_tick(tmp_path) -> None:
    """Issue 43: `ctl tree --watch` went on past the end (or ended on a frame of a tick still running): it ends on the last one."""
    import contextlib
    import io

    final = {"ok": True, "state": "COMPLETED", "reason": "every waypoint reached", "tree": {"live": False}, "status": {}}
    out, codes = io.StringIO(), []
    with serving(tmp_path / "ctl.sock", final) as seen, contextlib.redirect_stdout(out):
        watch = threading.Thread(
            target=lambda: codes.append(main(["ctl", "--socket", str(tmp_path / "ctl.sock"), "--json", "tree", "--watch", "--interval", "0.05"]))
        )
        watch.start()
        watch.join(10)  # bounds the old behaviour: it polled until Ctrl-C
        assert not watch.is_alive(), "the watch did not end on the run's last tick"
    assert codes == [0] and len(seen) == 1
    assert json.loads(out.getvalue())["tree"]["live"] is False
