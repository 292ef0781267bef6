"""The route keeper, tick by tick against a scripted ArduPilot mission store: one upload per edit, read back, retried, the home set."""

from __future__ import annotations

import logging
from collections.abc import Callable

import py_trees
import pytest

from executive.autopilot_link.route_keeper import RouteKeeper, RouteUpload, RouteUploadState
from executive.behaviours import KeepRouteOnAutopilot
from executive.io.mavlink.mission_protocol import TransferState
from executive.mission.lifecycle import MissionState
from executive.mission.model import Home, Mission
from executive.mission.route import offset
from executive.testing import Harness, MissionAutopilot, ack
from executive.world import geo
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.state import HomePosition

_M = mavlink
AUTOPILOT_HOME = (47.397742, 8.545594, 488.0)


class Autopilot(MissionAutopilot):
    """ArduPilot's mission store behind a link: what the executive sends in a tick is answered at the next one, as over a real link."""

    def __init__(self, h: Harness) -> None:
        self.home_result = _M.MAV_RESULT_ACCEPTED
        self.sent: list[MAVLinkMessage] = []  # everything the executive sent
        self.homes_set: list[tuple[float, float, float]] = []
        super().__init__(h, AUTOPILOT_HOME[:2], mode="GUIDED")
        h.vehicle.set(vehicle__home=HomePosition(*AUTOPILOT_HOME, h.clock.now()))

    def publish(self) -> None:
        """Nothing: the tests write the vehicle's facts themselves."""

    def acknowledge(self, command: int, result: int) -> None:
        self.replies.append(ack(command, result))

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        if msg.get_type() == "COMMAND_INT" and msg.command == _M.MAV_CMD_DO_SET_HOME:
            if self.home_result == _M.MAV_RESULT_ACCEPTED:
                self.homes_set.append((msg.x / 1e7, msg.y / 1e7, msg.z))
                self.home = (msg.x / 1e7, msg.y / 1e7)
            return self.home_result
        return super().on_command(msg)

    def respond(self) -> None:
        """What the executive sent this tick (its replies delivered at the next)."""
        for msg in self.h.link.take():
            self.sent.append(msg)
            self.answer(msg)
        self.store.update()

    def count(self, kind: str) -> int:
        return sum(1 for msg in self.sent if msg.get_type() == kind)

    def holds(self, state: MissionState) -> bool:
        """The store holds the mission state's route (to its 1e-7 degree)."""
        held = [x for point in self.held() for x in point]
        return held == pytest.approx([x for wp in state.legs.route.waypoints for x in (wp.lat, wp.lon)], abs=1.5e-7)


class Keeping:
    """A route keeper in the runtime's order on the kit's Harness: the autopilot's replies read, (an operator's edit), the tree, the keeper,
    the flushes; then the autopilot takes what was sent."""

    def __init__(self, mission: Mission, tree: py_trees.behaviour.Behaviour | None) -> None:
        self.h = Harness.build(mission, root=tree or py_trees.behaviours.Running("No tree"), transfer=True)
        self.state, self.transfer = self.h.mission_state, self.h.transfer
        self.keeper = RouteKeeper(self.state, self.transfer, self.h.commander, self.h.clock, attempts=3, retry_s=2.0)
        self.autopilot = Autopilot(self.h)
        self._edit: Callable[[], None] | None = None
        self.h.readers += [self.autopilot.deliver, lambda: self._edit and self._edit()]
        self.h.writers.append(self.keeper.service)
        self.seen: list[RouteUpload] = []

    def tick(self, edit: Callable[[], None] | None = None) -> RouteUpload | None:
        self._edit = edit
        self.h.tick()
        self.autopilot.respond()
        status = self.keeper.status
        if status is not None and (not self.seen or status != self.seen[-1]):
            self.seen.append(status)
        return status

    def until(self, done: Callable[[RouteUpload | None], bool], limit: int = 600) -> RouteUpload:
        for _ in range(limit):
            status = self.tick()
            if done(status):
                assert status is not None
                return status
        raise AssertionError(f"not done after {limit} ticks: {self.keeper.status}")

    def offset_edit(self, distance_m: float = 5.0) -> None:
        new = offset(self.state.legs.route, distance_m, 90.0)
        self.state.set_route(new.waypoints, f"test: offset {distance_m:g} m")


def ended(status: RouteUpload | None) -> bool:
    return status is not None and status.state is not RouteUploadState.UPLOADING


@pytest.fixture
def keeping(square_mission) -> Keeping:
    return Keeping(square_mission, None)


