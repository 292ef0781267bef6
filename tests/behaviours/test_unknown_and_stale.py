"""Unknown and stale are not healthy: each guard with no reading yet, and with one older than its limit while the autopilot is heard.

A reading's age runs while heartbeats arrive (``/link/last_heartbeat``), from its arrival or from when
the link last came up (``/link/up_since``), whichever is later: while the link is lost, Link alive?
stands for every reading. Vehicle time throughout (the harness's manual clock).
"""

from __future__ import annotations

import json
from dataclasses import replace

import pytest
from py_trees.common import Status

from executive.behaviours import (
    AltitudeWithin,
    BatteryAbove,
    EkfOk,
    GpsNotGlitching,
    HeadingSane,
    ModeSwitchClear,
    RcNotLost,
    SpeedWithin,
)
from executive.cli import main
from executive.io.mavlink.reader import MavlinkReader
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Range
from executive.mission.resume import ResumePoint
from executive.testing import AUTOPILOT, EKF_READY, Harness
from executive.tree.catalogue import catalogue
from executive.world import blackboard
from executive.world.dialect import mavlink
from executive.world.state import Battery, Rangefinder

EKF_FLAGS = int(EKF_READY.flags)


def heard_every_tick(h: Harness, **facts: object) -> None:
    """The reader's part each tick: a HEARTBEAT arrived now (and ``facts``, once)."""
    h.vehicle.set(**facts)
    h.readers.append(lambda: h.vehicle.set(link__up=True, link__last_heartbeat=h.clock.now()))


def ticks_until_failure(h: Harness, limit: int = 200) -> float:
    """Ticks (0.1 s) until the root fails; the vehicle time it failed at."""
    for _ in range(limit):
        if h.tick() == Status.FAILURE:
            return h.clock.now()
    raise AssertionError("never failed")


@pytest.mark.parametrize(
    ("make", "reading", "limit_s", "what"),
    [
        (EkfOk, lambda t: {"vehicle__ekf": replace(EKF_READY, time=t)}, 3.0, "the EKF report is"),
        (GpsNotGlitching, lambda t: {"vehicle__ekf": replace(EKF_READY, time=t)}, 3.0, "the EKF report is"),
        (
            lambda: BatteryAbove(20.0),
            lambda t: {"vehicle__battery": Battery(12.0, 1.0, 80, t)},
            5.0,
            "the battery report (SYS_STATUS) is",
        ),
        (
            RcNotLost,
            lambda t: {"rc__connected": True, "rc__channels": (1500,) * 8, "rc__last_update": t},
            3.0,
            "the RC report is",
        ),
        (
            lambda: AltitudeWithin(Range(min=2.0, max=100.0)),
            lambda t: {
                "vehicle__altitude_above_bottom_m": 10.0,
                "vehicle__rangefinder": Rangefinder(10.0, 0.2, 50.0, "good", t),
                "vehicle__altitude_last_update": t,
            },
            2.0,
            "the rangefinder reading is",
        ),
        (
            HeadingSane,
            lambda t: {"heading__ok": True, "heading__last_update": t},
            2.0,
            "the attitude (ATTITUDE) is",
        ),
    ],
    ids=["ekf", "gps", "battery", "rc", "rangefinder", "heading"],
)
def test_a_reading_older_than_its_limit_while_the_autopilot_is_heard_fails(harness, make, reading, limit_s, what):
    """Before: an old EKF report (a battery, an RC report, a sonar reading, an attitude) was trusted as long as heartbeats arrived.

    It fails at the first tick past its limit, and its own debounce (hold_after_s: the battery's 2 s) after that.
    """
    node = make()
    h = harness(node)
    t0 = h.clock.now()
    heard_every_tick(h, link__up_since=t0, **reading(t0))
    failed_at = ticks_until_failure(h)
    age = limit_s + 0.1 + node.hold_after_s
    assert failed_at == pytest.approx(t0 + age)
    assert f"{what} {age:.1f} s old while the autopilot is heard (limit {limit_s:g} s)" in node.feedback_message


