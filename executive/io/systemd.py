"""systemd's notify protocol (``Type=notify``, ``WatchdogSec=``): the executive tells its service manager how it is.

Under systemd a service finds a Unix datagram socket in ``$NOTIFY_SOCKET`` (a path, or ``@name``
in the abstract namespace) and sends it newline-separated ``KEY=VALUE`` lines (sd_notify(3)):
``READY=1`` once the executive has heard the autopilot (start-up is complete), ``STATUS=...`` (what
``systemctl status`` shows), ``WATCHDOG=1`` every half of ``$WATCHDOG_USEC`` and ``STOPPING=1``
when it ends. ``$WATCHDOG_PID``, when set, names the one process the watchdog is for.

The watchdog is activated when start-up is completed (systemd.service(5), ``WatchdogSec=``), and
:class:`Watchdog` is a runtime service, so it is fed from the tick loop itself: a loop stuck in a
tick sends nothing more, and systemd kills the executive (SIGABRT) and restarts it
(``Restart=on-failure``), which resumes the mission from its journal (``--resume``).
"""

from __future__ import annotations

import os
import socket
from collections.abc import Callable, Mapping

from executive.world.clock import Clock


class Notifier:
    """Sends notify messages to the service manager's socket at ``address``; never blocks, never raises."""

    def __init__(self, address: str) -> None:
        self.address = "\0" + address[1:] if address.startswith("@") else address
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM | socket.SOCK_CLOEXEC)
        self._sock.setblocking(False)
        self.dropped = 0  # messages the socket would not take

    @classmethod
    def from_environment(cls, environ: Mapping[str, str] | None = None) -> Notifier | None:
        """The notifier ``$NOTIFY_SOCKET`` names, or None when not run by systemd as ``Type=notify``."""
        address = (os.environ if environ is None else environ).get("NOTIFY_SOCKET", "")
        return cls(address) if address.startswith(("/", "@")) else None

    def notify(self, **fields: object) -> bool:
        """Send ``READY=1``-style fields (``notify(READY=1, STATUS="...")``); whether the manager got them."""
        message = "\n".join(f"{key}={value}" for key, value in fields.items()).encode()
        try:
            self._sock.sendto(message, self.address)
        except OSError:  # the manager is gone or its queue full: the next message may pass
            self.dropped += 1
            return False
        return True

    def close(self) -> None:
        self._sock.close()


def watchdog_period_s(environ: Mapping[str, str] | None = None) -> float | None:
    """Half of ``$WATCHDOG_USEC`` in seconds, if the watchdog is on for this process (sd_watchdog_enabled(3)), else None."""
    env = os.environ if environ is None else environ
    usec, pid = env.get("WATCHDOG_USEC", ""), env.get("WATCHDOG_PID", "")
    if not usec.isdigit() or int(usec) == 0 or (pid and pid != str(os.getpid())):
        return None
    return int(usec) / 2e6


class Watchdog:
    """A runtime service: ``WATCHDOG=1`` every ``period_s`` of ``clock`` (wall time), and ``STATUS=`` as the status changes.

    Serviced once per tick: when the loop stops ticking, the pings stop. ``status`` gives the
    status text and a key that changes when it matters (state, leg, mode, armed): on a change it is
    sent at once, else every ``status_period_s``.
    """

    def __init__(
        self,
        notifier: Notifier,
        clock: Clock,
        period_s: float | None,
        status: Callable[[], tuple[object, str]] = lambda: (None, ""),
        *,
        status_period_s: float = 5.0,
    ) -> None:
        self._notifier = notifier
        self._clock = clock
        self.period_s = period_s
        #: The status key and text (set by the plug that hands this service to the runtime).
        self.status = status
        self._status_period_s = status_period_s
        self._next_ping = float("-inf")
        self._next_status = float("-inf")
        self._last_key: object = None
        self.pings = 0

    def ready(self, text: str) -> None:
        """Start-up is complete (the autopilot answers): systemd starts the watchdog from now."""
        self._notifier.notify(READY=1, STATUS=text)
        self.service()

    def service(self) -> None:
        now = self._clock.now()
        if self.period_s is not None and now >= self._next_ping:
            self._next_ping = now + self.period_s
            self._notifier.notify(WATCHDOG=1)
            self.pings += 1
        key, text = self.status()
        if text and (key != self._last_key or now >= self._next_status):
            self._last_key, self._next_status = key, now + self._status_period_s
            self._notifier.notify(STATUS=text)

    def stopping(self, text: str) -> None:
        """The executive is ending (the mission is over, or it was asked to stop)."""
        self._notifier.notify(STOPPING=1, STATUS=text)
