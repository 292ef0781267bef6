"""The simulated vehicle on a real MAVLink link (UDP or TCP), served from a background thread."""

from __future__ import annotations

import logging
import threading
from types import TracebackType
from typing import TYPE_CHECKING

from executive.sim.clients import Clients
from executive.sim.firmware import DEFAULT_HOME, FirmwareSim, Home
from executive.sim.registry import make_autopilot
from executive.world.clock import Clock, ScaledClock
from executive.world.dialect import AUTOPILOT_COMPONENT

if TYPE_CHECKING:
    import can

    from executive.sim.agilex_base import SimulatedBase
    from executive.sim.faults import FaultInjector

log = logging.getLogger(__name__)


class SimServer:
    """A simulated vehicle (ArduPilot, or PX4 with ``autopilot="px4"``) listening on ``url`` (``udpin:HOST:PORT`` or ``tcpin:HOST:PORT``).

    Port 0 lets the OS choose: :attr:`port` and :attr:`url_for_client` tell where it landed. As on
    a real vehicle behind a ``udpin`` endpoint, nothing is sent until a peer has sent something.
    Several clients are served at once (:class:`~executive.sim.clients.Clients`). The autopilot runs in ``clock`` time; the
    loop sleeps ``period_s`` of wall time between iterations whatever the speed-up. Hold
    :attr:`lock` to touch :attr:`autopilot` from another thread. ``faults`` (on the same clock)
    are injected from the moment the server is created, the simulated vehicle's boot. Other
    keyword arguments go to the simulated firmware (``q_guided_mode=1`` for the vtol's ArduPlane).
    ``ekf_ready_after_s`` None keeps the firmware's own default (ArduPilot 40 s, PX4 3 s).
    With ``can_bus`` (bunker only; the caller shuts it down), :attr:`base` is the AgileX base's
    controller on that bus, serviced each iteration: then the tracks obey its motion commands.
    """

    MAX_DRAIN = 200  # messages handled per iteration: a flood cannot starve the telemetry

    def __init__(
        self,
        vehicle_kind: str,
        url: str = "udpin:127.0.0.1:0",
        clock: Clock | None = None,
        home: Home = DEFAULT_HOME,
        system_id: int = 1,
        ekf_ready_after_s: float | None = None,
        period_s: float = 0.005,
        faults: FaultInjector | None = None,
        signing_key: bytes | None = None,
        can_bus: can.BusABC | None = None,
        autopilot: str = "ardupilot",
        **firmware_options: float,
    ) -> None:
        self.clock = clock if clock is not None else faults.clock if faults is not None else ScaledClock()
        if ekf_ready_after_s is not None:
            firmware_options["ekf_ready_after_s"] = ekf_ready_after_s
        self.autopilot: FirmwareSim = make_autopilot(vehicle_kind, self.clock, home, autopilot=autopilot, system_id=system_id, **firmware_options)
        self.faults = faults
        if faults is not None:
            faults.attach(self.autopilot)
        self.base: SimulatedBase | None = None
        if can_bus is not None:
            from executive.sim.agilex_base import SimulatedBase  # python-can only when a bus is simulated

            self.base = SimulatedBase(can_bus, self.clock, self.autopilot, faults=faults)
        self.url = url
        self.period_s = period_s
        self.lock = threading.Lock()
        self._conn = Clients(url, system_id, AUTOPILOT_COMPONENT, signing_key)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def port(self) -> int:
        """The local port the link listens on."""
        return self._conn.address[1]

    @property
    def url_for_client(self) -> str:
        """What a client (the executive, a ground station) connects to: ``udpout:`` or ``tcp:``."""
        host, port = self._conn.address
        host = "127.0.0.1" if host in ("0.0.0.0", "") else host
        scheme = "tcp" if self._conn.tcp else "udpout"
        return f"{scheme}:{host}:{port}"

    def start(self) -> SimServer:
        """Start serving in a daemon thread; returns self."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=f"sim-{self.autopilot.profile.kind}", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close the link (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        self._conn.close()

    def __enter__(self) -> SimServer:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.stop()

    def step(self) -> None:
        """One iteration: drain the link, handle what came in, move the world, send what is due."""
        out = []
        with self.lock:
            if self.faults is not None:
                self.faults.update(self.autopilot)
            receiving = self.faults is None or self.faults.receiving
            for _ in range(self.MAX_DRAIN):
                msg = self._conn.recv_msg()
                if msg is None:
                    break
                if msg.get_type() != "BAD_DATA" and receiving:  # during an uplink loss what arrives is lost
                    out += self.autopilot.handle(msg)
            out += self.autopilot.update()
            if self.base is not None:
                self.base.service()
            if self.faults is not None:
                out = self.faults.transform(out)
        for msg in out:
            self._conn.mav.send(msg)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.step()
            except Exception:  # garbage on the link or a dead peer must not kill the vehicle
                log.exception("simulated vehicle: error in the serving loop")
            self._stop.wait(self.period_s)
