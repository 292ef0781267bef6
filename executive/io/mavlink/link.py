"""A MAVLink link: something that receives and sends messages without blocking."""

from __future__ import annotations

import contextlib
import errno
import hashlib
import logging
import os
import struct
import time
from collections import deque
from collections.abc import Collection
from pathlib import Path
from typing import Any, Protocol

from executive.io.mavlink.endpoint import Unreachable, is_serial, unreachable
from executive.io.mavlink.skim import Skimmer
from executive.io.storage import AppendFile, Storage
from executive.world.clock import Clock, ScaledClock
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, mavutil

log = logging.getLogger(__name__)

#: While a serial device is gone (its cable knocked out, the autopilot rebooting), how often it is opened again (clock seconds).
REOPEN_EVERY_S = 1.0


class Link(Protocol):
    """What the reader and the commander need from a link (a fake one in tick tests)."""

    def recv(self) -> MAVLinkMessage | None:
        """The next message received, or ``None`` at once when there is none."""
        ...

    def send(self, msg: MAVLinkMessage) -> None:
        """Send an encoded message (it gets this link's sequence number and ids)."""
        ...

    def close(self) -> None: ...


class MemoryLink:
    """A Link in memory: messages queued in ``incoming`` are received, sent ones collected in ``sent`` (tests, benchmarks, tools)."""

    def __init__(self) -> None:
        self.incoming: deque[MAVLinkMessage] = deque()
        self.sent: list[MAVLinkMessage] = []

    def recv(self) -> MAVLinkMessage | None:
        return self.incoming.popleft() if self.incoming else None

    def send(self, msg: MAVLinkMessage) -> None:
        self.sent.append(msg)

    def close(self) -> None:
        pass


def load_signing_key(path: str | os.PathLike[str]) -> bytes:
    """A MAVLink 2 signing key from a file: 32 raw bytes, 64 hex digits, or a passphrase (SHA-256, as MAVProxy)."""
    data = Path(path).read_bytes()
    if len(data) == 32:
        return data
    text = data.decode("utf-8", "replace").strip()
    if len(text) == 64:
        try:
            return bytes.fromhex(text)
        except ValueError:
            pass
    if not text:
        raise ValueError(f"{path}: empty signing key file")
    return hashlib.sha256(text.encode()).digest()


class TlogWriter:
    """Records messages in the .tlog format: an 8-byte big-endian µs wall-clock timestamp, then the raw packet.

    Each record is written whole or not at all (a full disk loses packets, said once, never the file's end).
    """

    def __init__(self, path: str | os.PathLike[str], storage: Storage | None = None) -> None:
        self._file = AppendFile(path, "tlog", "the MAVLink link is not recorded", storage)

    def write(self, msg: MAVLinkMessage) -> None:
        self._file.write(struct.pack(">Q", int(time.time() * 1e6)) + bytes(msg.get_msgbuf()))

    def close(self) -> None:
        self._file.close()


