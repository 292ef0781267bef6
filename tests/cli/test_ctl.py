"""Operator control of a running executive, end to end: `executive run` in one process, `ctl` and a ground station in others."""

from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from executive.cli import main
from executive.io.control import request
from executive.operator.status import status_line
from executive.world import geo
from executive.world.dialect import mavlink, mavutil
from tests_support import executive_process, mission_text

MISSION = mission_text(
    "two-legs",
    "{lat: -35.3629906, lon: 149.1652300}",
    "{lat: -35.3629906, lon: 149.1665504}  # 120 m east: time for an operator to act on this leg",
)


@pytest.fixture
def mission(tmp_path) -> Path:
    path = tmp_path / "two_legs.yaml"
    path.write_text(MISSION)
    return path


def run_executive(mission: Path, sock: Path, *extra: str, speedup: float = 10.0) -> subprocess.Popen:
    return executive_process("run", str(mission), "--speedup", str(speedup), "--socket", str(sock), "-v", *extra)


def ctl(capsys, sock: Path, *args: str) -> dict:
    """``executive ctl --json`` in this process (an interpreter's start per command would load a busy machine; `ctl` as a process of
    its own: the upload of a replaced mission below), its reply."""
    main(["ctl", "--socket", str(sock), "--json", *args])
    return json.loads(capsys.readouterr().out)


def wait_status(sock: Path, predicate, timeout_s: float = 300.0) -> dict:
    """The first status (asked over the control socket in this process: a `ctl` process per poll would load the machine) meeting ``predicate``.

    ``timeout_s`` of wall time only bounds a hung run; what the test waits for is judged on the status, in vehicle time (``t``).
    """
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            reply = request(str(sock), "status")
        except OSError:  # not listening yet
            reply = {}
        if reply.get("ok") and predicate(reply["status"]):
            return reply["status"]
        time.sleep(0.02)
    pytest.fail("the executive never reached the expected status")


def after(sock: Path, status: dict, seconds: float) -> dict:
    """The status ``seconds`` of vehicle time after ``status``."""
    return wait_status(sock, lambda s: s["t"] >= status["t"] + seconds)


