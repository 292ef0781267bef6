"""systemd's notify protocol against a fake NOTIFY_SOCKET: READY, WATCHDOG from the tick loop (and none when it is stuck), STATUS, STOPPING."""

from __future__ import annotations

import itertools
import os
import socket
from pathlib import Path

import pytest

from executive.io.systemd import Notifier, Watchdog, watchdog_period_s
from executive.runtime.assembly import service_manager
from executive.testing import RuntimeOnLink
from executive.world.clock import ManualClock


@pytest.fixture
def manager(tmp_path: Path):
    """The service manager's end: a Unix datagram socket, as systemd binds for $NOTIFY_SOCKET."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(str(tmp_path / "notify"))
    sock.setblocking(False)
    yield sock
    sock.close()


def received(sock: socket.socket) -> list[dict[str, str]]:
    """Every message waiting, each as its fields."""
    messages = []
    while True:
        try:
            data = sock.recv(4096)
        except BlockingIOError:
            return messages
        messages.append(dict(line.split("=", 1) for line in data.decode().split("\n")))


def test_the_environment_says_whether_and_how_often(tmp_path: Path) -> None:
    assert Notifier.from_environment({}) is None
    assert Notifier.from_environment({"NOTIFY_SOCKET": "relative/path"}) is None
    assert Notifier.from_environment({"NOTIFY_SOCKET": "@systemd-notify"}).address == "\0systemd-notify"
    assert watchdog_period_s({"WATCHDOG_USEC": "20000000"}) == 10.0  # half of WatchdogSec=20
    assert watchdog_period_s({"WATCHDOG_USEC": "20000000", "WATCHDOG_PID": str(os.getpid())}) == 10.0
    assert watchdog_period_s({"WATCHDOG_USEC": "20000000", "WATCHDOG_PID": "1"}) is None  # for another process
    assert watchdog_period_s({}) is None and watchdog_period_s({"WATCHDOG_USEC": "0"}) is None


def test_a_manager_gone_costs_nothing(tmp_path: Path) -> None:
    notifier = Notifier(str(tmp_path / "nobody"))
    assert notifier.notify(WATCHDOG=1) is False and notifier.dropped == 1


@pytest.fixture
def clock() -> ManualClock:
    """The notifications' times count from 0."""
    return ManualClock()


@pytest.fixture
def watchdog(manager: socket.socket, clock: ManualClock) -> Watchdog:
    """The watchdog on the manager's socket, a ping a second."""
    return Watchdog(Notifier(manager.getsockname()), clock, period_s=1.0)


@pytest.fixture
def watched(square_mission, watchdog: Watchdog, runtime_on_link) -> RuntimeOnLink:
    """A runtime with the watchdog plugged in, its autopilot answering (HOLD, disarmed); the manager's socket read by the test."""
    return runtime_on_link(square_mission, mode="HOLD", armed=False, plugs=[service_manager(watchdog)])


def test_watchdog_pings_come_from_the_tick_loop_and_stop_when_it_is_stuck(watched: RuntimeOnLink, watchdog: Watchdog, manager) -> None:
    watchdog.ready("autopilot 1/1 heard")
    ready = received(manager)
    assert ready[:2] == [{"READY": "1", "STATUS": "autopilot 1/1 heard"}, {"WATCHDOG": "1"}]  # the watchdog starts now
    pings_at = [0.0]
    for _ in range(50):  # 5 s of ticks: a ping every second (half of a 2 s WatchdogSec), at most a tick late
        watched.tick()
        pings_at += [watched.clock.now() for m in received(manager) if m.get("WATCHDOG") == "1"]
    gaps = [b - a for a, b in itertools.pairwise(pings_at)]
    assert len(gaps) == 4 and all(1.0 - 1e-9 <= gap <= 1.1 + 1e-9 for gap in gaps), pings_at
    watched.clock.advance(30.0)  # a tick stuck for 30 s: the loop services nothing, so nothing is sent
    assert received(manager) == []
    watched.tick()  # the loop comes back (too late under systemd: it was killed at 2 s): pings again at once
    assert any(m.get("WATCHDOG") == "1" for m in received(manager))


def test_status_follows_the_mission_and_stopping_ends_it(watched: RuntimeOnLink, watchdog: Watchdog, manager) -> None:
    watched.tick(3)  # the autopilot's heartbeat: its mode known
    assert [m["STATUS"] for m in received(manager) if "STATUS" in m][-1] == "READY     leg 1/4  HOLD disarmed"
    watched.tick(10)
    assert [m for m in received(manager) if "STATUS" in m] == []  # nothing changed, under 5 s
    watched.runtime.mission_state.start()
    watched.tick()
    assert [m["STATUS"].split()[0] for m in received(manager) if "STATUS" in m] == ["RUNNING"]  # a change: at once
    watched.tick(49)  # waiting for the EKF: nothing changes
    assert [m for m in received(manager) if "STATUS" in m] == []
    watched.tick(2)
    assert len([m for m in received(manager) if "STATUS" in m]) == 1  # at least every 5 s
    watchdog.stopping("mission ABORTED: stopped: SIGTERM")
    assert received(manager) == [{"STOPPING": "1", "STATUS": "mission ABORTED: stopped: SIGTERM"}]
