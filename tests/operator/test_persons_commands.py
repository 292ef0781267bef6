"""A person's mode, arm and disarm through the executive change the mission only by what the vehicle did (issue 44, item 3).

On the simulated firmware in lock-step: a mode the autopilot refuses leaves a RUNNING mission RUNNING
(PX4's POSCTL without RC: TEMPORARILY_REJECTED; ArduRover's FOLLOW without a target), the refusal in
ctl's answer, the status, the journal and a STATUSTEXT; a mode accepted after a refused one pauses the
mission, named as the heartbeat shows it.
"""

from __future__ import annotations

import logging
from typing import Any

import pytest

from executive.mission.lifecycle import MissionStatus
from executive.observers.journal import Journal, JournalLogHandler, journal_recorder
from executive.testing import GCS, Lockstep
from executive.world.clock import Clock
from executive.world.dialect import mavlink
from tests_support import line_mission


@pytest.fixture
def journalled(lockstep, tmp_path):
    """``journalled(mission, **options)`` -> a Lockstep whose runtime records its run and its warnings in a journal, and that journal."""
    handlers: list[logging.Handler] = []
    journals: list[Journal] = []

    def plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(tmp_path / f"run{len(journals)}.db", clock))
        handlers.append(JournalLogHandler(journals[-1]))
        logging.getLogger("executive").addHandler(handlers[-1])
        return {"plugs": [journal_recorder(journals[-1])]}

    def make(mission, **options: Any) -> tuple[Lockstep, Journal]:
        return lockstep(mission, options_for_clock=plug, **options), journals[-1]

    yield make
    for handler in handlers:
        logging.getLogger("executive").removeHandler(handler)
    for journal in journals:
        journal.close()


def mid_leg(sim: Lockstep) -> None:
    """Run until the rover drives its first leg (GUIDED, OFFBOARD on PX4), RUNNING."""
    driving = ("GUIDED", "OFFBOARD")
    assert sim.run(limit_s=120, until=lambda: sim.status is MissionStatus.RUNNING and sim.autopilot.mode in driving) is None
    started = sim.clock.now()
    sim.run(limit_s=10, until=lambda: sim.clock.now() >= started + 3.0)  # under way


def answer(sim: Lockstep, reply) -> dict:
    """What the autopilot answered to a person's command, once it has (ticking meanwhile)."""
    ask = {"ticket": reply.command["ticket"], "name": reply.command["name"]}
    sim.run(limit_s=10, until=lambda: sim.runtime.operator.request("command", **ask).command.get("final", False))
    return sim.runtime.operator.request("command", **ask).command


def events(journal: Journal) -> list[str]:
    return [event["text"] for event in journal.report()["events"] if event["kind"] == "operator"]


def test_px4_refuses_posctl_the_mission_stays_running_and_completes(journalled) -> None:
    """Before: `ctl mode POSCTL` refused (TEMPORARILY_REJECTED), yet PAUSED "hands off" and the run never ended without `ctl resume`."""
    sim, journal = journalled(line_mission("px4-posctl", autopilot="px4"), autopilot="px4")
    mid_leg(sim)
    leg = sim.runtime.mission_state.legs.leg_index
    reply = sim.runtime.operator.request("mode", source="ctl", mode="POSCTL")
    assert reply.ok and reply.state == "RUNNING"
    assert answer(sim, reply)["state"] == "REJECTED"
    assert sim.status is MissionStatus.RUNNING and sim.runtime.mission_state.legs.leg_index == leg
    status = sim.runtime.status.snapshot()
    assert status["command"] | {"t": None} == {
        "what": "mode POSCTL",
        "by": "ctl",
        "answer": "refused by the autopilot (TEMPORARILY_REJECTED)",
        "refused": True,
        "t": None,
    }
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED
    assert "ctl: mode POSCTL refused by the autopilot (TEMPORARILY_REJECTED): nothing changed (the mission RUNNING)" in events(journal)
    assert "PAUSED" not in [transition["after"] for transition in journal.report()["transitions"]]


def test_ardurover_refused_follow_then_accepted_simple_pauses_on_simple(journalled) -> None:
    """Before: after a refused FOLLOW and an accepted SIMPLE the status still named FOLLOW."""
    sim, journal = journalled(line_mission("follow-simple"))
    mid_leg(sim)
    refused = sim.runtime.operator.request("mode", source="ctl", mode="FOLLOW")
    assert answer(sim, refused)["state"] == "REJECTED" and sim.status is MissionStatus.RUNNING and sim.autopilot.mode == "GUIDED"
    accepted = sim.runtime.operator.request("mode", source="ctl", mode="SIMPLE")
    assert answer(sim, accepted)["state"] == "ACCEPTED"
    sim.run(limit_s=5, until=lambda: sim.status is MissionStatus.PAUSED)
    assert sim.autopilot.mode == "SIMPLE"
    assert sim.runtime.status.snapshot()["reason"] == "SIMPLE set by a person (ctl: mode SIMPLE)"
    assert events(journal)[:4] == [
        "ctl: mode FOLLOW; the mission pauses, hands off, once the vehicle shows it (refused: nothing changes), sent to the autopilot",
        "ctl: mode FOLLOW refused by the autopilot (FAILED): nothing changed (the mission RUNNING)",
        "ctl: mode SIMPLE; the mission pauses, hands off, once the vehicle shows it (refused: nothing changes), sent to the autopilot",
        "ctl: mode SIMPLE ACCEPTED by the autopilot",
    ]
    assert "SIMPLE set by a person (ctl: mode SIMPLE) -> mission paused at leg 1, hands off until resumed" in events(journal)


def test_a_ground_stations_mode_refused_by_px4_changes_nothing(journalled) -> None:
    """A ground station's DO_SET_MODE POSCTL goes to the autopilot, which refuses it: no heartbeat changes, the mission goes on."""
    sim, journal = journalled(line_mission("px4-gcs-posctl", autopilot="px4"), autopilot="px4")
    mid_leg(sim)
    posctl = GCS.command_long(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 3, 0, 0, 0, 0, 0)
    acks = [m for m in sim.autopilot.handle(posctl) + sim.autopilot.update() if m.get_type() == "COMMAND_ACK"]
    assert acks[-1].result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert sim.run_to_end(limit_s=300).status is MissionStatus.COMPLETED
    assert "PAUSED" not in [transition["after"] for transition in journal.report()["transitions"]]