class PymavlinkLink:
    """A link over serial, UDP or TCP, from a pymavlink connection string.

    ``udpout:127.0.0.1:14550``, ``udpin:0.0.0.0:14550``, ``tcp:127.0.0.1:5760``, ``/dev/ttyACM0``...
    A serial device may carry its baud rate after a comma: ``/dev/ttyAMA0,921600``. With a signing
    key everything sent is signed and unsigned (or badly signed) packets are dropped and counted.
    One that cannot be opened raises :class:`~executive.io.mavlink.endpoint.Unreachable` (check
    the string first with :func:`~executive.io.mavlink.endpoint.check_endpoint`).
    """

    def __init__(
        self,
        url: str,
        system_id: int = 1,
        component_id: int = EXECUTIVE_COMPONENT,
        *,
        signing_key: bytes | None = None,
        tlog: str | os.PathLike[str] | None = None,
        clock: Clock | None = None,
        storage: Storage | None = None,
    ) -> None:
        device, _, baud = url.partition(",")
        self.url = url
        try:
            self._conn = mavutil.mavlink_connection(
                device,
                baud=int(baud) if baud else 115200,
                source_system=system_id,
                source_component=component_id,
                dialect="ardupilotmega",
                autoreconnect=True,
                retries=0,  # one attempt: pymavlink's retries sleep 1 s each (printing "sleeping"), in the tick loop on a reconnect
            )
        except OSError as exc:  # nothing listening, no such device, the port taken (serial.SerialException is an OSError)
            raise unreachable(url, exc) from exc
        #: The serial device (None: a network link), its baud rate, and why it is gone while it is (None: it is there).
        self.device = device if is_serial(url) else None
        self._baud = int(baud) if baud else 115200
        self.device_lost: str | None = None
        self._clock: Clock = clock or ScaledClock()
        self._lost_at = self._next_open = 0.0
        self._tries = 0
        if self.device is not None:
            try:
                self._claim(self._conn.port)
            except Unreachable:
                self._conn.close()
                raise
        if signing_key is not None:
            if len(signing_key) != 32:
                raise ValueError("a MAVLink signing key is 32 bytes")
            self._conn.setup_signing(signing_key, sign_outgoing=True, allow_unsigned_callback=lambda _mav, _msg_id: False)
        self._tlog = TlogWriter(tlog, storage) if tlog else None
        self._post_message = self._conn.post_message
        self._conn.post_message = self._post  # type: ignore[method-assign]

    def _post(self, msg: MAVLinkMessage) -> None:
        """pymavlink's per-message bookkeeping, kept where the executive relies on it.

        ``mavfile.post_message`` keeps a cache of the latest message of each type per system, loss
        counters and timestamps for every message received: a fifth of the cost of receiving one,
        and the executive uses none of it (the reader keeps its own). It runs for heartbeats (the
        connection locks onto the vehicle's system id) and signed packets (the signing link id
        follows the vehicle's), which is what sending depends on.
        """
        if msg.get_signed() or msg.get_type() == "HEARTBEAT":
            self._post_message(msg)

    def skim(self, read: Collection[str]) -> None:
        """Decode in full only the messages of these kinds; the others come out as :class:`~executive.io.mavlink.skim.UnreadMessage`."""
        mav = self._conn.mav
        mav.decode = Skimmer(mav, read)  # type: ignore[method-assign]

    @property
    def unsigned_dropped(self) -> int:
        """Packets dropped for lacking a valid signature."""
        signing = self._conn.mav.signing
        return signing.reject_count if signing.secret_key is not None else 0

    @property
    def signature_failures(self) -> tuple[int, int, int]:
        """While signing is on: packets dropped unsigned, dropped signed with another key, and accepted well signed."""
        signing = self._conn.mav.signing
        if signing.secret_key is None:
            return 0, 0, 0
        return signing.reject_count - signing.badsig_count, signing.badsig_count, signing.goodsig_count

    def recv(self) -> MAVLinkMessage | None:
        if self.device_lost is not None and not self._reopen():
            return None
        try:
            msg = self._conn.recv_msg()
        except OSError as exc:  # serial.SerialException: the device went away (pymavlink raises it from its read)
            if self.device is None:
                raise
            self._lose(exc)
            return None
        if msg is not None and self._tlog is not None and msg.get_type() != "BAD_DATA":
            self._tlog.write(msg)
        return msg

    def send(self, msg: MAVLinkMessage) -> None:
        if self.device_lost is not None:
            return  # nobody to send it to; pymavlink's own write would try to reopen the device at every message
        self._conn.mav.send(msg)
        if self._tlog is not None:
            self._tlog.write(msg)

    def close(self) -> None:
        self._conn.close()
        if self._tlog is not None:
            self._tlog.close()

    # -- a serial device that comes and goes -----------------------------------------------------
    def _claim(self, port: Any) -> None:
        """Hold the device alone (an advisory lock, as pyserial's ``exclusive``): one another process holds is refused, Unreachable."""
        import fcntl

        try:
            fcntl.flock(port.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise Unreachable(
                    f"{self.url}: the serial device {self.device} is taken by another process (MAVProxy, ModemManager, another executive?)"
                ) from exc
            raise unreachable(self.url, exc) from exc

    def _lose(self, error: OSError) -> None:
        """The device went away: its port closed, opened again every REOPEN_EVERY_S by :meth:`recv` (the tick loop never waits on it)."""
        self._lost_at = self._clock.now()
        self._next_open = self._lost_at + REOPEN_EVERY_S
        self._tries = 0
        self.device_lost = f"serial device {self.device} gone ({error}): opening it again every {REOPEN_EVERY_S:g} s"
        log.warning("%s", self.device_lost)
        with contextlib.suppress(OSError):
            self._conn.port.close()

    def _reopen(self) -> bool:
        """Once due, try opening the lost device again (its name: a ``/dev/serial/by-id/`` name finds it whatever it is called now)."""
        now = self._clock.now()
        if now < self._next_open:
            return False
        self._next_open = now + REOPEN_EVERY_S
        self._tries += 1
        import serial

        try:
            port = serial.Serial(self.device, self._baud, timeout=0, dsrdtr=False, rtscts=False, xonxoff=False)
        except (OSError, ValueError):  # not there yet (serial.SerialException), or not a serial device yet
            self.device_lost = f"serial device {self.device} gone: opening it again every {REOPEN_EVERY_S:g} s ({self._tries} tries)"
            return False
        try:
            self._claim(port)
        except Unreachable as exc:
            port.close()
            self.device_lost = f"{exc}: opening it again every {REOPEN_EVERY_S:g} s ({self._tries} tries)"
            return False
        conn = self._conn
        conn.port, conn.fd, conn.portdead = port, port.fileno(), False  # as pymavlink's own reset(), without its print
        log.warning("serial device %s open again after %.1f s (%d tries)", self.device, now - self._lost_at, self._tries)
        self.device_lost = None
        return True
