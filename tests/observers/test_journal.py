"""The journal: every transition, leg and sample on disk at once; an unfinished run can be resumed."""

from __future__ import annotations

import sqlite3

import pytest

from executive.cli.report import render
from executive.mission.lifecycle import MissionState
from executive.mission.model import Home, Mission, Waypoint
from executive.mission.route import Route
from executive.observers.journal import Journal, mission_hash
from executive.world.state import SampleRead, SampleRecord


@pytest.fixture
def journal(tmp_path, clock):
    j = Journal(tmp_path / "run.db", clock)
    yield j
    j.close()


def sample(leg: int) -> SampleRecord:
    return SampleRecord(leg, 47.0, 8.0, (SampleRead("ph", 7.5, "", 1.0), SampleRead("temperature", 18.2, "°C", 1.0)), 1.0, 11.0)


def started(journal: Journal, mission: Mission) -> tuple[MissionState, int]:
    """A mission state the journal records, ``mission`` uploaded, its run begun and started; and the run's id."""
    state = MissionState()
    journal.attach(state)
    state.upload(mission)
    run = journal.begin_run(mission)
    state.start()
    return state, run


def reopen(journal, clock) -> Journal:
    """A second connection, as a new process after a crash would have."""
    return Journal(journal.path, clock)


def test_a_run_is_recorded_as_it_happens(journal, clock, square_mission):
    state, _ = started(journal, square_mission)
    journal.observe_leg(state, 47.0, 8.0)
    state.record_sample(sample(0))
    state.advance_leg()
    clock.advance(5.0)
    journal.observe_leg(state, 47.1, 8.1)
    journal.observe_leg(state, 47.1, 8.1)  # no change, no row
    journal.event("failsafe", "EKF lost: holding")
    other = reopen(journal, clock)  # committed already: another connection sees it all
    report = other.report()
    other.close()
    assert [(t["before"], t["after"]) for t in report["transitions"]] == [("READY", "RUNNING")]
    assert [(leg["waypoint"], leg["waypoints"]) for leg in report["legs"]] == [(1, 4), (2, 4)]  # numbered from 1, as the status
    assert report["samples"][0]["reads"][1] == {"sensor": "temperature", "value": 18.2, "unit": "°C", "time": 1.0}
    assert report["events"] == [{"t": clock.now(), "kind": "failsafe", "text": "EKF lost: holding"}]
    assert report["outcome"] is None and report["ended"] is None


def test_an_unfinished_run_resumes_at_its_last_leg_with_its_samples(journal, clock, square_mission):
    state, run = started(journal, square_mission)
    state.record_sample(sample(0))
    state.advance_leg()
    state.advance_leg()
    journal.observe_leg(state, None, None)
    # the process dies here (kill -9): nothing more is written
    after_crash = reopen(journal, clock)
    point = after_crash.resume_point(square_mission)
    after_crash.close()
    assert (point.run, point.leg_index) == (run, 2)
    assert point.samples == (sample(0),)
    assert point.route is None  # never edited: the mission file's route


def test_an_edited_route_is_recorded_and_resumed_as_edited(journal, clock, square_mission):
    state, run = started(journal, square_mission)
    state.advance_leg()
    journal.observe_leg(state, None, None)  # heading for waypoint 2 of 4
    clock.advance(3.0)
    first, *_, last = square_mission.waypoints
    extra = Waypoint(lat=47.3981, lon=8.5458, name="added")  # a leg the square's leg_timeout_s fits
    state.set_route([first, extra, last], "ctl route: remove 2 and 3, add one")  # renumbers: heading for waypoint 2 of 3
    home = Home(lat=47.3978, lon=8.5457, heading_deg=90.0)
    clock.advance(1.0)
    state.set_route([first, extra, last], "switch A: home here", leg_index=2, home=home)
    after_crash = reopen(journal, clock)
    point = after_crash.resume_point(square_mission)
    report = after_crash.report(run)
    after_crash.close()
    assert point.route == Route((first, extra, last), 2, home)
    assert point.leg_index == 2  # the route edit is the latest word on the leg
    assert [(r["waypoint"], r["name"], r["waypoints"], r["reason"]) for r in report["routes"]] == [
        (2, "added", 3, "ctl route: remove 2 and 3, add one"),
        (3, None, 3, "switch A: home here"),
    ]
    text = render(report)
    assert "route edits (2):" in text and "3 waypoints, heading for waypoint 2 'added' of 3: ctl route: remove 2 and 3, add one" in text


def test_a_leg_change_after_an_edit_is_where_it_resumes(journal, clock, square_mission):
    state, _ = started(journal, square_mission)
    state.set_route(square_mission.waypoints[:2], "switch A: remove")
    state.advance_leg()
    journal.observe_leg(state, None, None)  # same clock time as the edit: recorded after it
    point = journal.resume_point(square_mission)
    assert (point.leg_index, len(point.route)) == (1, 2)


def test_a_finished_run_or_another_mission_is_not_resumed(journal, clock, square_mission):
    journal.begin_run(square_mission)
    journal.end_run("COMPLETED", "every waypoint reached")
    assert journal.resume_point(square_mission) is None
    other = square_mission.model_copy(update={"name": "other"})
    journal.begin_run(other)
    assert journal.resume_point(square_mission) is None
    assert journal.resume_point(other) is not None
    assert mission_hash(other) != mission_hash(square_mission)


def test_a_sample_is_never_recorded_twice_for_a_leg(journal, square_mission):
    state, _ = started(journal, square_mission)
    state.record_sample(sample(0))
    with pytest.raises(sqlite3.IntegrityError):
        journal._on_sample(sample(0))


def test_the_database_is_in_wal_mode(journal):
    assert journal._db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_an_empty_route_is_not_every_waypoint_reached(journal, clock, square_mission):
    """Issue 43: a UGV's report opened with `every waypoint reached (0 of 0)` (its route is driven, then recorded by RC)."""
    _, run = started(journal, square_mission)
    report = journal.report(run)
    report["legs"] = [{"t": 0.0, "waypoint": None, "waypoints": 0, "name": None, "lat": None, "lon": None}]  # ugv_rc_route before a record
    text = render(report)
    assert "no waypoint yet (an empty route)" in text and "(0 of 0)" not in text
