"""The reader's altitude above the bottom: a downward DISTANCE_SENSOR (or, from an autopilot that sends none, RANGEFINDER); nothing else,
one source of truth, and no stale truth."""

from __future__ import annotations

import py_trees
import pytest

from executive.io.mavlink.reader import MavlinkReader
from executive.testing import AUTOPILOT, Peer
from executive.world.dialect import mavlink

DOWN, FORWARD = mavlink.MAV_SENSOR_ROTATION_PITCH_270, mavlink.MAV_SENSOR_ROTATION_NONE
KEY = "/vehicle/altitude_above_bottom_m"


def altitude():
    return py_trees.blackboard.Blackboard.get(KEY)


def heartbeat(source=AUTOPILOT):
    return source.heartbeat(mavlink.MAV_TYPE_SUBMARINE, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, mavlink.MAV_STATE_STANDBY)


def distance_sensor(current_cm: int, orientation: int = DOWN, quality: int = 100, min_cm: int = 50, max_cm: int = 5000, source=AUTOPILOT):
    return source.distance_sensor(
        0, min_cm, max_cm, current_cm, mavlink.MAV_DISTANCE_SENSOR_ULTRASOUND, 0, orientation, 0, 0.0, 0.0, [0.0] * 4, quality
    )


@pytest.fixture
def reader(link, clock, commander) -> MavlinkReader:
    reader = MavlinkReader(link, clock, commander)
    link.incoming.append(heartbeat())
    reader.drain()
    return reader


def receive(reader, link, *messages) -> None:
    link.incoming.extend(messages)
    reader.drain()


@pytest.mark.parametrize(
    ("message", "expected"),
    [
        (distance_sensor(1234), 12.34),
        (distance_sensor(1234, quality=0), 12.34),  # 0 = quality unknown: the reading stands
        (distance_sensor(50), 0.5),  # at the ends of its range
        (distance_sensor(5000), 50.0),
        (distance_sensor(1234, quality=1), None),  # 1 = invalid
        (distance_sensor(5001), None),  # beyond its range: says nothing
        (distance_sensor(49), None),
        (AUTOPILOT.rangefinder(7.5, 0.0), 7.5),
        (AUTOPILOT.rangefinder(float("nan"), 0.0), None),
        (AUTOPILOT.rangefinder(-1.0, 0.0), None),
    ],
)
def test_altitude_above_bottom(reader, link, message, expected):
    receive(reader, link, message)
    assert altitude() == (None if expected is None else pytest.approx(expected))


def test_an_invalid_reading_clears_the_last_valid_one(reader, link):
    seen = []
    for message in (distance_sensor(800), distance_sensor(800, quality=1), distance_sensor(650), distance_sensor(6500)):
        receive(reader, link, message)
        seen.append(altitude())
    assert seen == [8.0, None, 6.5, None]


def test_the_rangefinder_verdict_keeps_the_range(reader, link):
    """What the legs and the guard need to know beyond "no reading": the seabed is farther than the sensor reaches."""
    receive(reader, link, distance_sensor(4500, max_cm=3000))
    reading = py_trees.blackboard.Blackboard.get("/vehicle/rangefinder")
    assert (reading.distance_m, reading.min_m, reading.max_m, reading.status) == (45.0, 0.5, 30.0, "too_far")
    receive(reader, link, distance_sensor(20, max_cm=3000))
    assert py_trees.blackboard.Blackboard.get("/vehicle/rangefinder").status == "too_close"


def test_rangefinder_never_overrides_the_distance_sensor_verdict(reader, link):
    """Issue 14, ArduSub SITL (seabed 50 m down, RNGFND1_MAX 30 m): DISTANCE_SENSOR 45 m (beyond its 30 m: invalid) and
    RANGEFINDER 45.2 m (no range: taken as valid) arrived turn by turn; the height flipped None / 45.2 every message and
    the altitude guard held and resumed the sub 915 times in 400 s. One source of truth: the height stays unknown."""
    seen = set()
    for _ in range(20):
        receive(reader, link, distance_sensor(4500, max_cm=3000))
        seen.add(altitude())
        receive(reader, link, AUTOPILOT.rangefinder(45.2, 0.0))
        seen.add(altitude())
    assert seen == {None}


def test_rangefinder_alone_is_read_when_no_distance_sensor_comes(reader, link):
    receive(reader, link, AUTOPILOT.rangefinder(7.5, 0.0))
    assert altitude() == pytest.approx(7.5)


def test_sensors_not_looking_down_and_other_systems_are_ignored(reader, link):
    receive(reader, link, distance_sensor(900))
    receive(reader, link, distance_sensor(300, orientation=FORWARD))  # an obstacle sensor
    receive(reader, link, distance_sensor(100, source=Peer(2, 1)), Peer(2, 1).rangefinder(1.0, 0.0))
    assert altitude() == 9.0


def test_no_reading_until_a_rangefinder_reports(reader, link):
    assert altitude() is None
    receive(reader, link, distance_sensor(300, orientation=FORWARD))
    assert altitude() is None
