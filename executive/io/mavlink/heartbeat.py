"""The executive's own HEARTBEAT, as an onboard-computer component, at 1 Hz."""

from __future__ import annotations

from executive.io.mavlink.link import Link
from executive.world.clock import Clock
from executive.world.dialect import EXECUTIVE_COMPONENT, encoder, mavlink


class Heartbeat:
    """Sends a HEARTBEAT when one is due; the autopilot and ground stations see us by it."""

    def __init__(self, link: Link, clock: Clock, *, system_id: int = 1, component_id: int = EXECUTIVE_COMPONENT, period_s: float = 1.0) -> None:
        self._link = link
        self._clock = clock
        self._encoder = encoder(system_id, component_id)
        self._period_s = period_s
        self._next = float("-inf")
        self.system_status = mavlink.MAV_STATE_ACTIVE
        #: What we say we are: an onboard computer; a ground station to PX4, whose commander counts only MAV_TYPE_GCS
        #: heartbeats as the ground link (Commander.cpp: telemetry_status.heartbeat_type_gcs, gcs_connection_lost).
        self.mav_type = mavlink.MAV_TYPE_ONBOARD_CONTROLLER

    def service(self) -> bool:
        """Send a heartbeat if one is due; returns whether it did."""
        now = self._clock.now()
        if now < self._next:
            return False
        self._next = now + self._period_s
        msg = self._encoder.heartbeat_encode(self.mav_type, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, self.system_status)
        self._link.send(msg)
        return True
