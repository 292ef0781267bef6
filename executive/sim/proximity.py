"""ArduPilot's MAVLink proximity sensor (PRXn_TYPE 2) in the simulated autopilot, for OBSTACLE_DISTANCE.

As the firmware (AP_Proximity_MAV) takes the message: the sector width is ``increment_f`` if not
zero, else ``increment``, else the message is ignored; at most round(360 / width) sectors (72 at
most) are read; a distance of 0, UINT16_MAX, under ``min_distance`` or over ``max_distance`` is
ignored (so is "beyond range", max + 1); sector j lies at j x width + ``angle_offset`` clockwise
from the nose; the boundary keeps the closest reading in each of 8 faces of 45° (face 0 centred on
the nose), updated only by valid readings. With no message for 0.5 s the sensor reports no data.
"""

from __future__ import annotations

from executive.world.dialect import MAVLinkMessage

FACES = 8
FACE_WIDTH_DEG = 360.0 / FACES
TIMEOUT_S = 0.5
_MAX_SECTORS = 72
_UNKNOWN = 65535


def face_of(angle_deg: float) -> int:
    """The boundary face an angle (degrees clockwise from the nose) falls in."""
    return int(((angle_deg + FACE_WIDTH_DEG / 2.0) % 360.0) // FACE_WIDTH_DEG) % FACES


class Proximity:
    """The closest obstacle in each face, metres (None: nothing seen), and when the last message came."""

    def __init__(self) -> None:
        self.faces: list[float | None] = [None] * FACES
        self.last_update_s: float | None = None
        self.messages = 0

    def healthy(self, now_s: float) -> bool:
        """Data younger than the firmware's timeout."""
        return self.last_update_s is not None and now_s - self.last_update_s <= TIMEOUT_S

    def closest(self, now_s: float) -> tuple[int, float] | None:
        """(face, metres) of the nearest obstacle while healthy; None otherwise."""
        if not self.healthy(now_s):
            return None
        seen = [(d, f) for f, d in enumerate(self.faces) if d is not None]
        return (min(seen)[1], min(seen)[0]) if seen else None

    def handle(self, msg: MAVLinkMessage, now_s: float) -> None:
        width = msg.increment_f if msg.increment_f != 0.0 else float(msg.increment)
        if width == 0.0:
            return
        self.messages += 1
        self.last_update_s = now_s
        total = min(int(360.0 / abs(width) + 0.5), _MAX_SECTORS)
        closest: dict[int, float] = {}
        for j in range(total):
            cm = msg.distances[j]
            if cm == 0 or cm == _UNKNOWN or cm < msg.min_distance or cm > msg.max_distance:
                continue  # not a reading: its face is left as it was
            face = face_of(j * width + msg.angle_offset)
            closest[face] = min(closest.get(face, cm / 100.0), cm / 100.0)
        for face, metres in closest.items():
            self.faces[face] = metres
