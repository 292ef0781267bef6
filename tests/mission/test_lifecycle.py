"""The mission lifecycle: the AUV mission manager's transition table, refusals that change nothing."""

from __future__ import annotations

import re

import py_trees
import pytest

import executive
from executive.mission.events import Transition
from executive.mission.lifecycle import TRANSITIONS, MissionState, MissionStatus, Refused

S = MissionStatus


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


@pytest.fixture
def state_in(square_mission):
    """``state_in(S.PAUSED)``: a MissionState driven to a state by legal requests."""

    routes = {
        S.IDLE: [],
        S.READY: ["upload"],
        S.RUNNING: ["upload", "start"],
        S.PAUSED: ["upload", "start", "pause"],
        S.COMPLETED: ["upload", "start", "complete"],
        S.ABORTED: ["upload", "start", "abort"],
    }

    def make(status: MissionStatus) -> MissionState:
        state = MissionState()
        for request in routes[status]:
            {"upload": lambda: state.upload(square_mission), "abort": lambda: state.abort("test")}.get(request, getattr(state, request))()
        assert state.status is status
        return state

    return make


# (state, request) -> resulting state, or None when refused; the AUV table plus ABORTED.
TABLE = {
    (S.IDLE, "upload"): S.READY,
    (S.READY, "upload"): S.READY,
    (S.COMPLETED, "upload"): S.READY,
    (S.RUNNING, "upload"): None,
    (S.PAUSED, "upload"): None,
    (S.READY, "start"): S.RUNNING,
    (S.COMPLETED, "start"): S.RUNNING,
    (S.IDLE, "start"): None,
    (S.RUNNING, "start"): None,
    (S.PAUSED, "start"): None,
    (S.RUNNING, "pause"): S.PAUSED,
    (S.READY, "pause"): None,
    (S.PAUSED, "pause"): None,
    (S.PAUSED, "resume"): S.RUNNING,
    (S.RUNNING, "resume"): None,
    (S.READY, "resume"): None,
    (S.READY, "delete"): S.IDLE,
    (S.PAUSED, "delete"): S.IDLE,
    (S.COMPLETED, "delete"): S.IDLE,
    (S.RUNNING, "delete"): S.IDLE,  # paused first
    (S.IDLE, "delete"): None,
    (S.ABORTED, "start"): S.RUNNING,
    (S.ABORTED, "upload"): S.READY,
}


@pytest.mark.parametrize(("start", "request_", "expected"), [(s, r, e) for (s, r), e in TABLE.items()], ids=lambda v: str(v))
def test_transition_table(state_in, square_mission, start, request_, expected):
    state = state_in(start)
    action = (lambda: state.upload(square_mission)) if request_ == "upload" else getattr(state, request_)
    before = (state.status, state.legs.leg_index, state.mission, bb("/mission/state"))
    if expected is None:
        with pytest.raises(Refused, match=f"cannot {request_} while {start}"):
            action()
        assert (state.status, state.legs.leg_index, state.mission, bb("/mission/state")) == before  # nothing half-applied
    else:
        action()
        assert state.status is expected
        assert bb("/mission/state") == str(expected)


def test_every_request_in_the_table_is_covered():
    assert {r for _, r in TABLE} >= set(TRANSITIONS) - {"complete", "abort"}


def test_start_after_completion_runs_again_from_the_first_waypoint(state_in, square_mission):
    state = state_in(S.RUNNING)
    for _ in range(4):
        state.advance_leg()
    state.complete()
    state.start()
    assert state.legs.leg_index == 0
    assert state.legs.target == square_mission.waypoints[0]


def test_pause_and_resume_keep_the_leg(state_in, square_mission):
    state = state_in(S.RUNNING)
    state.advance_leg()
    state.pause()
    assert state.legs.target == square_mission.waypoints[1]
    state.resume()
    assert state.legs.leg_index == 1
    assert bb("/mission/target") == square_mission.waypoints[1]


