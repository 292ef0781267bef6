"""The simulated PX4's modes: their numbers, the names it reports them by, and which it cannot run or go back to."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from executive.io.mavlink.modes import PX4_MODES

#: PX4 mode name -> custom_mode, as the executive's mode table numbers them.
PX4_MODE_NUMBERS: Mapping[str, int] = MappingProxyType(dict(PX4_MODES))
#: Names PX4 reports modes by in STATUSTEXT (mode_util::nav_state_names).
NAV_STATE_NAMES: Mapping[str, str] = MappingProxyType({
    "MANUAL": "Manual", "ALTCTL": "Altitude", "POSCTL": "Position", "AUTO.MISSION": "Mission", "AUTO.LOITER": "Hold",
    "AUTO.RTL": "Return", "OFFBOARD": "Offboard", "STABILIZED": "Stabilized", "AUTO.TAKEOFF": "Takeoff", "AUTO.LAND": "Land",
    "AUTO.FOLLOW_TARGET": "Follow Target", "AUTO.PRECLAND": "Precision Land", "ACRO": "Acro", "AUTO.READY": "Ready",
    "RATTITUDE": "Rattitude",
})  # fmt: skip
#: Modes that need the pilot's sticks (mode requirement "manual control"): never available without RC.
PILOT_MODES = frozenset({"MANUAL", "ALTCTL", "POSCTL", "STABILIZED", "ACRO", "RATTITUDE"})
#: Modes with mode_req_prevent_arming (ModeUtil/mode_requirements.cpp): never the mode PX4 goes back to once disarmed.
PREVENT_ARMING_MODES = frozenset({"AUTO.RTL", "AUTO.LAND", "AUTO.PRECLAND", "AUTO.FOLLOW_TARGET"})
NOT_SIMULATED = frozenset({"AUTO.READY", "AUTO.FOLLOW_TARGET", "AUTO.PRECLAND"})
