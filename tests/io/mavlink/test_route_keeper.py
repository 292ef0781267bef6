"""The route keeper, tick by tick against a scripted ArduPilot mission store: one upload per edit, read back, retried, the home set."""

from __future__ import annotations

import logging
from collections.abc import Callable

import py_trees
import pytest

from executive import geo
from executive.behaviours import KeepRouteOnAutopilot
from executive.clock import ManualClock
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink
from executive.io.mavlink.mission_protocol import MissionTransfer, TransferState
from executive.io.mavlink.modes import ModeTable
from executive.io.mavlink.route_keeper import RouteKeeper, RouteUpload, RouteUploadState
from executive.mission.lifecycle import MissionState
from executive.mission.model import Home, Mission
from executive.mission.route import offset
from executive.sim.mission_store import MissionStore
from executive.state import HomePosition
from executive.testing import ScriptedAutopilot, ack, port_for

_M = mavlink
_EXECUTIVE = mavlink.MAVLink(None, srcSystem=1, srcComponent=EXECUTIVE_COMPONENT)
AUTOPILOT_HOME = (47.397742, 8.545594, 488.0)


def wire(msg: MAVLinkMessage) -> MAVLinkMessage:
    """As the autopilot receives it: packed by the executive, decoded."""
    return mavlink.MAVLink(None).decode(bytearray(msg.pack(_EXECUTIVE)))


class Autopilot(ScriptedAutopilot):
    """ArduPilot's mission store behind a link: what the executive sends in a tick is answered at the next one, as over a real link."""

    def __init__(self, clock: ManualClock, link, commander: Commander, transfer: MissionTransfer, vehicle) -> None:
        self.clock, self.link, self.commander, self.transfer = clock, link, commander, transfer
        self.system_id = self.component_id = 1
        self.home: tuple[float, float] | None = AUTOPILOT_HOME[:2]
        self.answers = True  # False: the mission protocol goes unanswered (a link that lost it)
        self.home_result = _M.MAV_RESULT_ACCEPTED
        self._replies: list[MAVLinkMessage] = []  # sent at the next tick
        self.store = MissionStore(self, self._replies.append, lambda severity, text: None)
        self.sent: list[MAVLinkMessage] = []  # everything the executive sent
        self.homes_set: list[tuple[float, float, float]] = []
        super().__init__(None, AUTOPILOT_HOME[:2], mode="GUIDED")
        vehicle.set(vehicle__home=HomePosition(*AUTOPILOT_HOME, clock.now()))

    @property
    def modes(self) -> ModeTable:
        return self.commander.modes

    @property
    def guided_mode(self) -> str:
        return self.commander.profile.guided_mode

    def publish(self) -> None:
        """Nothing: the tests write the vehicle's facts themselves."""

    def acknowledge(self, command: int, result: int) -> None:
        self._replies.append(ack(command, result))

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        if msg.get_type() == "COMMAND_INT" and msg.command == _M.MAV_CMD_DO_SET_HOME:
            if self.home_result == _M.MAV_RESULT_ACCEPTED:
                self.homes_set.append((msg.x / 1e7, msg.y / 1e7, msg.z))
                self.home = (msg.x / 1e7, msg.y / 1e7)
            return self.home_result
        return super().on_command(msg)

    def on_message(self, msg: MAVLinkMessage) -> None:
        if msg.get_type() in MissionStore.MESSAGES and self.answers:
            self.store.handle(wire(msg))

    def deliver(self) -> None:
        """The replies of the last tick reach the executive (the reader's part)."""
        handlers = {
            "MISSION_REQUEST": self.transfer.on_request, "MISSION_REQUEST_INT": self.transfer.on_request, "MISSION_ACK": self.transfer.on_ack,
            "MISSION_COUNT": self.transfer.on_count, "MISSION_ITEM_INT": self.transfer.on_item, "MISSION_CURRENT": self.transfer.on_current,
        }  # fmt: skip
        replies = list(self._replies)
        self._replies.clear()
        for msg in replies:
            if msg.get_type() == "COMMAND_ACK":
                self.commander.on_ack(msg)
            else:
                handlers[msg.get_type()](msg, self.clock.now())

    def receive(self) -> None:
        """What the executive sent this tick."""
        for msg in self.link.take():
            self.sent.append(msg)
            self.answer(msg)
        self.store.update()

    def count(self, kind: str) -> int:
        return sum(1 for msg in self.sent if msg.get_type() == kind)

    def holds(self, state: MissionState) -> bool:
        """The store holds the mission state's route (to its 1e-7 degree)."""
        held = [x for seq in range(1, self.store.count) for x in (self.store.command(seq).lat, self.store.command(seq).lon)]
        return held == pytest.approx([x for wp in state.route.waypoints for x in (wp.lat, wp.lon)], abs=1.5e-7)


