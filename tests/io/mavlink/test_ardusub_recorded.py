"""What real ArduSub said under a leg deeper than the water (issue 44), recorded, read by the executive.

The recording (tests/data/ardusub/, see its README) is the last leg of missions/auv_survey.yaml with
``depth_m: 80`` over the SITL's seabed (~50 m: its sonar read 49.5 m at the surface), driven by the
executive against ArduSub 4.7-dev SITL: the leg was held at the seabed floor, 2 m
(``limits.altitude_m.min``) above the seabed by the sonar. Times are seconds from the first record.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from tlog_replay import DATA, Replay, records

from executive.world.dialect import EXECUTIVE_COMPONENT
from executive.world.seabed import depth_floor
from executive.world.state import GlobalPosition, Rangefinder

LAST_LEG = DATA / "ardusub" / "auv_too_deep_last_leg.tlog"
CLEARANCE_M = 2.0  # the mission's limits.altitude_m.min


def readings(path: Path) -> Replay:
    return Replay(vehicle="sub", watch=("/vehicle/rangefinder", "/vehicle/position", "/vehicle/altitude_above_bottom_m")).play(path)


def test_ardusub_reports_its_sonar_as_a_downward_distance_sensor_judged_by_its_own_range() -> None:
    """ArduSub's DISTANCE_SENSOR (GCS_Common.cpp send_distance_sensor): PITCH_270, RNGFND1_MIN/MAX 0.2/30 m, signal quality 0
    (unknown) even beyond its maximum: the distance alone says it is out of range."""
    replay = readings(LAST_LEG)
    sonar: list[Rangefinder] = [r for r in replay.values("/vehicle/rangefinder") if r is not None]  # type: ignore[misc]
    assert {(r.min_m, r.max_m) for r in sonar} == {(0.2, 30.0)}
    assert {r.status for r in sonar} == {"good", "too_far"}  # too far while higher than 30 m above the seabed
    assert min(r.distance_m for r in sonar) == pytest.approx(2.09, abs=0.01)  # held 2 m above the seabed, as the sonar reads it


def test_the_seabed_by_depth_and_sonar_is_where_ardusub_sitl_puts_it() -> None:
    replay = readings(LAST_LEG)
    seabed: list[float] = []
    position: GlobalPosition | None = None
    for _, key, value in replay.seen:
        if key == "/vehicle/position":
            position = value  # type: ignore[assignment]
        elif key == "/vehicle/rangefinder" and position is not None and isinstance(value, Rangefinder) and value.good:
            seabed.append(-position.alt_rel_m + value.distance_m)
    assert min(seabed) > 50.0 and max(seabed) < 51.6  # the depth sensor and the sonar agree on the seabed to 1.5 m


def test_every_depth_target_the_executive_sent_was_no_deeper_than_the_seabed_floor_it_had_read() -> None:
    """The leg's 80 m was never sent: each target within the floor of the last depth and sonar reading before it."""
    replay = readings(LAST_LEG)
    sent = [
        (t, -msg.alt)
        for t, msg in records(LAST_LEG)
        if msg.get_type() == "SET_POSITION_TARGET_GLOBAL_INT" and msg.get_srcComponent() == EXECUTIVE_COMPONENT
    ]
    t0 = next(t for t, _ in records(LAST_LEG))
    assert len(sent) > 100 and max(depth for _, depth in sent) == pytest.approx(49.1, abs=0.01)
    for t, depth in sent:
        before = [(when, key, value) for when, key, value in replay.seen if when <= t - t0]
        position = next((v for _, k, v in reversed(before) if k == "/vehicle/position"), None)
        reading = next((v for _, k, v in reversed(before) if k == "/vehicle/rangefinder"), None)
        if position is None or reading is None:
            continue  # sent before the recording's first reading
        assert isinstance(position, GlobalPosition) and isinstance(reading, Rangefinder)
        floor = depth_floor(-position.alt_rel_m, reading, CLEARANCE_M, reading.time)
        assert floor is not None and depth <= floor.depth_m + 0.3, f"{depth:.2f} m sent at {t - t0:.1f} s: floor {floor}"
