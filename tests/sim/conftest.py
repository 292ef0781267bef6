"""Fixtures for the simulated vehicle: a ground station talking to an autopilot directly, and one over a socket."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from executive.sim import make_autopilot
from executive.world.clock import ManualClock
from sim_support import EKF_READY_S, HOME, Client, Gcs


@pytest.fixture
def make_gcs() -> Callable[..., Gcs]:
    """An autopilot of a kind (EKF ready after ``EKF_READY_S``), booted, and a ground station talking to it."""

    def make(kind: str = "rover", ekf_ready: bool = False, run_s: float | None = None, **options: float) -> Gcs:
        clock = ManualClock()
        gcs = Gcs(make_autopilot(kind, clock, HOME, ekf_ready_after_s=EKF_READY_S, **options), clock)
        gcs.update()
        gcs.run(run_s if run_s is not None else EKF_READY_S + 0.5 if ekf_ready else 1.5)
        return gcs

    return make


@pytest.fixture
def client_for() -> Iterator[Callable[[str], Client]]:
    clients: list[Client] = []

    def connect(url: str) -> Client:
        clients.append(Client(url))
        return clients[-1]

    yield connect
    for client in clients:
        client.close()
