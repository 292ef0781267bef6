"""One check for every way to start: ``run``, ``run --wait``, ``service install`` and ``ctl upload`` refuse what ``run`` refuses.

``service install`` checks the very command line its unit runs: a unit that exits 2 at boot is never
restarted (RestartPreventExitStatus=1 2), so it must not be written. Every case here is refused
before anything is opened: no simulator started, no unit printed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.cli import main
from executive.cli.run_checks import speedup_refusal
from executive.mission.loader import load_mission
from executive.runtime.assembly import build_runtime
from executive.testing import FakeLink
from executive.world.clock import ManualClock

ROOT = Path(__file__).parents[2]
MISSIONS = ROOT / "missions"
SQUARE = str(MISSIONS / "rover_square.yaml")
#: The ASV mission samples with no instrument named (the simulated one: the built-in simulator only).
ASV = str(MISSIONS / "asv_sampling.yaml")
AUV = str(MISSIONS / "auv_survey.yaml")
VTOL = str(MISSIONS / "vtol_transit.yaml")

#: (mission, `run` options, `service install` options, what the refusal says)
REFUSED = [
    pytest.param(
        SQUARE, ["--mavlink", "udp:127.0.0.1:14550x"], ["--mavlink", "udp:127.0.0.1:14550x"], "port '14550x' is not a number 0-65535", id="mavlink"
    ),
    pytest.param(
        ASV,
        ["--mavlink", "udpout:127.0.0.1:9"],
        ["--mavlink", "udpout:127.0.0.1:9"],
        "sampling.instrument: the mission takes samples and names no instrument",
        id="no-instrument",
    ),
    pytest.param(
        AUV, ["--autopilot", "px4"], ["--run-options=--autopilot px4"], "--autopilot px4: px4 drives rover, vtol here, not a sub", id="sub-px4"
    ),
    pytest.param(SQUARE, ["--speedup", "200"], ["--run-options=--speedup 200"], "--speedup 200: the executive cannot follow it", id="speedup"),
    pytest.param(
        SQUARE,
        ["--mavlink", "udpout:127.0.0.1:9", "--faults", str(MISSIONS / "faults" / "link_loss.yaml")],
        ["--mavlink", "udpout:127.0.0.1:9", f"--run-options=--faults {MISSIONS / 'faults' / 'link_loss.yaml'}"],
        "--faults applies to the built-in simulator only",
        id="faults-mavlink",
    ),
    pytest.param(SQUARE, ["--gcs", "udpin:0.0.0.0:99999"], ["--run-options=--gcs udpin:0.0.0.0:99999"], "--gcs ", id="gcs"),
    pytest.param(SQUARE, ["--can-log", "x.log"], ["--run-options=--can-log x.log"], "--can-log needs --can IFACE:CHANNEL", id="can-log"),
    pytest.param(SQUARE, ["--can", "nonsense"], ["--run-options=--can nonsense"], "--can: 'nonsense': expected IFACE:CHANNEL", id="can"),
    pytest.param(AUV, ["--can", "virtual:x"], ["--run-options=--can virtual:x"], "drives a sub (vehicle: sub), which has no tracks", id="can-sub"),
    pytest.param(VTOL, ["--can", "virtual:x"], ["--run-options=--can virtual:x"], "this mission drives a vtol (vehicle: vtol)", id="can-vtol"),
    pytest.param(
        SQUARE, ["--can", "virtual:x", "--autopilot", "px4"], ["--run-options=--can virtual:x --autopilot px4"], "the autopilot is PX4", id="can-px4"
    ),
    pytest.param(
        SQUARE, ["--can", "virtual:x"], ["--run-options=--can virtual:x"], "the built-in simulator's rover has no tracked base", id="can-rover-sim"
    ),
    pytest.param(SQUARE, ["--obstacles", "tcp:x"], ["--run-options=--obstacles tcp:x"], "--obstacles: ", id="obstacles"),
    pytest.param(SQUARE, ["--web-token-file", "t"], ["--run-options=--web-token-file t"], "--web-token-file needs --web [HOST:]PORT", id="web-token"),
    pytest.param(SQUARE, ["--web", "80x"], ["--run-options=--web 80x"], "--web: '80x': the port '80x' is not a number", id="web"),
    pytest.param(SQUARE, ["--rate", "0"], ["--run-options=--rate 0"], "--rate 0: must be a number > 0", id="rate"),
    pytest.param(SQUARE, ["--speedup", "nan"], ["--run-options=--speedup nan"], "--speedup nan: must be a number > 0", id="speedup-nan"),
    pytest.param(SQUARE, ["--speedup", "-1"], ["--run-options=--speedup -1"], "--speedup -1: must be a number > 0", id="speedup-negative"),
]


@pytest.mark.parametrize(("mission", "run_options", "service_options", "why"), REFUSED)
@pytest.mark.parametrize("way", ["run", "run --wait"])
def test_run_refuses_before_anything_is_opened(capsys, mission, run_options, service_options, why, way):
    wait = ["--wait"] if way == "run --wait" else []
    assert main(["run", mission, *run_options, *wait, "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert why in err
    assert "executive: run: simulated" not in err and "autopilot found" not in err  # nothing started, nothing heard


@pytest.mark.parametrize(("mission", "run_options", "service_options", "why"), REFUSED)
def test_service_install_refuses_what_run_would_and_writes_no_unit(capsys, tmp_path, mission, run_options, service_options, why):
    """Before: exit 0 with --print for each (the unit then failed once at boot and was never restarted)."""
    assert main(["service", "install", mission, *service_options, "--unit-dir", str(tmp_path), "--print"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert "executive: service: `executive run` would refuse it (exit 2, never restarted): " in err and why in err
    assert list(tmp_path.iterdir()) == []


def test_service_install_still_writes_a_unit_run_accepts(capsys, tmp_path):
    assert main(["service", "install", SQUARE, "--mavlink", "udpin:0.0.0.0:14550", "--run-options=--gcs udpin:0.0.0.0:14551", "--print"]) == 0
    assert "ExecStart=" in capsys.readouterr().out


def test_the_speedup_readme_refuses_is_refused_and_the_one_below_is_not():
    """README: `--speedup 200` at 10 Hz (2000 ticks per wall second) is refused; before, it ran (capped at 28.7x on a busy machine)."""
    assert speedup_refusal(10.0, 200.0) is not None
    assert "10 ticks per second of vehicle time would be 2000 per second of wall time" in (speedup_refusal(10.0, 200.0) or "")
    assert speedup_refusal(10.0, 199.0) is None and speedup_refusal(20.0, 100.0) is not None


@pytest.mark.parametrize(
    ("running", "upload", "autopilot", "simulated", "why"),
    [
        (str(MISSIONS / "boat_survey.yaml"), ASV, None, False, "sampling.instrument: the mission takes samples and names no instrument"),
        (SQUARE, str(MISSIONS / "ugv_rc_route.yaml"), "px4", True, "autopilot px4: tree ugv_rc_route needs ArduPilot"),
    ],
    ids=["no-instrument", "px4-ugv"],
)
def test_ctl_upload_refuses_what_run_would_refuse(running, upload, autopilot, simulated, why):
    """A running executive (run --wait serving mission after mission) checks an upload with run's own mission checks.
    Before: the px4 case was loaded READY (only an instrument was checked, and the autopilot only when replacing a paused mission)."""
    runtime = build_runtime(load_mission(running), FakeLink(), ManualClock(100.0), autopilot=autopilot, simulated_vehicle=simulated)
    try:
        reply = runtime.operator.request("upload", filename=upload, text=Path(upload).read_text(encoding="utf-8"))
        assert not reply.ok
        assert reply.reason.startswith(f"{upload}: {why}")
        assert runtime.mission_state.mission is not None and runtime.mission_state.mission.name == load_mission(running).name  # unchanged
    finally:
        runtime.close()


def test_rc_from_can_without_a_can_bus_is_refused_at_start_with_the_hint(capsys, tmp_path):
    """Issue 43: it ran, waited 60 s and ended `RC fresh? no RC report yet`."""
    import yaml

    mission = yaml.safe_load(Path(SQUARE).read_text(encoding="utf-8"))
    mission["rc"] = {**mission.get("rc", {}), "source": "can"}
    path = tmp_path / "can_rc.yaml"
    path.write_text(yaml.safe_dump(mission), encoding="utf-8")
    assert main(["run", str(path), "--socket", "none"]) == 2
    err = capsys.readouterr().err
    assert f"{path}: rc.source: can reads the transmitter from the AgileX base's CAN bus (frame 0x241): give --can IFACE:CHANNEL" in err
    assert "executive: run: simulated" not in err  # nothing started
