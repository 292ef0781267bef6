"""The blackboard's values as recordings show them."""

from __future__ import annotations

import pytest

from executive.world.state import EkfFlags, EkfStatus, SampleRead, SampleRecord


def test_a_sample_record_is_shown_by_the_name_the_recordings_have_used_since_0_1() -> None:
    """``/mission/samples`` is recorded as its repr (snapshot and MCAP files): renamed SampleRecord in 0.2, it still reads ``Sample(...)``."""
    record = SampleRecord(1, -35.29, 149.11, (SampleRead("ph", 8.1, "pH", 12.0),), 10.0, 12.0, "simulated", ("temperature",), True)
    assert repr((record,)) == (
        "(Sample(leg_index=1, lat=-35.29, lon=149.11, reads=(SampleRead(sensor='ph', value=8.1, unit='pH', time=12.0),), started=10.0, "
        "finished=12.0, instrument='simulated', missing=('temperature',), partial=True),)"
    )


@pytest.mark.parametrize(
    ("flags", "at_rest", "ok"),
    [
        (0x3AF & ~0x80, False, True),  # ArduRover flying on GPS: POS_HORIZ_REL, no CONST_POS_MODE
        (0x10, False, True),  # POS_HORIZ_ABS alone
        (0x3AF, False, False),  # ArduPilot's constant-position mode: no position (the ekf_loss failsafe's flags)
        (0x3FF, True, True),  # PX4 at rest on the ground before take-off, GNSS fused (PRED_POS_HORIZ_REL)
        (0x3FF & ~0x100, True, False),  # ... with no aiding source fused: a faked position
        (0x80, True, False),  # no horizontal position at all
        (0x8018, False, True),  # glitching GPS does not take the position away (GpsNotGlitching judges that)
    ],
)
def test_position_ok_reads_the_ekf_flags(flags: int, at_rest: bool, ok: bool) -> None:
    assert EkfStatus(EkfFlags(flags), 0.1, 0.1, 0.1, 0.1, 0.0, 0.0, const_pos_at_rest=at_rest).position_ok() is ok
