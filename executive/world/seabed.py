"""A sub's height above the seabed kept as a depth: what ArduSub accepts from a companion computer.

ArduSub drops a GUIDED target in the terrain frame when it cannot convert it (no terrain data under
water: ArduSub/GCS_MAVLink_Sub.cpp, SET_POSITION_TARGET_GLOBAL_INT, Location::get_vector_from_origin_NEU_cm
fails and the handler breaks, silently), and SURFTRAK keeps only the height it had when a good reading
came (ArduSub/mode_surftrak.cpp: its target is set from the first reading, or by the pilot's throttle
or a script, never from MAVLink) and does not move horizontally. So an altitude leg is flown with
depth targets (the relative-altitude frame, which GUIDED and ALT_HOLD take), computed from the
measured depth and the downward rangefinder, and re-sent as the seabed changes.

The seabed floor (:func:`depth_floor`): no leg, in any control mode, sends the sub closer to the
seabed than ``limits.altitude_m.min`` (the Zeno vehicle's altitude limit, [2, 100] m: seed 003) as
the sonar reads it. ArduSub itself guards the seabed only in AUTO's terrain following (its terrain
failsafe: ArduSub/failsafe.cpp failsafe_terrain_on_event, mode_auto.cpp auto_terrain_recover_start);
a GUIDED depth target is flown whatever is under it. ArduSub trusts its sonar only while its status
is Good (ArduSub/sensors.cpp read_rangefinder: ``alt_healthy``) and drops its filtered reading
after a second without one (RANGEFINDER_TIMEOUT_MS); here a reading that is invalid or older than
:data:`SONAR_STALE_S` says nothing of the seabed, so the descent stops where the sub is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from executive.world.state import Rangefinder

#: A sonar reading older than this (s) is lost: the sub goes no deeper than it is (DISTANCE_SENSOR comes at 5 Hz).
SONAR_STALE_S = 2.0

#: A seabed beyond the rangefinder's reach is approached this far short of the last depth that is sure not to overshoot.
BLIND_MARGIN_M = 1.0


def depth_for_altitude(depth_m: float, reading: Rangefinder | None, altitude_m: float) -> float | None:
    """The depth (m, down) that puts the vehicle ``altitude_m`` above the seabed; None when the reading cannot tell.

    A good reading: ``depth + reading - altitude``. Beyond its maximum the seabed is at least
    ``depth + max`` down, so ``depth + max - altitude`` (less a margin) is still above the target: a
    dive that cannot overshoot, repeated until the reading is good (whatever the seabed's depth,
    as long as ``altitude_m`` is within the sensor's range). Under its minimum the seabed is less than
    ``min`` below: ``depth + min - altitude`` rises without overshooting either. An invalid reading
    (or none) says nothing: keep what was sent last.
    """
    if reading is None:
        return None
    if reading.status == "good":
        wanted = depth_m + reading.distance_m - altitude_m
    elif reading.status == "too_far":
        wanted = depth_m + max(0.0, reading.max_m - altitude_m - BLIND_MARGIN_M)
    elif reading.status == "too_close":
        wanted = depth_m + reading.min_m - altitude_m
    else:
        return None
    return max(0.0, wanted)


@dataclass(frozen=True, slots=True)
class Floor:
    """The deepest depth (m, down) the sub may be sent to now, and why, as a person reads it.

    ``kind``: ``seabed``, the seabed measured (a good reading, or one under the sonar's minimum);
    ``beyond``, the seabed farther than the sonar reaches (the floor is only as deep as is sure);
    ``lost``, no reading to trust (the floor is where the sub is: the descent stops).
    """

    depth_m: float
    why: str
    kind: Literal["seabed", "beyond", "lost"]


def depth_floor(depth_m: float, reading: Rangefinder | None, clearance_m: float, now: float) -> Floor | None:
    """The seabed floor: how deep the sub may go keeping ``clearance_m`` above the seabed as the sonar reads it.

    A good reading puts the seabed at ``depth + reading``; beyond the sonar's maximum it is at least
    ``depth + max`` down; under its minimum, less than ``depth + min``. An invalid reading, or one
    older than :data:`SONAR_STALE_S` (the sonar lost), stops the descent: the floor is the depth the
    sub is at. None: no downward sonar was ever heard (nothing to keep the sub off the seabed but the
    mission's water depth, checked by ``validate``).
    """
    if reading is None:
        return None
    if now - reading.time > SONAR_STALE_S:
        return Floor(depth_m, f"no sonar reading for {now - reading.time:.0f} s", "lost")
    if reading.status == "good":
        seabed = depth_m + reading.distance_m
        return Floor(max(0.0, seabed - clearance_m), f"seabed at {seabed:.1f} m by the sonar ({reading.distance_m:.1f} m below)", "seabed")
    if reading.status == "too_far":
        seabed = depth_m + reading.max_m
        return Floor(max(0.0, seabed - clearance_m), f"seabed beyond the sonar's {reading.max_m:g} m: at least {seabed:.1f} m", "beyond")
    if reading.status == "too_close":
        seabed = depth_m + reading.min_m
        return Floor(max(0.0, seabed - clearance_m), f"seabed within the sonar's {reading.min_m:g} m: less than {seabed:.1f} m", "seabed")
    return Floor(depth_m, "the sonar's reading invalid", "lost")
