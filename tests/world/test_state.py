"""The blackboard's values as recordings show them."""

from __future__ import annotations

from executive.world.state import SampleRead, SampleRecord


def test_a_sample_record_is_shown_by_the_name_the_recordings_have_used_since_0_1() -> None:
    """``/mission/samples`` is recorded as its repr (snapshot and MCAP files): renamed SampleRecord in 0.2, it still reads ``Sample(...)``."""
    record = SampleRecord(1, -35.29, 149.11, (SampleRead("ph", 8.1, "pH", 12.0),), 10.0, 12.0, "simulated", ("temperature",), True)
    assert repr((record,)) == (
        "(Sample(leg_index=1, lat=-35.29, lon=149.11, reads=(SampleRead(sensor='ph', value=8.1, unit='pH', time=12.0),), started=10.0, "
        "finished=12.0, instrument='simulated', missing=('temperature',), partial=True),)"
    )