def test_while_the_link_is_lost_the_link_guard_stands_for_the_readings_and_their_age_counts_again_once_it_is_back(harness):
    """No heartbeat, no reading can come: EKF ok? keeps its verdict (Link alive? fails); back, the EKF has 3 s to report again."""
    node = EkfOk()
    h = harness(node)
    t0 = h.clock.now()
    h.vehicle.set(link__up=True, link__up_since=t0, link__last_heartbeat=t0, vehicle__ekf=replace(EKF_READY, time=t0))
    assert [h.tick(1.0) for _ in range(20)] == [Status.SUCCESS] * 20  # 20 s without a heartbeat: the age stays 0
    back = h.clock.now()
    h.vehicle.set(link__up_since=back)
    heard_every_tick(h)
    failed_at = ticks_until_failure(h)
    assert failed_at == pytest.approx(back + 3.1)
    assert "the EKF report is 3.1 s old" in node.feedback_message


@pytest.mark.parametrize(
    ("make", "why"),
    [
        (EkfOk, "no EKF status yet"),
        (GpsNotGlitching, "no EKF status yet: a GPS glitch cannot be ruled out"),
        (lambda: BatteryAbove(20.0), "battery not reported yet (no SYS_STATUS)"),
        (lambda: BatteryAbove(None, 10.5), "battery not reported yet (no SYS_STATUS)"),
        (lambda: SpeedWithin(Range(min=0.0, max=2.0)), "speed not reported yet (no GLOBAL_POSITION_INT, no VFR_HUD)"),
        (lambda: AltitudeWithin(Range(min=2.0, max=100.0)), "no altitude above the seabed (no valid rangefinder reading)"),
    ],
    ids=["ekf", "gps", "battery-pct", "battery-volts", "speed", "rangefinder"],
)
def test_no_reading_yet_fails(harness, make, why):
    """Before: no battery report, no EKF report (for the GPS guard), no speed passed with a note."""
    node = make()
    h = harness(node)
    h.vehicle.set(link__up=True, link__last_heartbeat=h.clock.now())
    assert h.tick() == Status.FAILURE
    assert node.feedback_message == why


def test_the_mode_switch_channel_not_read_yet_fails(square_mission):
    """Before: MODE_CH not read passed with a note (and so did a clash the answer would have shown)."""
    h = Harness.build(square_mission, root=ModeSwitchClear({6: "the take-over switch", 8: "switch D"}))
    h.vehicle.set(link__up=True, vehicle__params=None)
    assert h.tick() == Status.FAILURE
    assert h.root.feedback_message.startswith("MODE_CH not read yet (the autopilot has not answered PARAM_REQUEST_READ)")


def test_the_reader_stamps_when_the_link_came_up_and_the_ekf_guard_fails_when_its_reports_stop(harness, link, clock, commander):
    """End to end from MAVLink: heartbeats keep coming, EKF_STATUS_REPORT stops after one: EKF ok? fails 3 s on, naming it."""
    reader = MavlinkReader(link, clock, commander, link_timeout_s=3.0)
    node = EkfOk()
    h = harness(node)
    heartbeat = AUTOPILOT.heartbeat(mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 4, mavlink.MAV_STATE_ACTIVE)
    report = AUTOPILOT.ekf_status_report(EKF_FLAGS, 0.1, 0.1, 0.1, 0.1, 0.0)
    link.incoming.extend([heartbeat, report])
    reader.drain()
    t0 = clock.now()
    assert blackboard.value("/link/up_since") == t0
    beats = 0

    def autopilot() -> None:
        nonlocal beats
        beats += 1
        if beats % 10 == 0:  # ArduPilot's 1 Hz heartbeat, nothing else
            link.incoming.append(heartbeat)
        reader.drain()

    h.readers.append(autopilot)
    statuses = [h.tick() for _ in range(45)]
    assert statuses[:39] == [Status.SUCCESS] * 39  # heard at t0+1, +2, +3: 3 s old, not over the limit
    assert Status.FAILURE in statuses[39:]  # heard at t0+4: 4 s old
    assert "the EKF report is 4.0 s old while the autopilot is heard (limit 3 s)" in node.feedback_message


