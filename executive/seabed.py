"""A sub's height above the seabed kept as a depth: what ArduSub accepts from a companion computer.

ArduSub drops a GUIDED target in the terrain frame when it cannot convert it (no terrain data under
water: ArduSub/GCS_MAVLink_Sub.cpp, SET_POSITION_TARGET_GLOBAL_INT, Location::get_vector_from_origin_NEU_cm
fails and the handler breaks, silently), and SURFTRAK keeps only the height it had when a good reading
came (ArduSub/mode_surftrak.cpp: its target is set from the first reading, or by the pilot's throttle
or a script, never from MAVLink) and does not move horizontally. So an altitude leg is flown with
depth targets (the relative-altitude frame, which GUIDED and ALT_HOLD take), computed from the
measured depth and the downward rangefinder, and re-sent as the seabed changes.
"""

from __future__ import annotations

from executive.state import Rangefinder

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