def test_pause_holds_resume_keeps_the_leg_a_ground_stations_pause_is_obeyed_and_acked_abort_makes_safe(mission, tmp_path, capsys):
    """One run: paused and resumed with `ctl`, paused again by a ground station in another process, aborted with `ctl`."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    sock = tmp_path / "ctl.sock"
    run = run_executive(mission, sock, "--gcs", f"udpin:127.0.0.1:{port}", speedup=20)  # as the replaced mission below
    gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255, source_component=190, dialect="ardupilotmega")
    try:
        wait_status(sock, lambda s: s["state"] == "RUNNING" and s["leg"] == 2 and s["mode"] == "GUIDED")
        paused = ctl(capsys, sock, "pause")
        assert (paused["ok"], paused["state"]) == (True, "PAUSED")
        held = after(sock, wait_status(sock, lambda s: s["mode"] == "HOLD"), 3.0)  # the rover has braked to a stop
        later = after(sock, held, 3.0)  # and a held rover does not move
        assert (later["lat"], later["lon"], later["leg"]) == (held["lat"], held["lon"], 2)
        refused = ctl(capsys, sock, "pause")
        assert refused["ok"] is False and "cannot pause while PAUSED" in refused["reason"]
        assert ctl(capsys, sock, "resume")["state"] == "RUNNING"
        resumed = wait_status(sock, lambda s: s["mode"] == "GUIDED")
        assert resumed["leg"] == 2

        # a ground station's pause, from another process over MAVLink
        gcs.mav.command_long_send(1, 191, mavlink.MAV_CMD_DO_PAUSE_CONTINUE, 0, 0, 0, 0, 0, 0, 0, 0)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=10)
        assert ack is not None and (ack.command, ack.result) == (mavlink.MAV_CMD_DO_PAUSE_CONTINUE, mavlink.MAV_RESULT_ACCEPTED)
        assert wait_status(sock, lambda s: s["mode"] == "HOLD")["state"] == "PAUSED"
        report = gcs.recv_match(type="NAMED_VALUE_FLOAT", condition="NAMED_VALUE_FLOAT.name=='MSN_STATE'", blocking=True, timeout=10)
        assert report is not None and report.value == 3.0  # PAUSED
        # the executive is seen as a component of the vehicle: its own HEARTBEAT at 1 Hz, an onboard controller
        beat = gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=5)
        assert beat is not None and (beat.get_srcSystem(), beat.get_srcComponent()) == (1, 191)
        assert (beat.type, beat.autopilot) == (mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_AUTOPILOT_INVALID)

        assert ctl(capsys, sock, "abort")["state"] == "ABORTED"
        _, err = run.communicate(timeout=30)
        assert run.returncode == 1
        assert "executive: the vehicle made safe: HOLD (already in it)" in err and "ABORTED: ctl: abort" in err  # the pause held it
    finally:
        gcs.close()
        run.kill()
        run.communicate()


def ctl_text(capsys, sock: Path, *args: str) -> tuple[int, str, str]:
    """``executive ctl`` in this process (no interpreter to start on a busy machine): its exit code, stdout and stderr."""
    code = main(["ctl", "--socket", str(sock), *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_an_operators_arm_mode_and_disarm_are_obeyed_and_reported(tmp_path, capsys):
    mission = tmp_path / "operator_arms.yaml"
    # the mission waits for a person to arm; its second leg 600 m long: it is still running whatever the machine's load
    mission.write_text(MISSION.replace("auto_arm: true", "auto_arm: false").replace("149.1665504", "149.1718300"))
    sock = tmp_path / "ctl.sock"
    run = run_executive(mission, sock)
    try:
        # the tree waits for a person to arm once the EKF is usable: before that the autopilot refuses arming (PreArm: AHRS)
        wait_status(sock, lambda s: not s["armed"] and "Wait for the operator to arm" in ((s["waiting"] or {}).get("path") or ""))
        code, out, err = ctl_text(capsys, sock, "arm")
        assert code == 0, err
        assert out.splitlines() == ["RUNNING: ctl: arm, sent to the autopilot", "arm: ACCEPTED by the autopilot"]
        wait_status(sock, lambda s: s["armed"] and s["mode"] == "GUIDED")
        code, out, err = ctl_text(capsys, sock, "mode", "FOLLOW")  # no target to follow: refused, and nothing changes
        assert code == 1 and "executive: ctl: mode FOLLOW: refused by the autopilot (FAILED); nothing changed (the mission RUNNING)" in err
        status = request(str(sock), "status")["status"]
        assert (status["state"], status["mode"]) == ("RUNNING", "GUIDED")
        assert "ctl: mode FOLLOW refused by the autopilot (FAILED)" in status_line(status)
        code, out, err = ctl_text(capsys, sock, "mode", "HOLD")
        assert code == 0, err
        assert out.splitlines()[-1] == "mode HOLD: ACCEPTED by the autopilot"
        # the mode is read off the heartbeat before the tick that judges it: a status between the two shows HOLD still RUNNING
        status = wait_status(sock, lambda s: s["mode"] == "HOLD" and s["state"] != "RUNNING")
        assert (status["state"], status["reason"]) == ("PAUSED", "HOLD set by a person (ctl: mode HOLD)")
        disarmed = ctl(capsys, sock, "disarm")  # mid-mission: allowed
        assert (disarmed["ok"], disarmed["state"], disarmed["command"]["state"]) == (True, "PAUSED", "ACCEPTED")
        status = after(sock, wait_status(sock, lambda s: not s["armed"]), 5.0)  # nothing arms it again or takes it out of HOLD
        assert (status["state"], status["mode"], status["armed"]) == ("PAUSED", "HOLD", False)
        code, _, err = ctl_text(capsys, sock, "mode", "WARP")
        assert code == 1 and "mode WARP: not a mode of this vehicle's autopilot" in err
        assert ctl(capsys, sock, "abort")["state"] == "ABORTED"
        _, err = run.communicate(timeout=30)
        assert re.search(r"WARNING operator: HOLD set by a person \(ctl: mode HOLD\) -> mission paused at leg [12], hands off until resumed", err)
        assert "WARNING operator: ctl: disarm, sent to the autopilot" in err
    finally:
        run.kill()
        run.communicate()


def test_wait_mode_serves_mission_after_mission(tmp_path, capsys):
    mission = tmp_path / "short.yaml"
    mission.write_text(MISSION.split("  - {lat: -35.3629906, lon: 149.1665504}")[0])  # the first leg only
    sock = tmp_path / "ctl.sock"
    run = run_executive(mission, sock, "--wait", speedup=25)
    try:
        assert wait_status(sock, lambda s: True)["state"] == "READY"
        assert ctl(capsys, sock, "start")["state"] == "RUNNING"
        wait_status(sock, lambda s: s["state"] == "COMPLETED")
        uploaded = ctl(capsys, sock, "upload", str(mission))
        assert (uploaded["ok"], uploaded["state"]) == (True, "READY")
        bad = tmp_path / "bad.yaml"
        bad.write_text(MISSION.replace("lat: -35.3629906", "lat: -95.0", 1))
        refused = ctl(capsys, sock, "upload", str(bad))
        assert refused["ok"] is False and f"{bad}:8:" in refused["reason"]
        assert ctl(capsys, sock, "start")["state"] == "RUNNING"
        wait_status(sock, lambda s: s["state"] == "COMPLETED")
        yard = tmp_path / "yard.yaml"  # loaded, never started: the last line is the mission that ran (issue 28)
        yard.write_text(mission.read_text().replace("name: two-legs", "name: yard-loop"))
        assert ctl(capsys, sock, "upload", str(yard))["state"] == "READY"
        run.send_signal(signal.SIGTERM)
        _, err = run.communicate(timeout=30)
        assert run.returncode == 0, err
        *_, loaded, safe, last = err.splitlines()
        assert loaded == "executive: mission 'yard-loop' READY: loaded, never started", err
        assert re.fullmatch(r"executive: the vehicle made safe: HOLD \((already in it|confirmed)\)", safe), err  # SIGTERM makes sure
        assert re.fullmatch(r"executive: mission 'two-legs' COMPLETED: every waypoint reached \(\d+ ticks\)", last), err
    finally:
        run.kill()


def test_ctl_without_an_executive_exits_3(tmp_path, capsys):
    assert main(["ctl", "--socket", str(tmp_path / "none.sock"), "status"]) == 3
    assert "no executive answers" in capsys.readouterr().err


def test_ctl_upload_needs_a_readable_file(tmp_path, capsys):
    assert main(["ctl", "--socket", str(tmp_path / "none.sock"), "upload"]) == 2
    assert main(["ctl", "--socket", str(tmp_path / "none.sock"), "upload", str(tmp_path / "missing.yaml")]) == 2
    assert main(["ctl", "--socket", str(tmp_path / "none.sock"), "upload", str(tmp_path / "missing.yaml"), "--leg", "0"]) == 2
    assert "'0' is not a waypoint number (1, 2, ...)" in capsys.readouterr().err


def test_a_paused_mission_is_replaced_from_the_command_line_and_completes_on_the_new_route(mission, tmp_path, capsys):
    db, sock = tmp_path / "journal.db", tmp_path / "ctl.sock"
    north = tmp_path / "north.yaml"  # the leg east kept, then 30 m north of its end
    north.write_text(MISSION.replace("name: two-legs", "name: two-legs-north") + "  - {lat: -35.3627208, lon: 149.1665504, name: north}\n")
    run = run_executive(mission, sock, "--journal", str(db), speedup=20)
    try:
        wait_status(sock, lambda s: s["state"] == "RUNNING" and s["leg"] == 2 and s["mode"] == "GUIDED")
        assert ctl(capsys, sock, "pause")["state"] == "PAUSED"
        wait_status(sock, lambda s: s["mode"] == "HOLD")
        upload = executive_process("ctl", "--socket", str(sock), "upload", str(north), stdout=subprocess.PIPE)
        out, err = upload.communicate(timeout=120)
        assert upload.returncode == 0, err
        first, *route = out.splitlines()
        assert first.startswith("PAUSED: mission replaced: 'two-legs' -> 'two-legs-north', at leg 2/3 (the waypoint of old leg 2)")
        assert route[0].startswith("3 waypoints; on the autopilot:") and route[2].startswith(">   2  -35.3629906, 149.1665504")
        status = wait_status(sock, lambda s: s["state"] == "PAUSED" and s["legs"] == 3)
        assert status["reason"].startswith("mission replaced:") and status["mode"] == "HOLD"  # still held: a person resumes it
        later = after(sock, status, 5.0)  # 5 s of vehicle time later: still paused and held, the new route on the autopilot
        assert (later["state"], later["mode"]) == ("PAUSED", "HOLD")
        assert geo.distance(later["lat"], later["lon"], status["lat"], status["lon"]) < 0.2  # it has not moved
        shown = request(str(sock), "route", operation="show")["route"]
        assert (shown["upload"]["state"], shown["on_autopilot"], len(shown["waypoints"])) == ("DONE", True, 3)  # uploaded, read back
        assert ctl(capsys, sock, "resume")["state"] == "RUNNING"
        _, err = run.communicate(timeout=120)
        assert run.returncode == 0, err
        assert "mission 'two-legs-north' COMPLETED" in err
    finally:
        run.kill()
    assert main(["report", str(db), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["mission"], report["outcome"], report["resumed_from"]) == ("two-legs-north", "COMPLETED", 1)
    legs = [(leg["waypoint"], leg["waypoints"]) for leg in report["legs"]]
    assert legs == [(2, 3), (3, 3), (None, 3)]  # heading for the east end, the new point north, then done
    resumed = next(t["t"] for t in report["transitions"] if t["after"] == "RUNNING")
    turned, done = report["legs"][1:]
    assert geo.distance(turned["lat"], turned["lon"], -35.3629906, 149.1665504) < 5.0  # turned north at the east end (driven through)
    assert geo.distance(done["lat"], done["lon"], -35.3627208, 149.1665504) < 3.0  # and reached the new point (as last reported)
    assert done["t"] - resumed < 120.0  # vehicle time: the rest of the east leg and 30 m north
