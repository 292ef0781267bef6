"""The mission protocol over real UDP against the simulated rover, directly (lock-step) and through a lossy link (50x).

The loop polls the socket, as the runtime's tick would. Directly, the server steps when the loop waits (a
:class:`~tests_support.SteppedClock`): the transfer's timeouts (1.5 s of vehicle time, 30 ms of wall time at 50x) never
fire for a busy machine's sake, so no retry is a fact to assert. Through the proxy's thread, the waits are in wall time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import py_trees
import pytest

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.heartbeat import Heartbeat
from executive.io.mavlink.link import PymavlinkLink
from executive.io.mavlink.mission_protocol import MissionItem, MissionTransfer, TransferState, first_mismatch, waypoint_items
from executive.io.mavlink.reader import MavlinkReader
from executive.sim import SimServer
from executive.world.clock import Clock, ScaledClock
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m
from executive.world.vehicles import PROFILES
from lossy_udp import LossyUdpProxy
from tests_support import SteppedClock

HOME = (47.397742, 8.545594, 0.0)
M_PER_DEG_LAT = 111_319.49
SPEEDUP = 50.0
MISSION_IDS = {39, 40, 41, 42, 43, 44, 45, 47, 51, 73}  # MISSION_ITEM .. MISSION_ACK, MISSION_REQUEST_INT, MISSION_ITEM_INT


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


def path(legs: int, leg_m: float) -> list[tuple[float, float, float]]:
    """A zig-zag north-east of HOME: ``legs`` points ``leg_m`` apart."""
    lat0, lon0 = HOME[0], HOME[1]
    dlat, dlon = leg_m / M_PER_DEG_LAT, leg_m / (M_PER_DEG_LAT * math.cos(math.radians(lat0)))
    return [(lat0 + dlat * ((i + 2) // 2), lon0 + dlon * ((i + 1) // 2), 0.0) for i in range(legs)]


class RecordingTransfer(MissionTransfer):
    """Keeps every MISSION_ITEM_REACHED (the blackboard holds the last one only)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.reached: list[int] = []

    def on_reached(self, msg: MAVLinkMessage, now: float) -> None:
        self.reached.append(msg.seq)
        super().on_reached(msg, now)


class Executive:
    """The executive's MAVLink side (link, reader, commander, mission transfer, heartbeat), pumped until a condition holds."""

    def __init__(self, url: str, clock: Clock, **transfer_options: float) -> None:
        self.link = PymavlinkLink(url)
        self.commander = Commander(self.link, clock, PROFILES["rover"])
        self.transfer = RecordingTransfer(self.link, clock, **transfer_options)
        self.reader = MavlinkReader(self.link, clock, self.commander, mission=self.transfer)
        self.heartbeat = Heartbeat(self.link, clock)
        self.clock = clock

    def pump_until(self, done: Callable[[], bool], what: str, timeout_s: float = 3.0) -> None:
        """Poll until ``done()``: within ``timeout_s`` of wall time, or in lock-step as much vehicle time as that is at 50x."""
        stepped = isinstance(self.clock, SteppedClock)
        now = self.clock.now if stepped else time.monotonic
        deadline = now() + timeout_s * (SPEEDUP if stepped else 1.0)
        while now() < deadline:
            self.heartbeat.service()
            self.reader.drain()
            self.commander.flush()
            self.transfer.flush()
            if done():
                return
            if stepped:  # the server answers when our clock moves on
                self.clock.sleep_until(self.clock.now() + SteppedClock.STEP_S)
            else:
                time.sleep(0.001)  # poll the socket again in a moment
        raise AssertionError(f"not within {timeout_s} s: {what}")

    def connect(self) -> None:
        self.pump_until(lambda: self.reader.autopilot is not None, "the autopilot's heartbeat")
        self.pump_until(lambda: bb("/vehicle/ekf") is not None and bb("/vehicle/ekf").position_ok(), "an EKF position")

    def finish(self, ticket: int, what: str, timeout_s: float = 3.0) -> None:
        """Pump until transfer ``ticket`` is over; it must have succeeded."""

        def over() -> bool:
            status = self.transfer.status
            return status is not None and status.ticket == ticket and status.state is not TransferState.IN_PROGRESS

        self.pump_until(over, what, timeout_s)
        status = self.transfer.status
        assert status.state is TransferState.DONE, status.reason

    def close(self) -> None:
        self.link.close()


