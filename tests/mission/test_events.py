"""The mission's one event stream: each subscriber hears at the stage it declares, whoever subscribed first."""

from __future__ import annotations

import itertools

import pytest

from executive.mission.events import Announcement, MissionEvents, RouteChanged, SampleTaken, Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.world.state import SampleRecord


def test_subscribers_hear_by_stage_in_every_order_of_subscription() -> None:
    stages = [Stage.OBSERVER, Stage.RECORDING, Stage.TREE, Stage.GROUND_STATION, Stage.ROUTE_KEEPER]
    for order in itertools.permutations(stages):
        events, heard = MissionEvents(), []
        for stage in order:
            events.subscribe(Announcement, lambda text, warning, stage=stage, heard=heard: heard.append(stage), stage)
        events.tell(Announcement("failsafe battery -> RTL", True))
        assert heard == sorted(stages)


def test_a_stage_holds_one_subscriber_of_a_kind_but_recordings_and_observers_are_many() -> None:
    events = MissionEvents()
    events.subscribe(Transition, lambda *e: None, Stage.GROUND_STATION)
    with pytest.raises(ValueError, match="Transition at stage GROUND_STATION already has a subscriber"):
        events.subscribe(Transition, lambda *e: None, Stage.GROUND_STATION)
    events.subscribe(SampleTaken, lambda *e: None, Stage.GROUND_STATION)  # another kind
    for _ in range(2):  # recordings and observers only take note: any number
        events.subscribe(Transition, lambda *e: None, Stage.RECORDING)
        events.subscribe(Transition, lambda *e: None)


def test_the_lifecycle_tells_each_change_once_as_its_kind_of_event(square_mission) -> None:
    state, heard = MissionState(), []
    state.events.subscribe(Transition, lambda before, after, reason: heard.append(("transition", before, after)))
    state.events.subscribe(RouteChanged, lambda route, reason: heard.append(("route", len(route.waypoints), route.current)))
    state.events.subscribe(SampleTaken, lambda sample: heard.append(("sample", sample.leg_index)))
    state.events.subscribe(Announcement, lambda text, warning: heard.append(("announce", text)))
    state.upload(square_mission)
    state.start()
    state.set_route(square_mission.waypoints[:3], "operator", leg_index=1)
    state.record_sample(SampleRecord(leg_index=1, lat=0.0, lon=0.0, started=0.0, finished=1.0, reads=()))
    state.announce("failsafe cleared")
    S = MissionStatus
    assert heard == [
        ("transition", S.IDLE, S.READY),
        ("transition", S.READY, S.RUNNING),
        ("route", 3, 1),
        ("sample", 1),
        ("announce", "failsafe cleared"),
    ]
