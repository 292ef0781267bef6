"""Link health: packets received and lost (MAVLink sequence gaps), and autopilot reboots."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class LinkHealth:
    """Counts what arrives from one component and notices when it reboots.

    A gap in the 8-bit sequence counts as lost packets; a 'gap' of half the range or more is a
    late (reordered) or duplicated packet and is not counted. A reboot shows as the autopilot's
    boot clock running backwards.
    """

    received: int = 0
    lost: int = 0
    reboots: int = 0
    _last_seq: int | None = None
    _last_boot_ms: int | None = None

    def on_packet(self, seq: int) -> None:
        if self._last_seq is not None:
            gap = (seq - self._last_seq - 1) & 0xFF
            if gap >= 128:  # older than the last one: reordered or duplicated, not lost
                self.received += 1
                self.lost = max(0, self.lost - 1)
                return
            self.lost += gap
        self._last_seq = seq
        self.received += 1

    def on_boot_time(self, time_boot_ms: int) -> bool:
        """Feed ``time_boot_ms`` from any message carrying it; True when it shows a reboot."""
        rebooted = self._last_boot_ms is not None and time_boot_ms + 1000 < self._last_boot_ms
        self._last_boot_ms = time_boot_ms
        if rebooted:
            self.reboots += 1
            self._last_seq = None
        return rebooted

    @property
    def last_boot_ms(self) -> int | None:
        """The autopilot's boot clock in the latest message that carried it (None before any)."""
        return self._last_boot_ms

    @property
    def loss_pct(self) -> float:
        total = self.received + self.lost
        return 100.0 * self.lost / total if total else 0.0