@pytest.fixture
def server() -> Iterator[SimServer]:
    with SimServer("rover", clock=ScaledClock(SPEEDUP), home=HOME, ekf_ready_after_s=2.0) as sim:
        yield sim


@pytest.fixture
def stepped_server() -> Iterator[SimServer]:
    """The simulated rover stepped by its clock (:class:`SteppedClock`), its thread never started."""
    clock = SteppedClock(SPEEDUP)
    sim = SimServer("rover", clock=clock, home=HOME, ekf_ready_after_s=2.0)
    clock.servers.append(sim)
    yield sim
    sim.stop()


@pytest.fixture
def executive_for() -> Iterator[Callable[..., Executive]]:
    made: list[Executive] = []

    def make(server: SimServer, url: str, **transfer_options: float) -> Executive:
        made.append(Executive(url, server.clock, **transfer_options))
        return made[-1]

    yield make
    for executive in made:
        executive.close()


def test_upload_read_back_set_current_and_fly_the_mission(stepped_server: SimServer, executive_for: Callable[..., Executive]) -> None:
    server = stepped_server
    ex = executive_for(server, server.url_for_client)
    ex.connect()
    items = waypoint_items(path(5, 6.0))
    ex.finish(ex.transfer.upload(items, HOME[:2]), "the upload and its read-back")
    assert ex.transfer.status.total == 6 and ex.transfer.status.retries == 0

    ex.finish(ex.transfer.download(), "the download")
    assert first_mismatch(items, ex.transfer.items) is None
    assert [item.frame for item in ex.transfer.items] == [m.MAV_FRAME_GLOBAL_RELATIVE_ALT] * 5  # as ArduPilot reports it
    home = ex.transfer.home
    assert isinstance(home, MissionItem) and (home.x, home.y) == pytest.approx(server.autopilot.home, abs=1e-7)

    ex.finish(ex.transfer.set_current(3), "set current 3")
    assert bb("/vehicle/mission_current").seq == 3
    ex.finish(ex.transfer.set_current(1), "set current 1")

    ex.commander.arm()
    ex.pump_until(lambda: bb("/vehicle/armed"), "armed")
    ex.commander.command_long(m.MAV_CMD_MISSION_START, (0, 0))
    ex.pump_until(lambda: bb("/vehicle/mode") == "AUTO", "AUTO")
    ex.pump_until(lambda: len(ex.transfer.reached) >= 5, "every waypoint reached", timeout_s=4.0)
    assert ex.transfer.reached == [1, 2, 3, 4, 5]
    ex.pump_until(lambda: bb("/vehicle/mission_current").state == m.MISSION_STATE_COMPLETE, "the mission complete")
    assert bb("/vehicle/mode") == "AUTO"  # ArduRover stays in AUTO, stopped, at the end


def test_upload_and_download_survive_a_lossy_link(server: SimServer, executive_for: Callable[..., Executive]) -> None:
    with LossyUdpProxy(server.port, drop=0.2, reorder=0.1, seed=7, lifetime_s=8.0) as proxy:
        # more retries than by default: at 20 % loss each way, a round trip fails 36 % of the time
        ex = executive_for(server, f"udpout:127.0.0.1:{proxy.port}", retries=10)
        ex.connect()
        items = waypoint_items(path(8, 5.0))
        ex.finish(ex.transfer.upload(items, HOME[:2]), "the upload and its read-back", timeout_s=4.0)
        retries = ex.transfer.status.retries
        ex.finish(ex.transfer.download(), "the download", timeout_s=4.0)
        retries += ex.transfer.status.retries
        assert first_mismatch(items, ex.transfer.items) is None
    assert retries > 0  # the executive's own resends (ArduPilot's re-requests also helped the upload)
    lost = [msgid for msgid in proxy.up.dropped_ids + proxy.down.dropped_ids if msgid in MISSION_IDS]
    assert lost, "no mission message was lost: the link was not lossy enough to show anything"
    assert proxy.up.reordered + proxy.down.reordered > 0
