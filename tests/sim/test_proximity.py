"""The simulated autopilot's MAVLink proximity sensor takes OBSTACLE_DISTANCE as ArduPilot's AP_Proximity_MAV does."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import pytest

from executive.sim.proximity import TIMEOUT_S, face_of
from executive.world.dialect import mavlink as m

if TYPE_CHECKING:
    from sim_support import Gcs

MakeGcs = Callable[..., "Gcs"]


def obstacles(gcs: Gcs, distances: Sequence[int], *, increment: int = 0, increment_f: float = 0.0, offset: float = 0.0) -> None:
    padded = list(distances) + [65535] * (72 - len(distances))
    gcs.send(gcs.mav.obstacle_distance_encode(0, 0, padded, increment, 20, 1000, increment_f, offset, m.MAV_FRAME_BODY_FRD))


@pytest.mark.parametrize(("angle", "face"), [(0.0, 0), (22.4, 0), (22.5, 1), (-22.5, 0), (-22.6, 7), (180.0, 4), (359.0, 0), (-90.0, 6)])
def test_faces_are_45_degrees_centred_on_the_nose(angle, face):
    assert face_of(angle) == face


def test_the_closest_reading_of_each_face_is_kept(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("boat")
    prox = gcs.ap.proximity
    # 5° sectors from 90° left: 0-8 in face 6 (-90..-50), 9-17 in face 7, 18-26 in face 0 (-0..+40), ...
    obstacles(gcs, [900] * 18 + [450, 300, 600] + [700] * 6, increment=5, offset=-90.0)
    assert prox.faces == [3.0, 7.0, None, None, None, None, 9.0, 9.0]
    assert prox.closest(gcs.ap.elapsed_s) == (0, 3.0)


def test_readings_the_firmware_ignores_leave_their_face_alone(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("rover")
    prox = gcs.ap.proximity
    obstacles(gcs, [500], increment=10)
    assert prox.faces[0] == 5.0
    # 0 cm (touching, for MAVLink), unknown, under min_distance, beyond max_distance: none is a reading
    for cm in (0, 65535, 19, 1001):
        obstacles(gcs, [cm], increment=10)
        assert prox.faces[0] == 5.0, cm
    assert prox.messages == 5


def test_increment_f_wins_and_no_increment_means_no_message(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("rover")
    prox = gcs.ap.proximity
    obstacles(gcs, [800, 800, 800, 250], increment=30, increment_f=15.0)  # sector 3 at 45°: face 1 (at 30° wide: 90°, face 2)
    assert prox.faces[1] == 2.5 and prox.faces[2] is None
    obstacles(gcs, [100], increment=0, increment_f=0.0)
    assert prox.messages == 1 and prox.faces[0] == 8.0


def test_no_message_for_half_a_second_is_no_data(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("rover")
    prox = gcs.ap.proximity
    assert prox.closest(gcs.ap.elapsed_s) is None and not prox.healthy(gcs.ap.elapsed_s)
    obstacles(gcs, [400], increment=10)
    gcs.run(TIMEOUT_S - 0.1)
    assert prox.closest(gcs.ap.elapsed_s) == (0, 4.0)
    gcs.run(0.2)
    assert prox.closest(gcs.ap.elapsed_s) is None and not prox.healthy(gcs.ap.elapsed_s)
