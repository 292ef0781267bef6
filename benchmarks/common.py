"""What the benchmarks share: result rows, statistics, an in-memory link, missions, and the simulator in the same loop."""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from executive.io.mavlink.link import Link, MemoryLink, PymavlinkLink
from executive.mission.model import Mission
from executive.runtime.assembly import build_runtime
from executive.sim import FirmwareSim, make_autopilot
from executive.testing.lockstep import Wire
from executive.world.clock import ManualClock
from executive.world.dialect import AUTOPILOT_COMPONENT, EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink, mavutil
from executive.world.vehicles import AutopilotName

#: Where the benchmark missions start (ArduPilot SITL's home field).
HOME = (-35.363261, 149.165230, 0.0)
M_PER_DEG_LAT = 111_319.49


@dataclass
class Row:
    """One line of the results table: a figure, its unit, the target and whether it is met (None: no target)."""

    group: str
    name: str
    value: float
    unit: str
    target: str = ""
    passed: bool | None = None
    detail: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    #: The machine's 1-minute load average when the figure was taken (before, after): a figure taken on a busy machine shows it.
    load: tuple[float, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def median(values: Sequence[float]) -> float:
    return statistics.median(values) if values else math.nan


def percentile(values: Sequence[float], pct: float) -> float:
    """The ``pct`` percentile (nearest rank) of ``values``."""
    if not values:
        return math.nan
    ordered = sorted(values)
    rank = max(1, math.ceil(pct / 100.0 * len(ordered)))
    return ordered[rank - 1]


def offset(lat: float, lon: float, north_m: float, east_m: float) -> tuple[float, float]:
    """The point ``north_m``, ``east_m`` from (lat, lon) (flat earth: fine over a few km)."""
    return lat + north_m / M_PER_DEG_LAT, lon + east_m / (M_PER_DEG_LAT * math.cos(math.radians(lat)))


def serpentine(count: int, leg_m: float, row_m: float = 100.0) -> list[tuple[float, float]]:
    """``count`` waypoints ``leg_m`` apart, back and forth in rows ``row_m`` long (a survey pattern), from home."""
    points = []
    per_row = max(1, round(row_m / leg_m))
    for i in range(count):
        row, k = divmod(i, per_row)
        along = (k + 1) * leg_m if row % 2 == 0 else row_m - k * leg_m
        points.append(offset(HOME[0], HOME[1], along, -row * 10.0))
    return points


#: Wh of the benchmark rover's pack (``energy.capacity_wh``).
BENCH_PACK_WH = 2000.0


def rover_mission(
    points: Sequence[tuple[float, float]],
    *,
    name: str = "bench",
    ekf_ready_after_s: float = 40.0,
    autopilot: AutopilotName = "ardupilot",
    **limits: float,
) -> Mission:
    """A ``waypoints`` rover mission through ``points``, on ``autopilot`` (the built-in simulator runs that firmware)."""
    return Mission.model_validate(
        {
            "version": 1,
            "autopilot": autopilot,
            "name": name,
            "vehicle": "rover",
            "tree": "waypoints",
            "auto_arm": True,
            "home": {"lat": HOME[0], "lon": HOME[1], "heading_deg": 0.0},
            "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 600.0, "recovery_timeout_s": 600.0, **limits},
            "simulator": {"ekf_ready_after_s": ekf_ready_after_s},
            # the energy rule runs (its cost is part of the tick) on a pack for the longest route here (50 km at the rover's
            # 10 Wh/km): the simulator's own 111 Wh pack would refuse it before arming
            "energy": {"capacity_wh": BENCH_PACK_WH},
            "waypoints": [{"lat": lat, "lon": lon} for lat, lon in points],
        }
    )


#: Messages a real ArduPilot streams on a companion-computer port besides those the executive asks for (SRx_* at 4-10 Hz),
#: with their rate in Hz: the reader receives them, counts them and ignores them.
FILLER_RATES: dict[str, float] = {
    "RAW_IMU": 10.0,
    "SCALED_IMU2": 10.0,
    "SCALED_IMU3": 10.0,
    "SCALED_PRESSURE": 10.0,
    "ESC_TELEMETRY_1_TO_4": 10.0,
    "AHRS": 4.0,
    "AHRS2": 4.0,
    "POWER_STATUS": 4.0,
    "MEMINFO": 4.0,
    "VIBRATION": 4.0,
    "BATTERY_STATUS": 4.0,
    "SIMSTATE": 4.0,
    "RC_CHANNELS_RAW": 4.0,
    "SYSTEM_TIME": 2.0,
    "TIMESYNC": 1.0,
}


def _filler(mav: mavlink.MAVLink, name: str, boot_ms: int, t_us: int) -> MAVLinkMessage:
    """One ArduPilot message of a kind the executive does not read, with plausible values."""
    if name == "RAW_IMU":
        return mav.raw_imu_encode(t_us, 3, -2, -1000, 1, 0, -1, 200, 50, -400, 0, 3500)
    if name == "SCALED_IMU2":
        return mav.scaled_imu2_encode(boot_ms, 3, -2, -1000, 1, 0, -1, 200, 50, -400, 3500)
    if name == "SCALED_IMU3":
        return mav.scaled_imu3_encode(boot_ms, 2, -3, -998, 0, 1, 0, 210, 40, -410, 3400)
    if name == "ESC_TELEMETRY_1_TO_4":
        return mav.esc_telemetry_1_to_4_encode(
            [30, 30, 0, 0], [1200, 1210, 0, 0], [210, 300, 0, 0], [1500, 1480, 0, 0], [12, 12, 0, 0], [100, 100, 0, 0]
        )
    if name == "SCALED_PRESSURE":
        return mav.scaled_pressure_encode(boot_ms, 1013.2, 0.0, 2900, 0)
    if name == "AHRS":
        return mav.ahrs_encode(0.0, 0.0, 0.0, 0.0, 0.0, 0.001, 0.002)
    if name == "AHRS2":
        return mav.ahrs2_encode(0.0, 0.0, 0.1, 584.0, -353632610, 1491652300)
    if name == "POWER_STATUS":
        return mav.power_status_encode(5000, 0, 0)
    if name == "MEMINFO":
        return mav.meminfo_encode(4000, 65535, 131072)
    if name == "VIBRATION":
        return mav.vibration_encode(t_us, 0.01, 0.01, 0.01, 0, 0, 0)
    if name == "BATTERY_STATUS":
        return mav.battery_status_encode(0, 0, 0, 2500, [12600] + [65535] * 9, 150, 1200, -1, 88)
    if name == "SYSTEM_TIME":
        return mav.system_time_encode(1_700_000_000_000_000 + t_us, boot_ms)
    if name == "TIMESYNC":
        return mav.timesync_encode(0, t_us * 1000)
    if name == "SIMSTATE":
        return mav.simstate_encode(0.0, 0.0, 0.1, 0.0, 0.0, -9.8, 0.0, 0.0, 0.0, -353632610, 1491652300)
    if name == "RC_CHANNELS_RAW":
        return mav.rc_channels_raw_encode(boot_ms, 0, 1500, 1500, 1000, 1500, 1000, 1000, 1500, 1500, 255)
    raise ValueError(name)


class MemoryPort(mavutil.mavudp):
    """pymavlink's UDP connection (its ``recv_msg``, parser and bookkeeping) on datagrams in memory instead of a socket."""

    def __init__(self) -> None:
        mavutil.mavfile.__init__(self, None, "memory", source_system=1, source_component=EXECUTIVE_COMPONENT)
        self.incoming: deque[bytes] = deque()
        self.written: list[bytes] = []

    def recv(self, n: int | None = None) -> bytes:
        return self.incoming.popleft() if self.incoming else b""

    def write(self, buf: bytes) -> None:
        self.written.append(bytes(buf))

    def close(self) -> None:
        pass

    def link(self) -> PymavlinkLink:
        """The executive's :class:`PymavlinkLink`, built as usual but on this port."""
        connect = mavutil.mavlink_connection
        mavutil.mavlink_connection = lambda *args, **kwargs: self
        try:
            return PymavlinkLink("memory")
        finally:
            mavutil.mavlink_connection = connect


class SimLoop:
    """The runtime and the built-in simulated rover (on the mission's autopilot) in one loop on a manual clock, joined by in-memory links.

    Each :meth:`step` moves the vehicle one tick period, packs what it sends (its telemetry and a
    companion port's other streams, :data:`FILLER_RATES`) into bytes as on the wire, parses them
    back and queues them on the runtime's :class:`MemoryLink` (the lock-step simulation's
    :class:`~executive.testing.Wire`); what the runtime sent at its last tick reaches the vehicle
    first. Unlike :class:`~executive.testing.Lockstep` the caller ticks the runtime: nothing here
    is inside a timed region, callers time ``runtime.tick``.
    """

    def __init__(
        self, mission: Mission, *, rate_hz: float = 10.0, filler: bool = True, ekf_ready_after_s: float = 2.0, byte_link: bool = False,
        plugs_for: Callable[[ManualClock], list[Any]] | None = None,
    ) -> None:  # fmt: skip
        """``byte_link``: the runtime reads bytes through pymavlink (:class:`MemoryPort` under its :class:`PymavlinkLink`), as
        from a real port; ``plugs_for(clock)``: the runtime's plugs (recorders)."""
        self.clock = ManualClock(0.0)
        self.port: MemoryPort | None = MemoryPort() if byte_link else None
        self.link: Link = MemoryLink() if self.port is None else self.port.link()
        self.period_s = 1.0 / rate_hz
        self.ap: FirmwareSim = make_autopilot(
            "rover", self.clock, HOME, autopilot=mission.autopilot or "ardupilot", ekf_ready_after_s=ekf_ready_after_s
        )
        self.uplink = Wire(1, EXECUTIVE_COMPONENT)
        self.downlink = Wire(1, AUTOPILOT_COMPONENT, as_bytes=True)
        self.filler = filler
        self._filler_due = dict.fromkeys(FILLER_RATES, 0.0)
        self.messages = 0
        self._wire_mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=AUTOPILOT_COMPONENT)
        self._up_parser = mavlink.MAVLink(None)
        self._up_parser.robust_parsing = True
        self.runtime = build_runtime(mission, self.link, self.clock, rate_hz=rate_hz, plugs=plugs_for(self.clock) if plugs_for else ())

    def step(self) -> int:
        """Deliver what the runtime sent, move the vehicle one period, queue what it sent back; returns how many it sent."""
        return len(self.step_bytes()) if self.port is not None else self._step_messages()

    def _step_messages(self) -> int:
        assert isinstance(self.link, MemoryLink)
        sent, self.link.sent = self.link.sent, []
        out: list[MAVLinkMessage] = []
        for msg in self.uplink.carry(sent):
            out += self.ap.handle(msg)
        out += self._vehicle_step()
        received = self.downlink.carry(out)
        self.link.incoming.extend(received)
        self.messages += len(received)
        return len(received)

    def _vehicle_step(self) -> list[MAVLinkMessage]:
        self.clock.advance(self.period_s)
        out = self.ap.update()
        if self.filler:
            out += self._filler_messages()
        return out

    def step_bytes(self) -> list[bytes]:
        """:meth:`step` over the byte link: returns the datagrams queued for the runtime (one message each, as the simulator sends)."""
        assert self.port is not None
        written, self.port.written = self.port.written, []
        out: list[MAVLinkMessage] = []
        for data in written:
            for msg in self._up_parser.parse_buffer(data) or []:
                out += self.ap.handle(msg)
        out += self._vehicle_step()
        datagrams = []
        for msg in out:
            msg.pack(self._wire_mav)
            datagrams.append(bytes(msg.get_msgbuf()))
        self.port.incoming.extend(datagrams)
        self.messages += len(datagrams)
        return datagrams

    def _filler_messages(self) -> list[MAVLinkMessage]:
        now = self.clock.now()
        boot_ms = int(self.ap.elapsed_s * 1000)
        out = []
        for name, due in self._filler_due.items():
            if now + 1e-9 >= due:
                out.append(_filler(self.ap._mav, name, boot_ms, boot_ms * 1000))
                self._filler_due[name] = max(due + 1.0 / FILLER_RATES[name], now)
        return out

    def connect(self, limit_s: float = 10.0) -> None:
        """Run the vehicle until the runtime has found the autopilot."""
        rt = self.runtime
        while rt.link.reader.autopilot is None:
            if self.clock.now() > limit_s:
                raise RuntimeError("the simulated autopilot was not found")
            rt.link.heartbeat.service()
            self.step()
            rt.link.reader.drain()

    def run_until(self, done: Callable[[], bool], limit_s: float, tick: Callable[[], object] | None = None) -> None:
        """Step and tick until ``done()`` (RuntimeError after ``limit_s`` of clock time)."""
        tick = tick or self.runtime.tick
        deadline = self.clock.now() + limit_s
        while not done():
            if self.clock.now() > deadline:
                raise RuntimeError(f"not done within {limit_s:g} s of vehicle time")
            self.step()
            tick()
