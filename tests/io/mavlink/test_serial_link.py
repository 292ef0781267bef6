"""The autopilot on a serial device that comes and goes (a USB cable knocked out, an autopilot rebooting), over real pseudo-terminals.

The device vanishing is a link loss, never an exception out of the tick loop: the link opens the
device again (by the same name: a ``/dev/serial/by-id/`` name finds it whatever ``/dev/ttyACM*`` it
comes back as) every second of clock time, and the executive carries on as after any link recovery.
"""

from __future__ import annotations

import logging
import threading
from pathlib import Path

import pytest
from pty_bridge import PtyBridge

from executive.cli import main
from executive.io.mavlink.endpoint import Unreachable
from executive.io.mavlink.link import REOPEN_EVERY_S, PymavlinkLink
from executive.mission.lifecycle import MissionStatus
from executive.runtime.assembly import build_runtime
from executive.runtime.pacing import SpeedGovernor
from executive.sim import SimServer
from executive.sim.options import simulated_home
from executive.world.clock import ManualClock, ScaledClock
from executive.world.dialect import encoder, mavlink
from tests_support import line_mission, mission_text


def heartbeat_bytes(seq: int = 0) -> bytes:
    mav = encoder(1, 1)
    mav.seq = seq
    msg = mav.heartbeat_encode(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 4, 3)
    return bytes(msg.pack(mav))


def received(link: PymavlinkLink, tries: int = 200) -> list[str]:
    """What the link receives (a pty delivers at once; a few empty reads are allowed for the kernel)."""
    kinds = []
    for _ in range(tries):
        msg = link.recv()
        if msg is not None:
            kinds.append(msg.get_type())
        elif kinds:
            break
    return kinds


@pytest.fixture
def device(tmp_path: Path):
    with PtyBridge(str(tmp_path / "ttyAP")) as bridge:
        yield bridge


def test_a_device_that_vanishes_is_lost_then_opened_again_under_its_name(device: PtyBridge) -> None:
    clock = ManualClock()
    link = PymavlinkLink(f"{device.name},921600", clock=clock)
    try:
        device.write(heartbeat_bytes(0))
        assert received(link) == ["HEARTBEAT"] and link.device_lost is None
        device.unplug()
        assert all(link.recv() is None for _ in range(20))  # no exception: pyserial's SerialException is the link's business
        assert link.device_lost is not None and link.device_lost.startswith(f"serial device {device.name} gone (")
        link.send(encoder(1, 191).heartbeat_encode(mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0))  # dropped
        clock.advance(REOPEN_EVERY_S)
        assert link.recv() is None and link.device_lost.endswith("(1 tries)")  # not there yet: tried once a second, never waited on
        device.plug()  # the kernel may give it another /dev/pts/N: the name is what is opened
        clock.advance(REOPEN_EVERY_S / 2)
        assert link.recv() is None and link.device_lost is not None  # not due yet
        clock.advance(REOPEN_EVERY_S / 2)
        assert link.recv() is None and link.device_lost is None  # open again (pyserial empties what was waiting on it)
        device.write(heartbeat_bytes(1))
        assert received(link) == ["HEARTBEAT"]
    finally:
        link.close()


def test_a_device_another_process_holds_is_refused_naming_it(device: PtyBridge) -> None:
    first = PymavlinkLink(device.name)
    try:
        with pytest.raises(Unreachable, match=f"the serial device {device.name} is taken by another process"):
            PymavlinkLink(device.name)
    finally:
        first.close()


def test_a_device_that_is_no_autopilot_is_said_naming_it_exit_3(device: PtyBridge, tmp_path: Path, capsys) -> None:
    mission = tmp_path / "m.yaml"
    mission.write_text(mission_text("line", "{lat: -35.3630, lon: 149.1652}"))
    stop = threading.Event()

    def modem() -> None:  # a device speaking something else (or at another baud rate): bytes, never a MAVLink packet
        while not stop.wait(0.02):
            device.write(b"AT+CSQ\r\n\x00\x17garbage\xfe\x03\x00\x00\x00\x00")

    talker = threading.Thread(target=modem, daemon=True)
    talker.start()
    try:
        code = main(["run", str(mission), "--mavlink", f"{device.name},57600", "--connect-timeout", "1", "--socket", "none"])
    finally:
        stop.set()
        talker.join()
    assert code == 3
    err = capsys.readouterr().err
    assert f"no heartbeat from an autopilot within 1 s on {device.name},57600: " in err
    assert "bytes that are not MAVLink came in" in err and "the wrong baud rate" in err


def test_a_mission_goes_on_after_the_device_is_unplugged_mid_leg_and_plugged_back(tmp_path: Path, caplog) -> None:
    """The whole mission over a pty bridged to the simulated rover; the device gone for 6 s of vehicle time on the second leg."""
    caplog.set_level(logging.INFO, logger="executive")
    mission = line_mission("unplugged")
    clock = ScaledClock(10.0)
    with (
        SimServer("rover", clock=clock, home=simulated_home(mission), ekf_ready_after_s=2.0) as sim,
        PtyBridge(str(tmp_path / "ttyAP"), ("127.0.0.1", sim.port)) as device,
    ):
        link = PymavlinkLink(f"{device.name},921600", clock=clock)
        try:
            runtime = build_runtime(mission, link, clock)
            runtime.pacer.listeners.append(SpeedGovernor(clock))
            cable = Cable(device, runtime, unplug_on_leg=1, out_for_s=6.0)
            runtime.observers.append(cable)
            assert runtime.link.connect(10.0 * clock.speedup)
            outcome = runtime.run()
        finally:
            link.close()
    assert cable.unplugged_at is not None and cable.plugged_at is not None
    assert outcome.status is MissionStatus.COMPLETED and outcome.reason == "every waypoint reached"
    said = [r.getMessage() for r in caplog.records]
    assert any(m.startswith(f"serial device {device.name} gone (") for m in said)
    assert any(m.startswith("link lost: no heartbeat") for m in said)
    assert any(m.startswith("failsafe link_loss: no heartbeat from the autopilot -> hold (HOLD)") for m in said)
    assert any(m.startswith(f"serial device {device.name} open again after ") for m in said)
    assert any(m.startswith("failsafe link_loss: recovered after") for m in said)
    assert link.device_lost is None


class Cable:
    """A run observer that pulls the cable once the vehicle heads for leg ``unplug_on_leg`` + 1, and plugs it back ``out_for_s`` later."""

    def __init__(self, device: PtyBridge, runtime: object, unplug_on_leg: int, out_for_s: float) -> None:
        self.device, self.runtime, self.leg, self.out_for_s = device, runtime, unplug_on_leg, out_for_s
        self.unplugged_at: float | None = None
        self.plugged_at: float | None = None

    def begin(self, mission: object, root: object, resumed_from: int | None) -> None:
        pass

    def ticked(self, tick: int, t: float) -> None:
        state = self.runtime.mission_state  # type: ignore[attr-defined]
        if self.unplugged_at is None and state.legs.leg_index >= self.leg:
            self.unplugged_at = t
            self.device.unplug()
        elif self.unplugged_at is not None and self.plugged_at is None and t >= self.unplugged_at + self.out_for_s:
            self.plugged_at = t
            self.device.plug()

    def end(self, outcome: str, reason: str) -> None:
        pass
