"""Obstacle distances from a camera, forwarded to the autopilot as MAVLink OBSTACLE_DISTANCE.

The camera (a depth camera's process on the companion computer) sends one JSON object per UDP
datagram to ``--obstacles udpin:HOST:PORT``::

    {"distances_cm": [412, 398, null, 1500, ...], "increment_deg": 1.5,
     "angle_offset_deg": -54.0, "min_cm": 20, "max_cm": 1000}

``distances_cm``: 1 to 72 sectors, clockwise from ``angle_offset_deg`` (body frame, 0 = ahead;
default: the sectors centred on the bow), each ``increment_deg`` wide; ``null`` = unknown, a
distance over ``max_cm`` = no obstacle. Only ``distances_cm`` and ``increment_deg`` are required
(``min_cm`` 20 and ``max_cm`` 1000 by default). A datagram that is not such an object is dropped
whole, counted and logged with the field and the reason; nothing of it reaches the autopilot.

:class:`ObstacleReceiver` (a reader) puts the latest scan on the blackboard; :class:`ObstacleForwarder`
(a writer) sends each new scan once, at most once a tick. A scan older than :data:`STALE_S` is not
sent: ArduPilot's proximity backend reports no data 0.5 s after the last message, which is the
truth when the camera has stopped (repeating its last scan would not be).
ArduPilot ignores a sector of 0 cm (MAVLink: touching) or under ``min_cm``, and an increment of 0.
"""

from __future__ import annotations

import json
import logging
import math
import socket
from dataclasses import dataclass
from typing import Any

from executive.io.mavlink.link import Link
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import mavlink

log = logging.getLogger(__name__)

SECTORS = 72  # OBSTACLE_DISTANCE carries 72 distances
UNKNOWN_CM = 65535  # UINT16_MAX: unknown / not used
STALE_S = 0.5
MAX_DATAGRAM = 8192
DEFAULT_MIN_CM, DEFAULT_MAX_CM = 20, 1000
_FIELDS = {"distances_cm", "increment_deg", "angle_offset_deg", "min_cm", "max_cm"}


class ScanError(ValueError):
    """A datagram that is not a scan; ``field`` names what is wrong with it."""

    def __init__(self, field: str, why: str) -> None:
        super().__init__(f"{field}: {why}")
        self.field = field


class ObstacleSpecError(ValueError):
    """An ``--obstacles`` text that does not name a UDP endpoint."""


@dataclass(frozen=True)
class ObstacleScan:
    """One camera scan: distances in cm (None unknown) clockwise from ``angle_offset_deg``, received at ``time``."""

    distances_cm: tuple[int | None, ...]
    increment_deg: float
    angle_offset_deg: float
    min_cm: int
    max_cm: int
    time: float

    def closest_m(self) -> float | None:
        """The nearest obstacle within the sensor's range, metres; None when there is none."""
        seen = [d for d in self.distances_cm if d is not None and self.min_cm <= d <= self.max_cm]
        return min(seen) / 100.0 if seen else None


