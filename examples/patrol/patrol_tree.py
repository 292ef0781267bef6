"""A user's own tree: a rover patrol that turns its beacon on before it moves and drives only with enough satellites.

::

    Patrol (in order)
    ├── Pre-flight: wait for the EKF, arm
    ├── Beacon on                       <- the user's action (MAV_CMD_DO_SET_RELAY)
    ├── Patrol or hold (re-checked every tick)
    │   ├── Guarded legs: link alive? EKF ok? armed? enough satellites? <- the user's guard
    │   │   -> for each leg: GUIDED, go to
    │   └── Wait for guards: HOLD, then go on when they hold again (FAILURE after limits.recovery_timeout_s)
    └── Hold at the end
"""

from __future__ import annotations

import py_trees

from executive.autopilot.port import Request
from executive.behaviours import Arm, Armed, EkfOk, ForEachLeg, GoTo, Guard, LinkAlive, SetMode, WaitForGuards, WaitUntil
from executive.behaviours.actions import CommandAction
from executive.mission.model import Mission
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import CommandState, GpsFix


class EnoughSatellites(Guard):
    """The GPS sees at least ``minimum`` satellites (GPS_RAW_INT); no report yet is not enough."""

    reads = ("/vehicle/gps",)
    #: Said by `executive behaviours`: every guard states what it does without a reading, and with an old one.
    unknown_or_stale = "no GPS_RAW_INT yet, or no satellite count in it: fails; an old one: judged as it is (EKF ok? fails when the GPS goes)"

    def __init__(self, minimum: int = 8, name: str = "Enough satellites?") -> None:
        super().__init__(name)
        self.minimum = minimum

    def check(self) -> str | None:
        gps: GpsFix | None = self.get("/vehicle/gps")
        if gps is None or gps.satellites is None:
            return "no satellite count from the GPS yet"
        return None if gps.satellites >= self.minimum else f"{gps.satellites} satellites, fewer than {self.minimum}"


class BeaconOn(CommandAction):
    """Turn the beacon (a relay) on with MAV_CMD_DO_SET_RELAY; confirmed by the autopilot's ACCEPTED ack (nothing else reports a relay)."""

    outcome = "DO_SET_RELAY"  # a raw MAV_CMD no outcome of the port covers: its key is named after it

    def __init__(self, relay: int = 0, name: str = "Beacon on") -> None:
        blackboard.document_command(self.outcome)  # /command/do_set_relay: where the commander reports its ack
        super().__init__(name)
        self.relay = relay

    def request(self) -> Request:
        commander = self.autopilot.backend.commander  # the MAVLink back end's own: the autopilot port has no intent for a relay
        return Request(commander.command_long(mavlink.MAV_CMD_DO_SET_RELAY, [self.relay, 1]), self.outcome, f"relay {self.relay} on")

    def confirmed(self) -> bool:
        status = self.get(blackboard.command_key(self.outcome))
        return status is not None and self._ticket is not None and status.ticket == self._ticket.ticket and status.state is CommandState.ACCEPTED


def build(mission: Mission, satellites: int = 8) -> py_trees.behaviour.Behaviour:
    """The patrol tree for ``mission`` (a rover's waypoints)."""
    limits = mission.limits
    preflight = py_trees.composites.Sequence(
        "Pre-flight", memory=True, children=[WaitUntil(EkfOk(), limits.ekf_wait_s), WaitUntil(Arm(), limits.ekf_wait_s, name="Arm", retry_s=2.0)]
    )
    guards = [LinkAlive(), EkfOk(), Armed(), EnoughSatellites(satellites)]
    leg = py_trees.composites.Sequence("Leg", memory=True, children=[SetMode("GUIDED"), GoTo(limits.acceptance_radius_m, limits.leg_timeout_s)])
    legs = py_trees.composites.Sequence("Guarded legs", memory=False, children=[*guards, ForEachLeg(leg)])
    hold = WaitForGuards(guards, limits.recovery_timeout_s, hold_mode="HOLD")
    patrol = py_trees.composites.Selector("Patrol or hold", memory=False, children=[legs, hold])
    return py_trees.composites.Sequence("Patrol", memory=True, children=[preflight, BeaconOn(), patrol, SetMode("HOLD", name="Hold at the end")])
