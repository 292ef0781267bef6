"""Waiting for a person to arm the vehicle: how to arm it is said when the wait starts, and again when it gives up."""

from __future__ import annotations

import logging

from executive.mission.lifecycle import MissionStatus
from tests_support import line_mission

HOW = "to arm it: `executive ctl arm`"


def _hints(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if HOW in r.getMessage()]


def test_nobody_arms_how_to_arm_is_said_when_the_wait_starts_and_again_on_giving_up(lockstep, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    mission = line_mission("nobody arms", auto_arm=False, limits={"acceptance_radius_m": 1.5, "recovery_timeout_s": 5.0})
    outcome = lockstep(mission).run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason.startswith("Wait for the operator to arm: gave up after 5 s: vehicle is disarmed (to arm it: "), outcome.reason
    assert "`auto_arm: true` in the mission" in outcome.reason
    said = _hints(caplog)
    assert said[0] == (
        "Wait for the operator to arm (up to 5 s): to arm it: `executive ctl arm` or a ground station; "
        "or `auto_arm: true` in the mission to have it armed in pre-flight"
    ), said


def test_the_rc_arm_switch_is_named_where_the_mission_has_one(lockstep, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    limits = {"acceptance_radius_m": 1.5, "recovery_timeout_s": 3.0}
    outcome = lockstep(line_mission("rc arms", auto_arm=False, limits=limits, rc={"arm_channel": 5})).run_to_end(limit_s=60)
    assert "RC channel 5 high" in outcome.reason
    assert "`executive ctl arm`, RC channel 5 high or a ground station" in _hints(caplog)[0]


def test_a_vehicle_armed_before_the_wait_hears_no_hint(lockstep, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive")
    outcome = lockstep(line_mission("armed by the executive")).run_to_end(limit_s=120)
    assert outcome.status is MissionStatus.COMPLETED and not _hints(caplog)
