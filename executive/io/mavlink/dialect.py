"""The one place pymavlink is imported: MAVLink 2, ArduPilot dialect (it includes common)."""

from __future__ import annotations

import os

os.environ.setdefault("MAVLINK20", "1")
os.environ.setdefault("MAVLINK_DIALECT", "ardupilotmega")

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

MAVLinkMessage = mavlink.MAVLink_message

#: The executive's component id: an onboard (companion) computer, never the GCS id 255.
EXECUTIVE_COMPONENT = mavlink.MAV_COMP_ID_ONBOARD_COMPUTER
AUTOPILOT_COMPONENT = mavlink.MAV_COMP_ID_AUTOPILOT1


def encoder(system_id: int, component_id: int) -> mavlink.MAVLink:
    """A message factory (``encoder(1, 191).heartbeat_encode(...)``) that writes nowhere."""
    return mavlink.MAVLink(None, srcSystem=system_id, srcComponent=component_id)


__all__ = ["AUTOPILOT_COMPONENT", "EXECUTIVE_COMPONENT", "MAVLinkMessage", "encoder", "mavlink", "mavutil"]
