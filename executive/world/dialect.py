"""The one place pymavlink is imported: MAVLink 2, ArduPilot dialect (it includes common)."""

from __future__ import annotations

import importlib.util
import os
import sys

os.environ.setdefault("MAVLINK20", "1")
os.environ.setdefault("MAVLINK_DIALECT", "ardupilotmega")


def _load_on_first_use(name: str) -> None:
    """Register module ``name`` to be executed when first used, not when imported (importlib's LazyLoader)."""
    if name in sys.modules:
        return
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        return
    spec.loader = importlib.util.LazyLoader(spec.loader)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    parent, _, child = name.rpartition(".")
    setattr(sys.modules[parent], child, module)  # so that `from parent import child` finds it without touching it


# mavutil imports both at start-up and the executive uses neither: mavexpression (recv_match conditions) pulls
# mavextra and numpy; dialects.v10.all (imported for pyinstaller) is a 1.6 MB module. Together ~60 ms and ~20 MB.
_load_on_first_use("pymavlink.mavexpression")
_load_on_first_use("pymavlink.dialects.v10.all")

from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

MAVLinkMessage = mavlink.MAVLink_message

#: The executive's component id: an onboard (companion) computer, never the GCS id 255.
EXECUTIVE_COMPONENT = mavlink.MAV_COMP_ID_ONBOARD_COMPUTER
AUTOPILOT_COMPONENT = mavlink.MAV_COMP_ID_AUTOPILOT1


def encoder(system_id: int, component_id: int) -> mavlink.MAVLink:
    """A message factory (``encoder(1, 191).heartbeat_encode(...)``) that writes nowhere."""
    return mavlink.MAVLink(None, srcSystem=system_id, srcComponent=component_id)


__all__ = ["AUTOPILOT_COMPONENT", "EXECUTIVE_COMPONENT", "MAVLinkMessage", "encoder", "mavlink", "mavutil"]
