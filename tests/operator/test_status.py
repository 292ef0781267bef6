"""The status a person reads (issue 44): a sub's depth and the seabed below it, a vtol's height above home; nothing of the kind
for a vehicle on the ground or the water."""

from __future__ import annotations

import pytest

from executive.operator.status import StatusSource, status_line
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, Rangefinder


def _vehicle(mav_type: int, alt_rel_m: float, reading: Rangefinder | None = None) -> None:
    keys = ["/vehicle/mav_type", "/vehicle/position", "/vehicle/rangefinder", "/vehicle/altitude_above_bottom_m"]
    writer = blackboard.writer("test", keys)
    writer.set("/vehicle/mav_type", mav_type)
    writer.set("/vehicle/position", GlobalPosition(44.095, 9.863, alt_rel_m, 0.0, 0.0, 0.0, 0.0, 0.0))
    writer.set("/vehicle/rangefinder", reading)
    writer.set("/vehicle/altitude_above_bottom_m", reading.distance_m if reading is not None and reading.good else None)


@pytest.mark.parametrize(
    ("mav_type", "alt_rel_m", "reading", "shown", "values"),
    [
        (mavlink.MAV_TYPE_SUBMARINE, -26.0, Rangefinder(24.0, 0.2, 30.0, "good", 0.0), "depth 26.0 m, seabed 24.0 m below", (26.0, 24.0, None, None)),
        (mavlink.MAV_TYPE_SUBMARINE, -5.0, Rangefinder(45.0, 0.2, 30.0, "too_far", 0.0), "depth 5.0 m, seabed beyond 30 m", (5.0, None, 30.0, None)),
        (mavlink.MAV_TYPE_SUBMARINE, -5.0, None, "depth 5.0 m, seabed no sonar reading", (5.0, None, None, None)),
        (mavlink.MAV_TYPE_FIXED_WING, 30.04, None, "height 30.0 m", (None, None, None, 30.04)),  # ArduPlane's QuadPlane
        (mavlink.MAV_TYPE_VTOL_TILTROTOR, 118.5, None, "height 118.5 m", (None, None, None, 118.5)),
        (22, 118.5, None, "height 118.5 m", (None, None, None, 118.5)),  # PX4's standard VTOL (VTOL_FIXEDROTOR)
        (mavlink.MAV_TYPE_GROUND_ROVER, 0.3, None, None, (None, None, None, None)),
    ],
    ids=["sub-over-the-seabed", "sub-seabed-beyond-the-sonar", "sub-no-sonar", "quadplane", "vtol", "px4-standard-vtol", "rover"],
)
def test_the_status_shows_the_depth_and_seabed_of_a_sub_and_the_height_of_a_vtol(
    mav_type: int, alt_rel_m: float, reading: Rangefinder | None, shown: str | None, values: tuple[float | None, ...]
) -> None:
    _vehicle(mav_type, alt_rel_m, reading)
    status = StatusSource().snapshot()
    assert (status["depth_m"], status["altitude_above_bottom_m"], status["seabed_beyond_m"], status["height_m"]) == values
    line = status_line(status)
    if shown is None:
        assert "depth" not in line and "height" not in line
    else:
        assert f"  {shown}  " in line


def test_an_older_status_without_these_fields_still_reads() -> None:
    """``ctl status`` of an older executive, a replayed recording: the fields are simply absent."""
    status = {k: v for k, v in StatusSource().snapshot().items() if k not in ("depth_m", "altitude_above_bottom_m", "seabed_beyond_m", "height_m")}
    assert status_line(status).startswith("IDLE")
