"""Link health: sequence gaps are losses, late packets are not, a boot clock running backwards is a reboot."""

from __future__ import annotations

from executive.io.mavlink.link_health import LinkHealth


def feed(health: LinkHealth, seqs: list[int]) -> LinkHealth:
    for seq in seqs:
        health.on_packet(seq)
    return health


def test_no_gap_no_loss():
    h = feed(LinkHealth(), list(range(250, 256)) + list(range(0, 10)))  # across the 8-bit wrap
    assert (h.received, h.lost, h.loss_pct) == (16, 0, 0.0)


def test_gaps_are_counted_as_lost():
    h = feed(LinkHealth(), [1, 2, 5, 6, 10])
    assert (h.received, h.lost) == (5, 5)
    assert h.loss_pct == 50.0


def test_a_reordered_packet_is_not_a_loss():
    h = feed(LinkHealth(), [1, 2, 4, 3, 5])
    assert (h.received, h.lost) == (5, 0)


def test_reboot_is_the_boot_clock_running_backwards():
    h = LinkHealth()
    assert not h.on_boot_time(50_000)
    assert not h.on_boot_time(50_900)
    assert not h.on_boot_time(50_500)  # jitter between messages of different streams
    assert h.on_boot_time(1_200)
    assert h.reboots == 1
