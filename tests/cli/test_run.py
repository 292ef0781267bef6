"""``executive run`` end to end: real processes, real UDP sockets, the built-in simulated vehicle.

The wall-clock timeouts only bound a hung process: on a busy machine the built-in simulator's
speed-up is capped (``SpeedGovernor``) and a run takes longer; what each test checks is in vehicle time.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from executive.cli import main
from executive.io.mavlink.link import load_signing_key
from executive.sim import SimServer
from executive.world.clock import ScaledClock
from executive.world.dialect import mavutil
from tests_support import SteppedClock, executive_process, run_in_lockstep, run_over

ROOT = Path(__file__).parents[2]
#: The in-process simulators' EKF is ready after 2 s, not the firmware's 40: what those tests check comes once the rover drives.
EKF_READY_S = 2.0


def test_ctrl_c_leaves_the_vehicle_in_its_safe_mode(tmp_path):
    square = tmp_path / "square.yaml"  # README's square with the EKF ready after 2 s (not 40): the test is about leg 2
    square.write_text((ROOT / "missions/rover_square.yaml").read_text() + "simulator: {ekf_ready_after_s: 2}\n")
    proc = executive_process("run", str(square), "--speedup", "20", "-v", stdout=subprocess.PIPE)
    lines = []
    deadline = time.monotonic() + 300
    assert proc.stdout is not None
    while time.monotonic() < deadline:
        lines.append(proc.stdout.readline())
        status = json.loads(lines[-1])  # not a terminal: the status comes as JSON lines
        if status["state"] == "RUNNING" and status["leg"] == 2:
            break
    else:
        pytest.fail("mission never reached leg 2: " + "".join(lines))
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 1
    assert "vehicle in HOLD" in err
    assert "ABORTED: stopped: SIGINT" in err


def test_a_broken_mission_exits_2_before_anything_starts(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nname: x\nvehicle: rover\nwaypoints:\n  - {lat: 95.0, lon: 8.5}\n")
    assert main(["run", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:5:11: waypoints[0].lat:" in err
    assert "simulated" not in err


def test_no_vehicle_exits_3(capsys):
    assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--mavlink", "udpout:127.0.0.1:9", "--connect-timeout", "0.3"]) == 3
    assert "no heartbeat from an autopilot" in capsys.readouterr().err


def test_a_bad_obstacles_url_exits_2_before_anything_starts(capsys):
    assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--obstacles", "tcp:0.0.0.0:14600", "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert "--obstacles: 'tcp:0.0.0.0:14600': expected udpin:HOST:PORT" in err
    assert "simulated" not in err


def test_an_obstacles_port_in_use_exits_3_before_the_vehicle_is_started(capsys):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--obstacles", f"udpin:127.0.0.1:{port}", "--socket", "none"]) == 3
    err = capsys.readouterr().err
    assert f"--obstacles: cannot listen on udpin:127.0.0.1:{port}" in err
    assert "simulated" not in err


def test_with_mavlink_the_speedup_is_the_vehicles_and_ticks_keep_to_its_time(tmp_path):
    """The executive and the vehicle in two processes joined by UDP: a simulator at 8x (as a SITL at --speedup 8) in this one;
    told so, the executive ticks ~10 times a vehicle second, not a wall one (on the wall clock against a vehicle:
    tests/cli/test_target_system.py). Not both in one process: on a busy machine they would starve each other of the GIL."""
    mission = tmp_path / "north.yaml"
    mission.write_text(
        "version: 1\nname: north\nvehicle: rover\nauto_arm: true\n"
        "waypoints:\n  - {lat: -35.3629906, lon: 149.1652300}\n"  # 30 m north of the simulator's home: 15 s and more of driving
    )
    with SimServer("rover", clock=ScaledClock(8.0), home=(-35.363261, 149.165230, 0.0), ekf_ready_after_s=0.5) as sim:
        run = executive_process("run", str(mission), "--mavlink", sim.url_for_client, "--speedup", "8", "--socket", "none", "--connect-timeout", "40")
        try:
            _, err = run.communicate(timeout=300)
        finally:
            if run.poll() is None:
                run.kill()
                run.communicate()
    assert run.returncode == 0, err
    assert "COMPLETED" in err
    assert "the vehicle's time runs 8x real time" in err
    ticks = int(err.rsplit("(", 1)[1].split(" ticks")[0])
    # the ticks due, in vehicle time, whatever the machine's load: the ticks run and those skipped (a loop more than a tick
    # behind does not catch up; the pacer counts what it missed: "the loop ran behind its 10 Hz: ..., 143 skipped")
    skipped = sum(int(n) for n in re.findall(r"the loop ran behind its 10 Hz: .*, (\d+) skipped", err))
    # ~20 s of vehicle time: 200 ticks due at 10 Hz of vehicle time; ticking on the wall clock it would be ~25
    assert ticks + skipped >= 100, err


def test_in_process_run_against_a_sim_server(square_mission, monkeypatch):
    """The runtime over a real loopback socket, in one process: what `run` does without --mavlink (lock-step: the server steps
    when the runtime waits)."""
    run_in_lockstep(monkeypatch)
    clock = SteppedClock(50.0)
    first = square_mission.waypoints[0]
    with SimServer("rover", clock=clock, home=(first.lat - 0.0002, first.lon, 0.0), ekf_ready_after_s=EKF_READY_S) as sim:
        _, outcome = run_over(sim.url_for_client, square_mission, clock)
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert os.environ.get("MAVLINK20") == "1"


def test_tlog_and_signing_end_to_end(tmp_path, capsys, monkeypatch):
    """A signed run on the built-in simulator, recorded: the tlog replays both sides, every packet signed."""
    key, tlog = tmp_path / "key", tmp_path / "run.tlog"
    key.write_text("field team passphrase\n")
    mission = tmp_path / "short.yaml"
    mission.write_text(
        "version: 1\nname: short\nvehicle: rover\nauto_arm: true\nhome: {lat: -35.363261, lon: 149.165230}\n"
        "simulator: {ekf_ready_after_s: 2}\nwaypoints:\n  - {lat: -35.3631710, lon: 149.1652300}\n"  # 10 m north
    )
    run_in_lockstep(monkeypatch)
    assert main(["run", str(mission), "--speedup", "50", "--tlog", str(tlog), "--signing-key", str(key), "--socket", "none"]) == 0, (
        capsys.readouterr().err
    )
    replay = mavutil.mavlink_connection(str(tlog), dialect="ardupilotmega")
    replay.setup_signing(load_signing_key(key), sign_outgoing=False)  # to check each signature
    senders, signed, total = set(), 0, 0
    while (msg := replay.recv_match()) is not None:
        total += 1
        signed += msg.get_signed()
        senders.add((msg.get_srcSystem(), msg.get_srcComponent(), msg.get_type() == "HEARTBEAT"))
    assert {(1, 1, True), (1, 191, True)} <= senders  # the autopilot's heartbeats and ours
    assert total > 100 and signed == total


@pytest.mark.parametrize(("autopilot_key", "failing"), [(b"A" * 32, "signed with another key"), (None, "unsigned")])
def test_a_wrong_signing_key_is_named_as_the_reason_no_heartbeat_was_heard(tmp_path, capsys, autopilot_key, failing):
    ours = tmp_path / "key"
    ours.write_text("our passphrase\n")
    with SimServer("rover", clock=ScaledClock(), signing_key=autopilot_key) as sim:
        argv = ["run", str(ROOT / "missions/rover_square.yaml"), "--mavlink", sim.url_for_client, "--signing-key", str(ours)]
        assert main([*argv, "--connect-timeout", "1.5", "--socket", "none"]) == 3
    err = capsys.readouterr().err
    assert "no heartbeat from an autopilot within 1.5 s: every packet from the autopilot was unsigned or signed with another key" in err
    counts = re.search(r"\((\d+) unsigned, (\d+) signed with another key\)", err)
    assert counts is not None, err
    counted = {"unsigned": int(counts[1]), "signed with another key": int(counts[2])}
    assert counted.pop(failing) > 0 and list(counted.values()) == [0]


def test_an_unreadable_signing_key_is_bad_input(tmp_path, capsys):
    assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--signing-key", str(tmp_path / "missing")]) == 2
    assert "--signing-key" in capsys.readouterr().err


def test_a_mission_completes_over_a_lossy_link(square_mission):
    """10 % of datagrams lost each way and 5 % reordered: retries and guards carry the mission through."""
    from lossy_udp import LossyUdpProxy

    clock = ScaledClock(25.0)
    first = square_mission.waypoints[0]
    with (
        SimServer("rover", clock=clock, home=(first.lat - 0.0002, first.lon, 0.0), ekf_ready_after_s=EKF_READY_S) as sim,
        LossyUdpProxy(sim.port, drop=0.1, reorder=0.05, seed=3, lifetime_s=30.0) as proxy,
    ):
        runtime, outcome = run_over(f"udpout:127.0.0.1:{proxy.port}", square_mission, clock)
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert proxy.up.dropped > 0 and proxy.down.dropped > 0
    assert runtime.link.reader.health.lost > 0  # the reader saw the gaps


def test_the_mission_chooses_its_simulator_and_plays_its_event_file(tmp_path, capsys, monkeypatch):
    # the loss 30 s after boot, on a 60 m leg: the executive has connected by then even when a busy machine
    # slows its start (at 3 s, 0.15 s of wall time, it was lost before the executive ever heard the vehicle)
    (tmp_path / "events.yaml").write_text("version: 1\nfaults:\n  - {kind: link_loss, at_s: 30, for_s: 5}\n")
    mission = tmp_path / "tracked.yaml"
    mission.write_text(
        "version: 1\nname: tracked\nvehicle: rover\nauto_arm: true\nhome: {lat: -35.363261, lon: 149.165230}\n"
        "simulator: {model: bunker, events: events.yaml, ekf_ready_after_s: 2}\n"
        "waypoints:\n  - {lat: -35.3627210, lon: 149.1652300}\n"  # 60 m north
    )
    run_in_lockstep(monkeypatch)
    code = main(["run", str(mission), "--speedup", "20", "--socket", "none", "-v"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "simulated bunker" in err
    assert "link lost" in err and "link up" in err  # the event file's link loss was played and recovered from


def test_a_waypoint_out_of_reach_is_refused_at_start_exit_1_with_nothing_sent(tmp_path, capsys, monkeypatch):
    """Issue 28: a `waypoints` mission with a waypoint 10 km off armed, set GUIDED and drove off. Now refused before the tree runs:
    the log, the status (JSON lines) and the last line say why, exit 1 (README: aborted at run time), the vehicle untouched."""
    far = tmp_path / "far.yaml"  # no home: the simulated rover boots at the first waypoint
    far.write_text(
        "version: 1\nname: far\nvehicle: rover\nauto_arm: true\nsimulator: {ekf_ready_after_s: 2}\nlimits: {leg_timeout_s: 3000}\nwaypoints:\n"
        "  - {lat: -35.3629906, lon: 149.1652300}\n  - {lat: -35.2730000, lon: 149.1652300, name: town}\n"
    )  # a leg_timeout_s the 10 km leg fits (issue 40: else validate refuses it, exit 2)
    run_in_lockstep(monkeypatch)
    assert main(["run", str(far), "--speedup", "10", "--socket", "none"]) == 1
    out, err = capsys.readouterr()
    why = (
        "refused before anything was commanded: Within reach: waypoints[1] (town): 9984 m from the vehicle, over limits.max_goal_distance_m (5000 m)"
    )
    assert f"WARNING runtime: mission 'far' {why}" in err
    assert re.search(rf"executive: mission 'far' ABORTED: {re.escape(why)} \(\d+ ticks\)\n$", err), err
    last = json.loads(out.splitlines()[-1])
    assert (last["state"], last["reason"], last["armed"], last["mode"]) == ("ABORTED", why, False, "MANUAL")
    assert "vehicle in HOLD" not in err and "commanding" not in err


def test_a_second_ctrl_c_while_stopping_keeps_the_outcomes_exit_code(tmp_path):
    """Issue 28: two SIGINTs 10-50 ms apart turned exit 1 (ABORTED, vehicle made safe) into 130 most times: the second landed after
    the handler was put back and raised KeyboardInterrupt in the shutdown. Here the vehicle goes silent as the operator presses
    Ctrl-C: making it safe asks HOLD every 1.5 s until its bound (9 s: 3 asks each for HOLD and the disarm after it), the second
    Ctrl-C comes meanwhile (sent once the first was acted on; the executive's clock held from that moment until it arrives,
    tests/held_clock.py, so it lands there at 10x however busy the machine), and a third as the run ends ABORTED (where the
    handler used to be put back)."""
    square = tmp_path / "square.yaml"
    square.write_text((ROOT / "missions/rover_square.yaml").read_text() + "simulator: {ekf_ready_after_s: 2}\n")
    # the EKF ready after 2 s, not ArduPilot's 40 (the mission's simulator options are the built-in one's): armed in seconds
    sim = SimServer("rover", clock=ScaledClock(10.0), home=(-35.363261, 149.165230, 0.0), ekf_ready_after_s=EKF_READY_S).start()
    try:
        proc = executive_process(
            *("run", str(square), "--mavlink", sim.url_for_client, "--target-system", "1", "--speedup", "10", "--socket", "none"),
            via=("held_clock.py", "stopped"),
            stdout=subprocess.PIPE,
        )
        assert proc.stdout is not None and proc.stderr is not None
        for line in proc.stdout:
            if json.loads(line)["armed"]:  # armed by this run: there is something to make safe (issue 34: else nothing is commanded)
                break
    finally:
        sim.stop()
    proc.send_signal(signal.SIGINT)
    said = []
    for line in proc.stderr:
        said.append(line)
        if "mission aborted: stopped: SIGINT" in line:  # the loop took the first: now it waits for the vehicle's HOLD
            proc.send_signal(signal.SIGINT)
        if "mission RUNNING -> ABORTED" in line:  # the run is over: the shutdown begins
            proc.send_signal(signal.SIGINT)
            break
    # the rest from the same file object: communicate() reads the pipe itself and would miss what iterating it read ahead
    err = "".join(said) + proc.stderr.read()
    proc.wait(timeout=60)
    proc.stdout.read()
    assert proc.returncode == 1, err
    assert "executive: run: SIGINT again: already stopping (the vehicle is made safe all the same; the exit code stays the mission's)" in err
    assert re.search(r"executive: could not make the vehicle safe: HOLD not answered x\d.*\n", err), err  # in the last lines, said so
    assert err.index("SIGINT again: already stopping") < err.index("could not make the vehicle safe")  # came while making it safe
    assert re.search(r"executive: mission 'rover-square' ABORTED: stopped: SIGINT \(\d+ ticks\)\n$", err), err
