"""Stream set-up: ask the autopilot for the messages the executive needs, at the rates it needs.

One MAV_CMD_SET_MESSAGE_INTERVAL is in flight at a time (acks of one command kind cannot be told
apart). The whole set is requested again after a reconnect or an autopilot reboot.
"""

from __future__ import annotations

import logging
from collections import deque

from executive.io.mavlink.commander import Commander
from executive.mission.declaration import vehicle_profile
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import Outcome

log = logging.getLogger(__name__)

#: message name -> rate in Hz.
DEFAULT_RATES: dict[str, float] = {
    "GLOBAL_POSITION_INT": 5.0,
    "ATTITUDE": 10.0,
    "EKF_STATUS_REPORT": 2.0,
    "SYS_STATUS": 1.0,
    "RC_CHANNELS": 5.0,
    "SERVO_OUTPUT_RAW": 5.0,
    "VFR_HUD": 2.0,
    "GPS_RAW_INT": 2.0,
    "EXTENDED_SYS_STATE": 1.0,
    "MISSION_CURRENT": 1.0,
    "HOME_POSITION": 0.2,
    # the point the autopilot steers to: a target we did not ask for is a person's (executive.autopilot.target_watch)
    "POSITION_TARGET_GLOBAL_INT": 5.0,
    "BATTERY_STATUS": 1.0,  # last: the energy rule's, asked once the guards' streams are set
}

_KEY = blackboard.command_key(Outcome.MESSAGE_RATE)


def rates_for(kind: str, autopilot: str = "ardupilot") -> dict[str, float]:
    """The streams a kind of vehicle has: only aircraft report VTOL and landed state, only subs a downward sonar.

    PX4 reports its estimator in ESTIMATOR_STATUS (it has no EKF_STATUS_REPORT) and its landed state in
    EXTENDED_SYS_STATE on every vehicle.
    """
    aircraft = vehicle_profile(kind).aircraft
    rates = {name: hz for name, hz in DEFAULT_RATES.items() if aircraft or autopilot == "px4" or name != "EXTENDED_SYS_STATE"}
    if kind == "sub":
        rates["DISTANCE_SENSOR"] = 5.0
    if autopilot == "px4":
        del rates["EKF_STATUS_REPORT"]
        rates["ESTIMATOR_STATUS"] = 2.0
    return rates


class StreamRequester:
    """Requests each stream in turn; call :meth:`restart` after a reconnect or reboot, :meth:`service` every tick."""

    def __init__(self, commander: Commander, rates: dict[str, float] | None = None) -> None:
        self._commander = commander
        self.rates = dict(DEFAULT_RATES if rates is None else rates)
        self._queue: deque[str] = deque()
        self._ticket: int | None = None
        self._bb = blackboard.reader("stream requester", [_KEY])
        self.refused: set[str] = set()

    def restart(self) -> None:
        """Ask for every stream again, from the first."""
        self._queue = deque(self.rates)
        self._ticket = None

    @property
    def done(self) -> bool:
        return not self._queue and self._ticket is None

    def service(self) -> None:
        if self._ticket is not None:
            status = self._bb.get(_KEY)
            if status is None or status.ticket != self._ticket or not status.state.done:
                return
            if status.state.name != "ACCEPTED":
                self.refused.add(self._queue[0])
                log.info("autopilot refused stream %s: %s", self._queue[0], status.state)
            self._queue.popleft()
            self._ticket = None
        if self._queue:
            name = self._queue[0]
            interval_us = 1e6 / self.rates[name]
            msg_id = getattr(mavlink, f"MAVLINK_MSG_ID_{name}")
            self._ticket = self._commander.command_long(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, (msg_id, interval_us))
