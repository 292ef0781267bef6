"""Hot reload against the simulated autopilot: a paused mission replaced, held until resumed, completed on the new route; journalled."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
import yaml

from executive.io.mavlink.mission_protocol import route_not_on_autopilot
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.observers.journal import Journal, journal_recorder
from executive.testing import Lockstep
from executive.world import blackboard, geo
from executive.world.clock import Clock
from tests.tests_support import LINE_HOME, line_mission

#: 25 m east of the line's second waypoint, and of its fourth.
EAST_2 = {"lat": LINE_HOME[0] + 0.0002248 * 2, "lon": LINE_HOME[1] + 0.000275}
EAST_4 = {"lat": LINE_HOME[0] + 0.0002248 * 4, "lon": LINE_HOME[1] + 0.000275}
SAMPLING = {"duration_s": 2, "rate_hz": 1, "sensors": ["temperature"]}


def text(mission: Mission, **fields: Any) -> str:
    return yaml.safe_dump({**mission.model_dump(mode="json", exclude_none=True), **fields}, sort_keys=False)


def points(mission: Mission) -> list[dict[str, Any]]:
    return [wp.model_dump(mode="json", exclude_none=True) for wp in mission.waypoints]


class Track:
    """Each step of the world: where the vehicle is, and its mode, as the runtime last heard them."""

    def __init__(self) -> None:
        self._bb = blackboard.reader("test track", ["/vehicle/position", "/vehicle/mode"])
        self.fixes: list[tuple[float, float, float, str | None]] = []

    def __call__(self, sim: Lockstep) -> None:
        position = self._bb.get("/vehicle/position")
        if position is not None:
            self.fixes.append((sim.clock.now(), position.lat, position.lon, self._bb.get("/vehicle/mode")))

    def closest(self, point: dict[str, float], since: float = 0.0) -> float:
        return min(geo.distance(lat, lon, point["lat"], point["lon"]) for t, lat, lon, _ in self.fixes if t >= since)


def pause_on_leg(sim: Lockstep, leg_index: int, hold: str = "HOLD") -> None:
    """Run until the mission heads for ``leg_index``, pause it (ctl) and run until the vehicle holds."""
    state = sim.runtime.mission_state
    assert sim.run(limit_s=300, until=lambda: state.legs.leg_index >= leg_index) is None
    assert sim.runtime.operator.request("pause", source="ctl").ok
    mode = blackboard.reader("test mode", ["/vehicle/mode"])
    assert sim.run(limit_s=30, until=lambda: mode.get("/vehicle/mode") == hold) is None


def run_for(sim: Lockstep, seconds: float) -> None:
    end = sim.clock.now() + seconds
    assert sim.run(limit_s=seconds + 1, until=lambda: sim.clock.now() >= end) is None


def test_a_paused_rover_holds_takes_the_new_route_on_resume_and_completes_on_it(lockstep):
    line = line_mission("line")
    wps = points(line)
    sim = lockstep(line)
    track = Track()
    sim.observers.append(track)
    pause_on_leg(sim, 1)
    new = text(line, name="bent", waypoints=[wps[0], wps[1], EAST_2, EAST_4])
    reply = sim.runtime.operator.request("upload", source="ctl", filename="bent.yaml", text=new)
    assert (reply.ok, reply.state) == (True, "PAUSED"), reply.reason
    assert reply.reason.startswith("mission replaced: 'line' -> 'bent', at leg 2/4 (the waypoint of old leg 2)")
    replaced_at = sim.clock.now()
    run_for(sim, 10.0)  # paused: held where it stopped, nothing commanded, while the new route goes to the autopilot
    held = [fix for fix in track.fixes if fix[0] >= replaced_at]
    assert {mode for *_, mode in held} == {"HOLD"}
    stopped = [fix for fix in held if fix[0] >= replaced_at + 3.0]  # braked to a stop by then
    assert geo.distance(stopped[0][1], stopped[0][2], stopped[-1][1], stopped[-1][2]) < 0.1
    state = sim.runtime.mission_state
    assert (state.status, state.mission.name, state.legs.leg_index) == (MissionStatus.PAUSED, "bent", 1)
    items = blackboard.reader("test items", ["/vehicle/mission_items"]).get("/vehicle/mission_items")
    assert route_not_on_autopilot(state.legs.route.waypoints, items) is None  # uploaded and read back before the resume
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert track.closest(EAST_2, since=replaced_at) < 3.0  # driven through toward the next (10 Hz fixes)
    assert track.closest(EAST_4, since=replaced_at) < 1.5
    assert track.closest(wps[3], since=replaced_at) > 20.0  # the old line's end was never driven to


@pytest.mark.parametrize("paused_by", ["ctl", "the person"])
def test_a_person_who_has_the_vehicle_keeps_it_through_a_reload(lockstep, paused_by):
    line = line_mission("line")
    sim = lockstep(line)
    track = Track()
    sim.observers.append(track)
    state = sim.runtime.mission_state
    if paused_by == "ctl":
        pause_on_leg(sim, 1)  # held in HOLD, then a person takes the rover while paused
    else:
        assert sim.run(limit_s=300, until=lambda: state.legs.leg_index >= 1) is None
    sim.autopilot.set_mode(0)  # a ground station puts the rover in MANUAL (ArduRover mode 0)
    run_for(sim, 2.0)
    assert state.status is MissionStatus.PAUSED  # by ctl, or at once by the person's mode change
    wps = points(line)
    assert sim.runtime.operator.request("upload", source="ctl", filename="bent.yaml", text=text(line, waypoints=[*wps[:2], EAST_2])).ok
    replaced_at = sim.clock.now()
    run_for(sim, 10.0)
    assert {mode for t, *_, mode in track.fixes if t >= replaced_at} == {"MANUAL"}  # nothing commanded: the person keeps it
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED and track.closest(EAST_2, since=replaced_at) < 1.5


def test_an_incompatible_mission_is_refused_and_the_old_one_completes_unchanged(lockstep):
    line = line_mission("line", waypoints=line_mission("line").waypoints[:2])  # paused on its second leg, as the others
    sim = lockstep(line)
    pause_on_leg(sim, 1)
    reply = sim.runtime.operator.request("upload", source="ctl", filename="px4.yaml", text=text(line, name="px4", autopilot="px4"))
    assert (reply.ok, reply.state) == (False, "PAUSED")
    assert reply.reason == "px4.yaml: cannot replace 'line': autopilot: the vehicle runs ardupilot, the mission is for px4"
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED
    assert sim.runtime.mission_state.mission is line


def sampling_line(name: str, samples_at: tuple[int, ...] = (1, 3)) -> Mission:
    """The line, driven by a boat that samples at waypoints 2 and 4 (0-based ``samples_at``)."""
    line = line_mission(name, vehicle="boat", tree="goto_sample", sampling=SAMPLING)
    wps = [{**wp, "sample": i in samples_at} for i, wp in enumerate(points(line))]
    return line_mission(name, vehicle="boat", tree="goto_sample", sampling=SAMPLING, waypoints=wps)


def test_a_sample_taken_is_kept_at_its_place_and_never_taken_again(lockstep):
    boat = sampling_line("boat-line")
    wps = points(boat)
    sim = lockstep(boat)
    pause_on_leg(sim, 2, hold="LOITER")  # waypoint 2 sampled, heading for 3
    (taken,) = sim.runtime.mission_state.sample_log.taken
    # waypoint 2 first now (its sample kept, renumbered), then 3 (headed for), a new sample point east, 4 (a sample point)
    new = text(boat, name="boat-more", waypoints=[wps[1], wps[2], {**EAST_4, "sample": True}, wps[3]])
    reply = sim.runtime.operator.request("upload", source="ctl", filename="more.yaml", text=new)
    assert reply.ok and "at leg 2/4 (the waypoint of old leg 3); 1 sample kept (leg 1)" in reply.reason
    assert sim.runtime.operator.request("resume", source="ctl").ok
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    samples = sim.runtime.mission_state.sample_log.taken
    assert [s.leg_index for s in samples] == [0, 2, 3]
    assert (samples[0].started, samples[0].reads) == (taken.started, taken.reads)  # the one taken before, not again


def test_a_crash_after_a_reload_resumes_on_the_new_mission_at_its_leg(tmp_path: Path, lockstep):
    db = tmp_path / "journal.db"
    boat = sampling_line("boat-line")
    wps = points(boat)
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, Any]:
        journals.append(Journal(db, clock))
        return {"plugs": [journal_recorder(journals[-1])]}

    first = lockstep(boat, options_for_clock=journal_plug)
    pause_on_leg(first, 2, hold="LOITER")
    new = text(boat, name="boat-east", waypoints=[wps[1], wps[2], {**EAST_4, "sample": True}])
    assert first.runtime.operator.request("upload", source="ctl", filename="east.yaml", text=new).ok
    run_for(first, 1.0)  # then the crash: kill -9, never ticked again

    resume = journals[0].resume_point(boat)  # `executive run boat-line.yaml --resume`: the file it started with
    assert resume is not None and resume.mission is not None
    assert (resume.run, resume.mission.name, resume.leg_index, [s.leg_index for s in resume.samples]) == (2, "boat-east", 1, [0])
    assert journals[0].resume_point(resume.mission) == replace(resume, mission=None)  # or the new mission's file: that very mission
    second = lockstep(resume.mission, options_for_clock=journal_plug)
    outcome = second.run(limit_s=300, resume=resume)
    assert outcome is not None and outcome.status is MissionStatus.COMPLETED, outcome
    assert [s.leg_index for s in second.runtime.mission_state.sample_log.taken] == [0, 2]

    replaced, continued, resumed = (journals[1].report(run) for run in (1, 2, 3))
    reload_event = [e["text"] for e in replaced["events"] if e["kind"] == "mission"]
    assert len(reload_event) == 1 and reload_event[0].startswith("mission replaced: 'boat-line' -> 'boat-east', at leg 2/3")
    assert (replaced["outcome"], replaced["reason"]) == ("REPLACED", reload_event[0])
    assert (continued["mission"], continued["resumed_from"], continued["outcome"]) == ("boat-east", 1, None)
    assert [e["text"] for e in continued["events"] if e["kind"] == "mission"] == reload_event
    assert [s["waypoint"] for s in continued["samples"]] == [1]  # carried, renumbered
    assert [leg["waypoint"] for leg in continued["legs"]] == [2]
    assert (resumed["mission"], resumed["resumed_from"], resumed["outcome"]) == ("boat-east", 2, "COMPLETED")
    assert [s["waypoint"] for s in resumed["samples"]] == [3]  # the new point only: waypoint 2 never sampled again
    assert journals[1].resume_point(boat) is None  # finished
    for journal in journals:
        journal.close()