def test_with_drive_auto_an_edit_gives_the_autopilot_only_the_horizon(square_mission: Mission) -> None:
    """drive: auto: the autopilot never holds more than the current leg's waypoint and limits.auto_horizon_legs beyond it."""
    mission = square_mission.model_copy(update={"drive": "auto", "limits": square_mission.limits.model_copy(update={"auto_horizon_legs": 1})})
    keeping = Keeping(mission, None)
    keeping.state.continue_from(1)
    keeping.tick(keeping.offset_edit)
    done = keeping.until(ended)
    assert (done.state, done.detail) == (RouteUploadState.DONE, "the horizon of leg 2 (drive: auto), read back")
    edited = keeping.state.legs.route.waypoints
    held = [x for point in keeping.autopilot.held() for x in point]
    assert held == pytest.approx([x for wp in edited[:3] for x in (wp.lat, wp.lon)], abs=1.5e-7)  # legs 1-2, and one beyond


def test_an_edit_is_uploaded_once_read_back_and_reported(keeping: Keeping, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive.autopilot_link.route_keeper")
    keeping.tick()
    assert keeping.keeper.status is None and keeping.autopilot.sent == []  # nothing to do without an edit
    keeping.tick(keeping.offset_edit)
    done = keeping.until(ended)
    assert (done.state, done.attempt, done.waypoints, done.edit) == (RouteUploadState.DONE, 1, 4, "test: offset 5 m")
    assert done.detail == "4 waypoints, read back"
    assert keeping.autopilot.holds(keeping.state)
    assert (keeping.autopilot.count("MISSION_COUNT"), keeping.autopilot.count("MISSION_REQUEST_LIST")) == (1, 1)  # one upload, one read-back
    assert [s.state for s in keeping.seen] == [RouteUploadState.UPLOADING] * (len(keeping.seen) - 1) + [RouteUploadState.DONE]
    assert "route on the autopilot: 4 waypoints, read back (test: offset 5 m)" in caplog.messages
    assert keeping.autopilot.homes_set == []  # the home did not move
    for _ in range(30):
        keeping.tick()
    assert keeping.autopilot.count("MISSION_COUNT") == 1  # and nothing more


def test_a_failed_upload_is_tried_again_and_given_up_after_the_last_attempt(keeping: Keeping, caplog) -> None:
    keeping.autopilot.answers_missions = False
    keeping.tick(keeping.offset_edit)
    failed = keeping.until(ended)
    assert (failed.state, failed.attempt) == (RouteUploadState.FAILED, 3)
    assert failed.detail == "not on the autopilot after 3 uploads: no MISSION_REQUEST for item 0 after 5 retries"
    assert keeping.autopilot.count("MISSION_COUNT") == 3 * 6  # three uploads, each sent once and resent five times
    assert any("route not on the autopilot" in m for m in caplog.messages)
    assert any(s.detail.startswith("upload 1 failed (no MISSION_REQUEST for item 0 after 5 retries); again in") for s in keeping.seen)


def test_an_autopilot_that_answers_again_gets_the_route_on_the_next_attempt(keeping: Keeping) -> None:
    keeping.autopilot.answers_missions = False
    keeping.tick(keeping.offset_edit)
    keeping.until(lambda s: s is not None and s.attempt == 2)
    keeping.autopilot.answers_missions = True
    done = keeping.until(ended)
    assert (done.state, done.attempt) == (RouteUploadState.DONE, 2)
    assert keeping.autopilot.holds(keeping.state)


def test_a_newer_edit_replaces_the_upload_in_progress(keeping: Keeping) -> None:
    keeping.tick(keeping.offset_edit)
    keeping.tick()
    assert keeping.transfer.status is not None and keeping.transfer.status.state is TransferState.IN_PROGRESS
    keeping.tick(lambda: keeping.offset_edit(10.0))
    done = keeping.until(ended)
    assert (done.state, done.attempt, done.edit) == (RouteUploadState.DONE, 1, "test: offset 10 m")
    assert keeping.autopilot.holds(keeping.state)
    assert keeping.autopilot.count("MISSION_REQUEST_LIST") == 1  # only the newer one was read back
    assert all(s.state is not RouteUploadState.FAILED for s in keeping.seen)


def test_another_components_transfer_is_waited_for_not_superseded(keeping: Keeping) -> None:
    download = keeping.transfer.download()
    keeping.tick(keeping.offset_edit)
    assert keeping.keeper.status is not None and keeping.keeper.status.detail == "waiting for another mission transfer to end"
    done = keeping.until(ended)
    assert done.state is RouteUploadState.DONE
    assert keeping.autopilot.count("MISSION_COUNT") == 1 and keeping.autopilot.count("MISSION_REQUEST_LIST") == 2  # the download, our read-back
    assert download != keeping.transfer.status.ticket  # type: ignore[union-attr]


def test_an_edit_the_autopilot_already_holds_is_not_uploaded_again(keeping: Keeping) -> None:
    keeping.tick(keeping.offset_edit)
    keeping.until(ended)
    keeping.tick(lambda: keeping.state.set_route(keeping.state.legs.route.waypoints, "test: the same again"))
    done = keeping.until(ended)
    assert (done.state, done.attempt, done.detail) == (RouteUploadState.DONE, 0, "4 waypoints, already held")
    assert keeping.autopilot.count("MISSION_COUNT") == 1


def test_set_home_sets_the_autopilot_home_keeping_its_altitude(keeping: Keeping) -> None:
    home = Home(lat=47.3978, lon=8.5457)
    keeping.tick(lambda: keeping.state.set_route(keeping.state.legs.route.waypoints, "test: set home", home=home))
    done = keeping.until(ended)
    assert (done.state, done.detail) == (RouteUploadState.DONE, "4 waypoints, read back; home set")
    [(lat, lon, alt)] = keeping.autopilot.homes_set
    assert geo.distance(lat, lon, home.lat, home.lon) < 0.02 and alt == AUTOPILOT_HOME[2]


def test_a_refused_home_fails_the_edit_with_the_reason(keeping: Keeping) -> None:
    keeping.autopilot.home_result = _M.MAV_RESULT_DENIED
    keeping.tick(lambda: keeping.state.set_route(keeping.state.legs.route.waypoints, "test: set home", home=Home(lat=47.3978, lon=8.5457)))
    done = keeping.until(ended)
    assert done.state is RouteUploadState.FAILED
    assert done.detail == "4 waypoints, read back, but the home was not set: DO_SET_HOME rejected (MAV_RESULT_DENIED)"


def test_another_missions_home_is_not_an_edit(keeping: Keeping, square_mission: Mission) -> None:
    keeping.state.abort("test")
    keeping.state.upload(square_mission.model_copy(update={"home": Home(lat=47.3975, lon=8.5450)}))
    keeping.state.start()
    keeping.tick(keeping.offset_edit)
    assert keeping.until(ended).state is RouteUploadState.DONE
    assert keeping.autopilot.homes_set == []


# -- with the ugv_rc_route tree, which keeps the route on the autopilot too ------------------------


@pytest.fixture
def ugv_keeping() -> Keeping:
    mission = Mission.model_validate(
        {"version": 1, "name": "rc", "vehicle": "rover", "tree": "ugv_rc_route", "waypoints": [{"lat": 47.3978, "lon": 8.5456}]}
    )
    return Keeping(mission, KeepRouteOnAutopilot())


def tree_feedback(keeping: Keeping) -> str:
    return keeping.h.root.feedback_message


def test_with_the_rc_route_tree_an_edit_is_uploaded_once(ugv_keeping: Keeping) -> None:
    keeping = ugv_keeping
    for _ in range(10):
        keeping.tick()
    assert keeping.autopilot.count("MISSION_COUNT") == 1  # the tree's own upload of the route it starts with
    assert tree_feedback(keeping) == "the autopilot holds the route: 1 waypoints, read back"
    keeping.tick(keeping.offset_edit)
    assert tree_feedback(keeping) == "waiting for another mission transfer to end"  # the keeper started first
    assert keeping.until(ended).state is RouteUploadState.DONE
    keeping.tick()
    assert tree_feedback(keeping) == "the autopilot holds the route: 1 waypoints, read back"
    assert keeping.autopilot.count("MISSION_COUNT") == 2


def test_with_the_rc_route_tree_an_edit_during_the_trees_upload_waits_for_it(ugv_keeping: Keeping) -> None:
    keeping = ugv_keeping
    keeping.tick()
    assert keeping.transfer.status is not None and keeping.transfer.status.state is TransferState.IN_PROGRESS  # the tree's upload
    keeping.tick(keeping.offset_edit)
    assert keeping.keeper.status is not None and keeping.keeper.status.detail == "waiting for another mission transfer to end"
    done = keeping.until(ended)
    assert done.state is RouteUploadState.DONE
    assert keeping.autopilot.count("MISSION_COUNT") == 2  # the tree's first upload (not cut short) and one of the edit
    assert keeping.autopilot.holds(keeping.state)
