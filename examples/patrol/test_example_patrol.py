"""Tests of the patrol tree, written only with ``executive.testing`` (copy this file next to your own tree).

Tick by tick with a scripted autopilot (every input in the test's hands), then the whole mission
in the lock-step simulation (the built-in simulated ArduRover, deterministic, a few seconds).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from py_trees.common import Status

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.testing import EKF_READY, Harness, ScriptedAutopilot
from executive.world.state import GpsFix
from patrol_tree import build

MISSION = load_mission(Path(__file__).with_name("patrol.yaml"))
HOME = (MISSION.home.lat, MISSION.home.lon)


class Rover(ScriptedAutopilot):
    """The scripted autopilot with a GPS (``satellites``) and an EKF that is ready."""

    satellites = 12

    def facts(self) -> dict[str, object]:
        gps = GpsFix(3, self.satellites, 0.8, self.h.clock.now())
        return {**super().facts(), "link__up": True, "vehicle__ekf": EKF_READY, "vehicle__gps": gps}


@pytest.fixture
def rover() -> Rover:
    """The patrol tree, the mission started, over a scripted rover at home."""
    return Rover(Harness.build(MISSION, root=build(MISSION)), HOME, step_m=4.0)


def test_the_beacon_goes_on_after_arming_and_before_the_first_leg(rover: Rover) -> None:
    statuses = rover.run(400)
    assert statuses[-1] == Status.SUCCESS
    assert rover.commands[:3] == [("arm", 1.0), ("DO_SET_RELAY",), ("mode", "GUIDED")]
    assert rover.commands[-1] == ("mode", "HOLD")  # held at the end
    assert rover.h.feedback("Beacon on") == "confirmed"


def test_a_refused_beacon_ends_the_patrol_before_it_moves(rover: Rover) -> None:
    rover.refuse.add("DO_SET_RELAY")
    statuses = rover.run(100)
    assert statuses[-1] == Status.FAILURE
    assert rover.h.feedback("Beacon on") == "refused: FAILED"
    assert ("mode", "GUIDED") not in rover.commands and rover.target is None


def test_too_few_satellites_hold_the_rover_until_they_come_back(rover: Rover) -> None:
    rover.run(400, until=lambda: rover.h.mission_state.legs.leg_index == 1)  # on the second leg
    rover.satellites = 5
    rover.publish()  # the GPS reports it before the next tick
    rover.commands.clear()
    assert rover.run(1) == [Status.RUNNING]  # HOLD asked in the tick the guard fails
    assert rover.h.status("Guarded legs/Enough satellites?") == Status.FAILURE
    assert rover.h.feedback("Guarded legs/Enough satellites?") == "5 satellites, fewer than 8"
    assert rover.commands == [("mode", "HOLD")]
    assert rover.run(50)[-1] == Status.RUNNING and rover.mode == "HOLD"  # it waits (within limits.recovery_timeout_s)
    rover.satellites = 9
    rover.publish()
    assert rover.run(400)[-1] == Status.SUCCESS
    assert rover.h.mission_state.legs.leg_index == 4


def test_without_satellites_for_longer_than_the_recovery_limit_the_patrol_fails(rover: Rover) -> None:
    rover.run(400, until=lambda: rover.h.mission_state.legs.leg_index == 1)
    rover.satellites = 3
    rover.publish()
    statuses = rover.run(400)
    assert statuses[-1] == Status.FAILURE
    assert len(statuses) * 0.1 == pytest.approx(MISSION.limits.recovery_timeout_s, abs=0.25)  # 20 s of vehicle time
    assert rover.h.feedback("Wait for guards") == "not recovered after 20 s: Enough satellites? 3 satellites, fewer than 8"


def test_the_patrol_completes_on_the_simulated_rover_with_its_beacon_on(lockstep) -> None:
    sim = lockstep(MISSION, root=build(MISSION))
    outcome = sim.run_to_end(limit_s=300)
    assert (outcome.status, outcome.reason) == (MissionStatus.COMPLETED, "every waypoint reached")
    assert sim.autopilot.relays == {0: True}
    assert sim.autopilot.mode == "HOLD"
