"""Several vehicles on one link: each executive commands its own autopilot only (``--target-system``), or refuses to guess."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from executive.cli import main
from executive.sim import SimServer
from executive.sim.firmware import DEFAULT_HOME
from executive.world.clock import ScaledClock
from executive.world.dialect import MAVLinkMessage
from mavlink_hub import UdpHub
from tests_support import executive_process

ROOT = Path(__file__).parents[2]
SPEEDUP = 4.0  # the simulated vehicles; an executive on --mavlink runs in real time


def _mission(path: Path, name: str, lat: float, lon: float) -> Path:
    path.write_text(
        f"version: 1\nname: {name}\nvehicle: rover\nauto_arm: true\n"
        "limits: {acceptance_radius_m: 2.0, leg_timeout_s: 60, ekf_wait_s: 30}\n"
        f"waypoints:\n  - {{lat: {lat + 0.00015:.7f}, lon: {lon:.7f}}}\n"
    )
    return path


class Received:
    """What a simulated autopilot was sent that names a target: (message type, sender's system, target system)."""

    def __init__(self, sim: SimServer) -> None:
        self.messages: list[tuple[str, int, int]] = []
        handle = sim.autopilot.handle

        def recording(msg: MAVLinkMessage) -> list[MAVLinkMessage]:
            if hasattr(msg, "target_system"):
                self.messages.append((msg.get_type(), msg.get_srcSystem(), msg.target_system))
            return handle(msg)

        sim.autopilot.handle = recording  # type: ignore[method-assign]

    def addressed_to(self, system: int) -> list[tuple[str, int, int]]:
        return [m for m in self.messages if m[2] in (0, system)]


def _run_args(mission: Path, hub: UdpHub, *args: str) -> list[str]:
    """``executive run``'s arguments for ``mission`` on the hub's link."""
    return ["run", str(mission), "--mavlink", f"udpout:127.0.0.1:{hub.port}", "--socket", "none", *args]


def _executive(mission: Path, hub: UdpHub, *args: str) -> subprocess.Popen[str]:
    return executive_process(*_run_args(mission, hub, *args))


@pytest.fixture
def two_vehicles():
    """Rovers 1 and 2, 100 m apart, behind one hub."""
    clock = ScaledClock(SPEEDUP)
    lat, lon, heading = DEFAULT_HOME
    homes = {1: (lat, lon, heading), 2: (lat + 0.0009, lon, heading)}
    sims = {n: SimServer("rover", clock=clock, home=home, system_id=n, ekf_ready_after_s=2.0) for n, home in homes.items()}
    received = {n: Received(sim) for n, sim in sims.items()}
    for sim in sims.values():
        sim.start()
    with UdpHub([sim.port for sim in sims.values()]) as hub:
        yield sims, received, homes, hub
    for sim in sims.values():
        sim.stop()


def test_two_executives_on_one_hub_each_drive_their_own_vehicle(two_vehicles, tmp_path, capsys):
    """Vehicle 2's executive in a process of its own, vehicle 1's in this one (an interpreter's start less), at the same time."""
    sims, received, homes, hub = two_vehicles
    missions = {n: _mission(tmp_path / f"v{n}.yaml", f"vehicle-{n}", *homes[n][:2]) for n in (1, 2)}
    second = _executive(missions[2], hub, "--target-system", "2", "--sysid", "2")
    try:
        codes = {1: main(_run_args(missions[1], hub, "--target-system", "1", "--sysid", "1"))}
        errors = {1: capsys.readouterr().err, 2: second.communicate(timeout=300)[1]}
        codes[2] = second.returncode
    finally:
        if second.poll() is None:
            second.kill()
            second.communicate()
    for n in (1, 2):
        assert codes[n] == 0, errors[n]
        assert "COMPLETED: every waypoint reached" in errors[n]
        mine = received[n].addressed_to(n)
        assert {kind for kind, _, _ in mine} >= {"COMMAND_LONG", "SET_POSITION_TARGET_GLOBAL_INT"}  # armed, set GUIDED, driven there
        assert {sender for _, sender, _ in mine} == {n}, f"vehicle {n} was addressed by {sorted({s for _, s, _ in mine})}"
        other = 3 - n
        assert any(target == other for _, _, target in received[n].messages)  # the hub did carry the other's commands here...
        with sims[n].lock:  # ...and each vehicle went to its own waypoint, 17 m north of its own home
            vehicle = sims[n].autopilot.vehicle
            assert abs(vehicle.lat - (homes[n][0] + 0.00015)) < 3e-5, (n, vehicle.lat)


def test_without_a_target_system_two_autopilots_refuse_the_start(two_vehicles, tmp_path, capsys):
    _, received, homes, hub = two_vehicles
    assert main(_run_args(_mission(tmp_path / "v.yaml", "which", *homes[1][:2]), hub, "--connect-timeout", "10")) == 3
    err = capsys.readouterr().err
    assert "2 autopilots on the link: system 1 (MAV_TYPE 10), system 2 (MAV_TYPE 10)" in err
    assert "--target-system" in err
    for n in (1, 2):  # nothing but heartbeats was sent: no command reached either vehicle
        assert received[n].messages == []


def test_a_target_system_that_is_not_there_is_no_vehicle(two_vehicles, tmp_path, capsys):
    _, received, homes, hub = two_vehicles
    assert main(_run_args(_mission(tmp_path / "v.yaml", "absent", *homes[1][:2]), hub, "--target-system", "7", "--connect-timeout", "2")) == 3
    assert "no heartbeat from autopilot 7/1 within 2 s" in capsys.readouterr().err
    assert received[1].messages == [] and received[2].messages == []