def test_delete_while_running_pauses_first(state_in):
    state = state_in(S.RUNNING)
    seen = []
    state.events.subscribe(Transition, lambda before, after, reason: seen.append((before, after)))
    state.delete()
    assert seen == [(S.RUNNING, S.PAUSED), (S.PAUSED, S.IDLE)]
    assert state.mission is None and bb("/mission/leg_count") == 0


def test_advance_leg_only_while_running(state_in):
    state = state_in(S.PAUSED)
    with pytest.raises(Refused):
        state.advance_leg()


def test_progress_is_published(state_in, square_mission):
    state = state_in(S.RUNNING)
    state.advance_leg()
    assert (bb("/mission/leg_index"), bb("/mission/leg_count"), bb("/mission/target")) == (1, 4, square_mission.waypoints[1])
    assert bb("/mission/next_target") == square_mission.waypoints[2]  # the leg may be driven through toward it
    state.advance_leg()
    state.advance_leg()
    assert (bb("/mission/target"), bb("/mission/next_target")) == (square_mission.waypoints[3], None)  # the last leg stops
    state.advance_leg()
    assert (bb("/mission/target"), bb("/mission/next_target")) == (None, None)


def test_past_the_last_waypoint_the_leg_a_person_reads_is_the_last_as_the_status_says(state_in, square_mission):
    """Issue 43: a 2-leg VTOL mission paused while landing said `paused at leg 3` beside the status's `leg 2/2`."""
    state = state_in(S.RUNNING)
    for _ in square_mission.waypoints:
        state.advance_leg()  # every waypoint reached: a VTOL lands now, still RUNNING
    assert (state.legs.leg_index, state.legs.leg_number) == (4, 4)
    state.pause()
    state.resume()
    assert state.reason == "resumed at leg 4"


# -- the lifecycle holds only the lifecycle: the route is read at state.legs, the samples at state.sample_log ----------------------
#: What MissionState is: its state, the mission loaded, its requests, its parts and its checks.
LIFECYCLE = {
    *TRANSITIONS, "replace", "continue_from", "advance_leg", "set_route", "route_refusal", "record_sample", "restore_samples",
    "explain", "announce", "status", "reason", "hold_while_paused", "mission", "legs", "sample_log", "events", "replace_checks",
    "resume_checks",
}  # fmt: skip
#: The pass-throughs of 0.1 and where each is read now (deprecated for one release).
MOVED = {
    "leg_index": "legs.leg_index", "leg_count": "legs.leg_count", "leg_number": "legs.leg_number", "target": "legs.target",
    "next_target": "legs.next_target", "route": "legs.route", "samples": "sample_log.taken", "sampled": "sample_log.sampled",
    "work_left": "sample_log.work_left(mission)",
}  # fmt: skip


def public(instance: object) -> set[str]:
    return {name for name in dir(instance) if not name.startswith("_")}


def test_the_lifecycle_s_own_surface_has_no_route_or_sample_member_but_the_deprecated_ones(square_mission) -> None:
    state = MissionState()
    state.upload(square_mission)
    deprecated = {name for name in public(MissionState) if isinstance(getattr(MissionState, name), executive.MovedMember)}
    assert deprecated == set(MOVED)
    assert public(state) - deprecated == LIFECYCLE
    # nothing of the route's or the sample log's is the lifecycle's own (the mission loaded is what its states are of)
    assert (public(state.legs) | public(state.sample_log)) & (public(state) - deprecated) == {"mission"}


@pytest.mark.parametrize("old", sorted(MOVED))
def test_each_old_pass_through_warns_naming_where_it_is_read_now(state_in, old: str) -> None:
    state = state_in(S.RUNNING)
    state.advance_leg()
    new = {
        "leg_index": 1, "leg_count": 4, "leg_number": 2, "target": state.legs.mission.waypoints[1], "next_target": state.legs.mission.waypoints[2],
        "route": state.legs.route, "samples": (), "sampled": state.sample_log.sampled, "work_left": None,
    }[old]  # fmt: skip
    with pytest.warns(DeprecationWarning, match=rf"MissionState\.{old} moved to MissionState\.{re.escape(MOVED[old])} \(0\.2\)"):
        value = getattr(state, old)
    assert (value() if old == "work_left" else value) == new