def _number(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ScanError(field, f"expected a number, got {type(value).__name__}")
    if not math.isfinite(value):
        raise ScanError(field, f"{value} is not a finite number")
    return float(value)


def _centimetres(value: Any, field: str) -> int:
    cm = _number(value, field)
    if not 0 <= cm < UNKNOWN_CM:
        raise ScanError(field, f"{value:g} cm is outside [0, {UNKNOWN_CM - 1}]")
    return round(cm)


def parse_scan(data: bytes, now: float) -> ObstacleScan:
    """The scan in one datagram; ScanError naming the field when it is not one."""
    try:
        obj = json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ScanError("datagram", f"not JSON ({exc})") from None
    except RecursionError:
        raise ScanError("datagram", "nested too deeply") from None
    if not isinstance(obj, dict):
        raise ScanError("datagram", f"expected a JSON object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - _FIELDS)
    if unknown:
        raise ScanError(unknown[0], f"unknown field (expected {', '.join(sorted(_FIELDS))})")
    for required in ("distances_cm", "increment_deg"):
        if required not in obj:
            raise ScanError(required, "missing")
    raw = obj["distances_cm"]
    if not isinstance(raw, list) or not 1 <= len(raw) <= SECTORS:
        got = f"{len(raw)} values" if isinstance(raw, list) else type(raw).__name__
        raise ScanError("distances_cm", f"expected a list of 1 to {SECTORS} distances, got {got}")
    distances = tuple(None if d is None else _centimetres(d, f"distances_cm[{i}]") for i, d in enumerate(raw))
    increment = _number(obj["increment_deg"], "increment_deg")
    if not 0.0 < increment * len(distances) <= 360.0:
        raise ScanError("increment_deg", f"{increment:g}° x {len(distances)} sectors must cover more than 0° and at most 360°")
    offset = _number(obj.get("angle_offset_deg", -increment * (len(distances) - 1) / 2.0), "angle_offset_deg")
    if not -360.0 <= offset <= 360.0:
        raise ScanError("angle_offset_deg", f"{offset:g}° is outside [-360, 360]")
    min_cm = _centimetres(obj.get("min_cm", DEFAULT_MIN_CM), "min_cm")
    max_cm = _centimetres(obj.get("max_cm", DEFAULT_MAX_CM), "max_cm")
    if not min_cm < max_cm < UNKNOWN_CM - 1:
        raise ScanError("max_cm", f"{max_cm} must be above min_cm ({min_cm}) and below {UNKNOWN_CM - 1}")
    return ObstacleScan(distances, increment, offset, min_cm, max_cm, now)


def parse_endpoint(spec: str) -> tuple[str, int]:
    """(host, port) of ``udpin:HOST:PORT`` (``udp:`` too); ObstacleSpecError otherwise."""
    scheme, _, rest = spec.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme not in ("udpin", "udp") or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ObstacleSpecError(f"{spec!r}: expected udpin:HOST:PORT, e.g. udpin:0.0.0.0:14600")
    return host, int(port)


def open_endpoint(spec: str) -> socket.socket:
    """A non-blocking UDP socket bound where ``spec`` says; ObstacleSpecError for a bad text, OSError when it cannot be bound."""
    host, port = parse_endpoint(spec)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((host, port))
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    return sock


class ObstacleReceiver:
    """Reads the camera's scans from a bound UDP socket each tick; writes /obstacles/*. Never blocks."""

    def __init__(self, sock: socket.socket, clock: Clock) -> None:
        self._clock = clock
        self._socket = sock
        self._bb = blackboard.writer("obstacle receiver", ["/obstacles/scan", "/obstacles/received", "/obstacles/rejected", "/obstacles/last_error"])
        self.received = self.rejected = 0
        self._last_warning = -math.inf

    def drain(self, max_datagrams: int = 100) -> int:
        """Take what arrived (at most ``max_datagrams``); the latest valid scan goes on the blackboard. Returns how many arrived."""
        now = self._clock.now()
        count = 0
        latest: ObstacleScan | None = None
        while count < max_datagrams:
            try:
                data = self._socket.recv(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:  # e.g. ICMP port unreachable reported on a later recv: not a datagram
                log.debug("obstacle socket: %s", exc)
                break
            count += 1
            try:
                latest = parse_scan(data, now)
                self.received += 1
            except ScanError as exc:
                self.rejected += 1
                self._bb.set("/obstacles/rejected", self.rejected)
                self._bb.set("/obstacles/last_error", str(exc))
                if now - self._last_warning >= 5.0:  # a broken camera must not flood the log
                    self._last_warning = now
                    log.warning("obstacle scan dropped (%d so far): %s", self.rejected, exc)
        if latest is not None:
            self._bb.set("/obstacles/scan", latest)
            self._bb.set("/obstacles/received", self.received)
        return count


class ObstacleForwarder:
    """Sends each new scan on /obstacles/scan to the autopilot once, as OBSTACLE_DISTANCE (body frame); stale scans are not sent."""

    def __init__(self, link: Link, clock: Clock, *, sensor_type: int = mavlink.MAV_DISTANCE_SENSOR_UNKNOWN) -> None:
        self._link = link
        self._clock = clock
        self._sensor_type = sensor_type
        self._mav = mavlink.MAVLink(None)
        self._in = blackboard.reader("obstacle forwarder in", ["/obstacles/scan"])
        self._out = blackboard.writer("obstacle forwarder", ["/obstacles/forwarded"])
        self._sent: ObstacleScan | None = None
        self.forwarded = 0

    def service(self) -> None:
        scan: ObstacleScan | None = self._in.get("/obstacles/scan")
        if scan is None or scan is self._sent or self._clock.now() - scan.time > STALE_S:
            return
        self._link.send(encode(self._mav, scan, self._sensor_type))
        self._sent = scan
        self.forwarded += 1
        self._out.set("/obstacles/forwarded", self.forwarded)


def encode(mav: mavlink.MAVLink, scan: ObstacleScan, sensor_type: int) -> mavlink.MAVLink_obstacle_distance_message:
    """OBSTACLE_DISTANCE for ``scan``: unknown and unused sectors UINT16_MAX, beyond range max + 1 (no obstacle)."""
    distances = [UNKNOWN_CM if d is None else min(d, scan.max_cm + 1) for d in scan.distances_cm]
    distances += [UNKNOWN_CM] * (SECTORS - len(distances))
    whole = scan.increment_deg.is_integer() and scan.increment_deg <= 255
    return mav.obstacle_distance_encode(
        int(scan.time * 1e6),
        sensor_type,
        distances,
        int(scan.increment_deg) if whole else 0,
        scan.min_cm,
        scan.max_cm,
        scan.increment_deg,
        scan.angle_offset_deg,
        mavlink.MAV_FRAME_BODY_FRD,
    )