class Rig:
    """The runtime's order each tick: drain the link, (an operator's edit), the tree, the keeper, flush; the autopilot answers."""

    def __init__(self, mission: Mission, clock: ManualClock, link, commander: Commander, vehicle, tree: py_trees.behaviour.Behaviour | None) -> None:
        self.clock = clock
        self.transfer = MissionTransfer(link, clock)
        self.commander = commander
        self.state = MissionState()
        self.keeper = RouteKeeper(self.state, self.transfer, commander, clock, attempts=3, retry_s=2.0)
        self.state.upload(mission)
        self.state.start()
        self.autopilot = Autopilot(clock, link, commander, self.transfer, vehicle)
        self.tree = None
        if tree is not None:
            self.tree = py_trees.trees.BehaviourTree(tree)
            self.tree.setup(clock=clock, autopilot=port_for(commander, self.transfer), mission_state=self.state)
        self.seen: list[RouteUpload] = []

    def tick(self, edit: Callable[[], None] | None = None) -> RouteUpload | None:
        self.clock.advance(0.1)
        self.autopilot.deliver()
        if edit is not None:
            edit()
        if self.tree is not None:
            self.tree.tick()
        self.keeper.service()
        self.commander.flush()
        self.transfer.flush()
        self.autopilot.receive()
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
        new = offset(self.state.route, distance_m, 90.0)
        self.state.set_route(new.waypoints, f"test: offset {distance_m:g} m")


def ended(status: RouteUpload | None) -> bool:
    return status is not None and status.state is not RouteUploadState.UPLOADING


@pytest.fixture
def rig(square_mission, clock, link, commander, vehicle) -> Rig:
    return Rig(square_mission, clock, link, commander, vehicle, None)


def test_an_edit_is_uploaded_once_read_back_and_reported(rig: Rig, caplog) -> None:
    caplog.set_level(logging.INFO, logger="executive.io.mavlink.route_keeper")
    rig.tick()
    assert rig.keeper.status is None and rig.autopilot.sent == []  # nothing to do without an edit
    rig.tick(rig.offset_edit)
    done = rig.until(ended)
    assert (done.state, done.attempt, done.waypoints, done.edit) == (RouteUploadState.DONE, 1, 4, "test: offset 5 m")
    assert done.detail == "4 waypoints, read back"
    assert rig.autopilot.holds(rig.state)
    assert (rig.autopilot.count("MISSION_COUNT"), rig.autopilot.count("MISSION_REQUEST_LIST")) == (1, 1)  # one upload, one read-back
    assert [s.state for s in rig.seen] == [RouteUploadState.UPLOADING] * (len(rig.seen) - 1) + [RouteUploadState.DONE]
    assert "route on the autopilot: 4 waypoints, read back (test: offset 5 m)" in caplog.messages
    assert rig.autopilot.homes_set == []  # the home did not move
    for _ in range(30):
        rig.tick()
    assert rig.autopilot.count("MISSION_COUNT") == 1  # and nothing more


def test_a_failed_upload_is_tried_again_and_given_up_after_the_last_attempt(rig: Rig, caplog) -> None:
    rig.autopilot.answers = False
    rig.tick(rig.offset_edit)
    failed = rig.until(ended)
    assert (failed.state, failed.attempt) == (RouteUploadState.FAILED, 3)
    assert failed.detail == "not on the autopilot after 3 uploads: no MISSION_REQUEST for item 0 after 5 retries"
    assert rig.autopilot.count("MISSION_COUNT") == 3 * 6  # three uploads, each sent once and resent five times
    assert any("route not on the autopilot" in m for m in caplog.messages)
    assert any(s.detail.startswith("upload 1 failed (no MISSION_REQUEST for item 0 after 5 retries); again in") for s in rig.seen)


def test_an_autopilot_that_answers_again_gets_the_route_on_the_next_attempt(rig: Rig) -> None:
    rig.autopilot.answers = False
    rig.tick(rig.offset_edit)
    rig.until(lambda s: s is not None and s.attempt == 2)
    rig.autopilot.answers = True
    done = rig.until(ended)
    assert (done.state, done.attempt) == (RouteUploadState.DONE, 2)
    assert rig.autopilot.holds(rig.state)


def test_a_newer_edit_replaces_the_upload_in_progress(rig: Rig) -> None:
    rig.tick(rig.offset_edit)
    rig.tick()
    assert rig.transfer.status is not None and rig.transfer.status.state is TransferState.IN_PROGRESS
    rig.tick(lambda: rig.offset_edit(10.0))
    done = rig.until(ended)
    assert (done.state, done.attempt, done.edit) == (RouteUploadState.DONE, 1, "test: offset 10 m")
    assert rig.autopilot.holds(rig.state)
    assert rig.autopilot.count("MISSION_REQUEST_LIST") == 1  # only the newer one was read back
    assert all(s.state is not RouteUploadState.FAILED for s in rig.seen)