def test_every_guard_says_what_it_does_without_a_reading_and_with_an_old_one(capsys):
    guards = catalogue().nodes("guard")
    assert len(guards) >= 20
    assert [g.name for g in guards if not g.unknown_or_stale] == []
    assert main(["behaviours", "ekf_ok", "battery_above", "mode_switch_clear"]) == 0
    out = capsys.readouterr().out
    assert "unknown or stale: no EKF report yet: fails; a report older than 3 s while the autopilot is heard: fails" in out
    assert "unknown or stale: no SYS_STATUS yet, or the field a floor needs unknown" in out
    assert "unknown or stale: MODE_CH (ArduRover) or FLTMODE_CH (ArduPlane) not read yet: fails" in out
    assert main(["behaviours", "--json", "--kind", "guard"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert all(g["unknown_or_stale"] for g in listed)


# -- pre-flight waits for what the guards need, bounded, then refuses naming what never came ---------------------------------------


def ready(h: Harness, **facts: object) -> None:
    h.vehicle.set(link__up=True, vehicle__ekf=EKF_READY, vehicle__mode="HOLD", rc__channels=(1500,) * 8, **facts)


def test_pre_flight_waits_for_the_mode_switch_channel_asking_for_it_then_arms(square_mission):
    h = Harness.build(square_mission)
    ready(h, vehicle__params=None)
    assert h.tick() == Status.RUNNING
    assert h.asked() == [("PARAM_REQUEST_READ",)]  # asked, nothing armed
    assert h.feedback("Pre-flight/Readings in?").startswith("waiting (0/10 s) for MODE_CH (PARAM_VALUE)")
    for _ in range(14):
        h.tick()
    assert h.asked() == [("PARAM_REQUEST_READ",)]  # once a second
    h.vehicle.set(vehicle__params={"MODE_CH": 8.0})
    h.tick()
    assert h.asked() == [("arm", True)]


@pytest.mark.parametrize(
    ("facts", "never_came"),
    [
        ({"vehicle__params": None}, "never came within 10 s: MODE_CH (PARAM_VALUE)"),
        ({"vehicle__battery": None}, "never came within 10 s: a battery report (SYS_STATUS)"),
        (
            {"vehicle__battery": Battery(12.0, None, None, 0.0)},
            "never came within 10 s: the battery's remaining % (battery_remaining) (SYS_STATUS reports it unknown: set the autopilot's battery "
            "monitor, ArduPilot BATT_MONITOR, or fly without this floor: limits.battery_min_pct: null)",
        ),
        ({"vehicle__params": None, "vehicle__battery": None}, "never came within 10 s: MODE_CH (PARAM_VALUE); a battery report (SYS_STATUS)"),
    ],
    ids=["mode-switch", "battery", "battery-remaining", "both"],
)
def test_pre_flight_refuses_naming_what_never_came(square_mission, facts, never_came):
    """square_mission: take-over on channel 6, limits.battery_min_pct 20 (the default): MODE_CH and a battery report are needed."""
    h = Harness.build(square_mission)
    ready(h, **facts)
    statuses = [h.tick() for _ in range(102)]
    assert statuses[:100] == [Status.RUNNING] * 100 and statuses[-1] == Status.FAILURE  # 10 s, then refused
    assert h.feedback("Pre-flight/Readings in?") == never_came
    assert ("arm", True) not in h.asked()


def test_a_resume_with_the_ekf_ready_at_the_first_tick_waits_for_the_mode_switch_channel_and_refuses_the_clash(lockstep, square_mission):
    """Issue 25: `run --resume` on a vehicle whose EKF is ready at the first tick ticked the check before MODE_CH was answered,
    and it passed: the take-over switch on channel 8, ArduRover's mode switch, was never refused. Lock-step, vehicle time."""
    clash = square_mission.model_copy(update={"rc": square_mission.rc.model_copy(update={"takeover_channel": 8})})
    sim = lockstep(clash, ekf_ready_after_s=0.0)
    outcome = sim.run(limit_s=120, resume=ResumePoint(run=1, leg_index=1, samples=()))
    assert outcome is not None and outcome.status is not MissionStatus.COMPLETED
    assert "RC channel 8 (the take-over switch) is the autopilot's mode switch (MODE_CH = 8)" in outcome.reason
    assert not sim.autopilot.armed  # refused before arming
    assert outcome.ticks < 20  # the answer came within a second or so: nothing waited for long