def test_another_components_transfer_is_waited_for_not_superseded(rig: Rig) -> None:
    download = rig.transfer.download()
    rig.tick(rig.offset_edit)
    assert rig.keeper.status is not None and rig.keeper.status.detail == "waiting for another mission transfer to end"
    done = rig.until(ended)
    assert done.state is RouteUploadState.DONE
    assert rig.autopilot.count("MISSION_COUNT") == 1 and rig.autopilot.count("MISSION_REQUEST_LIST") == 2  # the download, our read-back
    assert download != rig.transfer.status.ticket  # type: ignore[union-attr]


def test_an_edit_the_autopilot_already_holds_is_not_uploaded_again(rig: Rig) -> None:
    rig.tick(rig.offset_edit)
    rig.until(ended)
    rig.tick(lambda: rig.state.set_route(rig.state.route.waypoints, "test: the same again"))
    done = rig.until(ended)
    assert (done.state, done.attempt, done.detail) == (RouteUploadState.DONE, 0, "4 waypoints, already held")
    assert rig.autopilot.count("MISSION_COUNT") == 1


def test_set_home_sets_the_autopilot_home_keeping_its_altitude(rig: Rig) -> None:
    home = Home(lat=47.3978, lon=8.5457)
    rig.tick(lambda: rig.state.set_route(rig.state.route.waypoints, "test: set home", home=home))
    done = rig.until(ended)
    assert (done.state, done.detail) == (RouteUploadState.DONE, "4 waypoints, read back; home set")
    [(lat, lon, alt)] = rig.autopilot.homes_set
    assert geo.distance(lat, lon, home.lat, home.lon) < 0.02 and alt == AUTOPILOT_HOME[2]


def test_a_refused_home_fails_the_edit_with_the_reason(rig: Rig) -> None:
    rig.autopilot.home_result = _M.MAV_RESULT_DENIED
    rig.tick(lambda: rig.state.set_route(rig.state.route.waypoints, "test: set home", home=Home(lat=47.3978, lon=8.5457)))
    done = rig.until(ended)
    assert done.state is RouteUploadState.FAILED
    assert done.detail == "4 waypoints, read back, but the home was not set: DO_SET_HOME rejected (MAV_RESULT_DENIED)"


def test_another_missions_home_is_not_an_edit(rig: Rig, square_mission: Mission) -> None:
    rig.state.abort("test")
    rig.state.upload(square_mission.model_copy(update={"home": Home(lat=47.0, lon=8.0)}))
    rig.state.start()
    rig.tick(rig.offset_edit)
    assert rig.until(ended).state is RouteUploadState.DONE
    assert rig.autopilot.homes_set == []


# -- with the ugv_rc_route tree, which keeps the route on the autopilot too ------------------------


@pytest.fixture
def ugv_rig(clock, link, commander, vehicle) -> Rig:
    mission = Mission.model_validate(
        {"version": 1, "name": "rc", "vehicle": "rover", "tree": "ugv_rc_route", "waypoints": [{"lat": 47.3978, "lon": 8.5456}]}
    )
    return Rig(mission, clock, link, commander, vehicle, KeepRouteOnAutopilot())


def tree_feedback(rig: Rig) -> str:
    assert rig.tree is not None
    return rig.tree.root.feedback_message


def test_with_the_rc_route_tree_an_edit_is_uploaded_once(ugv_rig: Rig) -> None:
    rig = ugv_rig
    for _ in range(10):
        rig.tick()
    assert rig.autopilot.count("MISSION_COUNT") == 1  # the tree's own upload of the route it starts with
    assert tree_feedback(rig) == "the autopilot holds the route: 1 waypoints, read back"
    rig.tick(rig.offset_edit)
    assert tree_feedback(rig) == "waiting for another mission transfer to end"  # the keeper started first
    assert rig.until(ended).state is RouteUploadState.DONE
    rig.tick()
    assert tree_feedback(rig) == "the autopilot holds the route: 1 waypoints, read back"
    assert rig.autopilot.count("MISSION_COUNT") == 2


def test_with_the_rc_route_tree_an_edit_during_the_trees_upload_waits_for_it(ugv_rig: Rig) -> None:
    rig = ugv_rig
    rig.tick()
    assert rig.transfer.status is not None and rig.transfer.status.state is TransferState.IN_PROGRESS  # the tree's upload
    rig.tick(rig.offset_edit)
    assert rig.keeper.status is not None and rig.keeper.status.detail == "waiting for another mission transfer to end"
    done = rig.until(ended)
    assert done.state is RouteUploadState.DONE
    assert rig.autopilot.count("MISSION_COUNT") == 2  # the tree's first upload (not cut short) and one of the edit
    assert rig.autopilot.holds(rig.state)
