"""The mission protocol, executive side, tick by tick: exact message sequences, retries, refusals, read-back."""

from __future__ import annotations

import math
from dataclasses import replace

import py_trees
import pytest

from executive.io.mavlink.mission_protocol import (
    MissionCurrent,
    MissionItem,
    MissionItemReached,
    MissionTransfer,
    MissionTransferStatus,
    TransferOperation,
    TransferState,
    first_mismatch,
    route_items,
    route_not_on_autopilot,
    waypoint_items,
)
from executive.io.mavlink.reader import MavlinkReader
from executive.mission.model import Waypoint
from executive.testing import AUTOPILOT, GCS
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m

HOME = (47.397742, 8.545594)
POINTS = [(47.3979220, 8.5455940, 0.0), (47.3979220, 8.5458600, 2.5)]
ITEMS = waypoint_items(POINTS)
US = (1, 191)  # what the autopilot addresses its replies to
FLOAT_FRAME = {m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: m.MAV_FRAME_GLOBAL_RELATIVE_ALT, m.MAV_FRAME_GLOBAL_INT: m.MAV_FRAME_GLOBAL}


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


def brief(messages: list[MAVLinkMessage]) -> list[tuple]:
    """(type, the field that matters) of each message sent."""
    out: list[tuple] = []
    for msg in messages:
        kind = msg.get_type()
        detail = {"MISSION_COUNT": "count", "MISSION_ACK": "type", "MISSION_WRITE_PARTIAL_LIST": "start_index"}.get(kind, "seq")
        out.append((kind, getattr(msg, detail)) if hasattr(msg, detail) else (kind,))
    return out


def held(item: MissionItem) -> MAVLinkMessage:
    """``item`` as ArduPilot sends it back: the non-INT frame, the altitude to the cm, always autocontinue."""
    frame = FLOAT_FRAME.get(item.frame, item.frame)
    return AUTOPILOT.mission_item_int(
        *US, item.seq, frame, item.command, 0, 1, item.param1, item.param2, item.param3, item.param4,
        round(item.x * 1e7), round(item.y * 1e7), int(item.z * 100) / 100, 0,
    )  # fmt: skip


def home_item(lat: float = HOME[0], lon: float = HOME[1]) -> MAVLinkMessage:
    return AUTOPILOT.mission_item_int(*US, 0, m.MAV_FRAME_GLOBAL, m.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), 0, 0)


def request(seq: int) -> MAVLinkMessage:
    return AUTOPILOT.mission_request(*US, seq, 0)  # what ArduPilot sends


def request_int(seq: int) -> MAVLinkMessage:
    return AUTOPILOT.mission_request_int(*US, seq, 0)


def ack(result: int = m.MAV_MISSION_ACCEPTED) -> MAVLinkMessage:
    return AUTOPILOT.mission_ack(*US, result, 0)


def count(n: int) -> MAVLinkMessage:
    return AUTOPILOT.mission_count(*US, n, 0)


class Exchange:
    """The executive's IO for one tick: the clock moves, the reader drains what the vehicle sent, the transfer flushes."""

    def __init__(self, link, clock, reader: MavlinkReader, transfer: MissionTransfer) -> None:
        self.link, self.clock, self.reader, self.transfer = link, clock, reader, transfer

    def tick(self, *incoming: MAVLinkMessage, dt: float = 0.1) -> list[tuple]:
        self.clock.advance(dt)
        self.link.incoming.extend(incoming)
        self.reader.drain()
        self.transfer.flush()
        return brief(self.link.take())

    @property
    def status(self) -> MissionTransferStatus:
        status = bb("/link/mission_transfer")
        assert status is self.transfer.status
        return status


@pytest.fixture
def transfer(link, clock) -> MissionTransfer:
    return MissionTransfer(link, clock, item_timeout_s=1.5, retries=3)


@pytest.fixture
def x(link, clock, commander, transfer) -> Exchange:
    reader = MavlinkReader(link, clock, commander, mission=transfer)
    link.incoming.append(AUTOPILOT.heartbeat(m.MAV_TYPE_GROUND_ROVER, m.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, 4, m.MAV_STATE_STANDBY))
    reader.drain()
    link.take()
    return Exchange(link, clock, reader, transfer)


def upload_until_last_item(x: Exchange, items=ITEMS, **options) -> int:
    ticket = x.transfer.upload(items, HOME, **options)
    assert x.tick() == [("MISSION_COUNT", len(items) + 1)]
    for seq in range(len(items) + 1):
        assert x.tick(request(seq)) == [("MISSION_ITEM_INT", seq)]
    return ticket


def test_upload_exact_sequence_with_read_back(x: Exchange, link) -> None:
    ticket = x.transfer.upload(ITEMS, HOME)
    assert link.sent == [] and x.status.state is TransferState.IN_PROGRESS  # nothing before the flush
    assert x.tick() == [("MISSION_COUNT", 3)]
    assert x.tick(request(0)) == [("MISSION_ITEM_INT", 0)]
    x.clock.advance(0.1)
    x.link.incoming.append(request_int(1))  # either kind of request gets a MISSION_ITEM_INT
    x.reader.drain()
    x.transfer.flush()
    [sent] = link.take()
    assert (sent.target_system, sent.target_component, sent.seq, sent.frame, sent.command, sent.mission_type) == (1, 1, 1, 6, 16, 0)
    assert (sent.x, sent.y, sent.z, sent.autocontinue) == (473979220, 85455940, 0.0, 1)
    assert x.tick(request(2)) == [("MISSION_ITEM_INT", 2)]
    assert (x.status.progress, x.status.total, x.status.verifying) == (2, 3, False)
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]  # the read-back
    assert x.status.verifying and x.status.state is TransferState.IN_PROGRESS
    assert x.tick(count(3)) == [("MISSION_REQUEST_INT", 0)]
    assert x.tick(home_item()) == [("MISSION_REQUEST_INT", 1)]
    assert x.tick(held(ITEMS[0])) == [("MISSION_REQUEST_INT", 2)]
    assert x.tick(held(ITEMS[1])) == [("MISSION_ACK", m.MAV_MISSION_ACCEPTED)]
    status = x.status
    assert (status.ticket, status.operation, status.state, status.progress, status.total, status.retries, status.reason) == (
        ticket, TransferOperation.UPLOAD, TransferState.DONE, 3, 3, 0, "",
    )  # fmt: skip
    assert [(i.seq, i.x, i.frame) for i in bb("/vehicle/mission_items")] == [(1, 47.397922, 3), (2, 47.397922, 3)]
    assert (bb("/vehicle/mission_home").x, bb("/vehicle/mission_home").y) == HOME
    assert x.tick(dt=10.0) == []  # done: nothing more is sent


def test_download_returns_home_apart(x: Exchange) -> None:
    x.transfer.download()
    assert x.tick() == [("MISSION_REQUEST_LIST",)]
    assert x.tick(count(3)) == [("MISSION_REQUEST_INT", 0)]
    assert x.tick(home_item(), home_item()) == [("MISSION_REQUEST_INT", 1)]  # a duplicate is dropped
    assert x.tick(held(ITEMS[0])) == [("MISSION_REQUEST_INT", 2)]
    assert x.status.progress == 2
    assert x.tick(held(ITEMS[1])) == [("MISSION_ACK", m.MAV_MISSION_ACCEPTED)]
    assert x.status.state is TransferState.DONE and x.status.operation is TransferOperation.DOWNLOAD
    assert x.transfer.home is not None and (x.transfer.home.seq, x.transfer.home.x) == (0, HOME[0])
    assert x.transfer.items == bb("/vehicle/mission_items")
    assert [(i.seq, i.y, i.z) for i in x.transfer.items] == [(1, 8.545594, 0.0), (2, 8.54586, 2.5)]
    assert bb("/vehicle/mission_home") == x.transfer.home


def test_download_of_an_empty_mission(x: Exchange) -> None:
    x.transfer.download()
    x.tick()
    assert x.tick(count(0)) == []
    assert x.status.state is TransferState.DONE
    assert (x.transfer.home, x.transfer.items, bb("/vehicle/mission_items")) == (None, (), ())


def test_clear(x: Exchange) -> None:
    x.transfer.clear()
    assert x.tick() == [("MISSION_CLEAR_ALL",)]
    assert x.tick(ack()) == []
    assert x.status.state is TransferState.DONE and bb("/vehicle/mission_items") == ()


def test_clear_refused(x: Exchange) -> None:
    x.transfer.clear()
    x.tick()
    x.tick(ack(m.MAV_MISSION_ERROR))
    assert (x.status.state, x.status.result) == (TransferState.FAILED, m.MAV_MISSION_ERROR)
    assert x.status.reason == "the vehicle refused to clear its mission: MAV_MISSION_ERROR"
    assert bb("/vehicle/mission_items") is None


def test_set_current_is_confirmed_by_mission_current(x: Exchange) -> None:
    x.transfer.set_current(2)
    assert x.tick() == [("MISSION_SET_CURRENT", 2)]
    assert x.tick(AUTOPILOT.mission_current(1, 2, m.MISSION_STATE_ACTIVE, 1)) == []  # streamed, still on item 1
    assert x.status.state is TransferState.IN_PROGRESS
    x.tick(AUTOPILOT.mission_current(2, 2, m.MISSION_STATE_ACTIVE, 1))
    assert x.status.state is TransferState.DONE
    current = bb("/vehicle/mission_current")
    assert current == MissionCurrent(2, 2, m.MISSION_STATE_ACTIVE, True, x.clock.now())


def test_a_missing_request_is_answered_by_resending_the_last_item(x: Exchange) -> None:
    x.transfer.upload(ITEMS, HOME, verify=False)
    x.tick()
    assert x.tick(request(0)) == [("MISSION_ITEM_INT", 0)]
    assert x.tick(dt=1.0) == []
    assert x.tick(dt=0.6) == [("MISSION_ITEM_INT", 0)]  # 1.5 s without a request for item 1
    assert x.status.retries == 1
    assert x.tick(request(1)) == [("MISSION_ITEM_INT", 1)]
    assert x.tick(request(2)) == [("MISSION_ITEM_INT", 2)]
    assert x.tick(ack()) == []
    assert (x.status.state, x.status.retries) == (TransferState.DONE, 1)
    assert bb("/vehicle/mission_items") == x.transfer.items and [i.seq for i in x.transfer.items] == [1, 2]


def test_gives_up_after_the_retries(x: Exchange) -> None:
    x.transfer.upload(ITEMS, HOME)
    sent = x.tick()
    for _ in range(3):
        sent += x.tick(dt=1.5)
    assert sent == [("MISSION_COUNT", 3)] * 4  # the first send and three retries
    assert x.status.state is TransferState.IN_PROGRESS
    assert x.tick(dt=1.5) == []
    assert (x.status.state, x.status.retries) == (TransferState.FAILED, 3)
    assert x.status.reason == "no MISSION_REQUEST for item 0 after 3 retries"
    assert x.tick(dt=5.0) == [] and x.transfer.idle


def test_a_lost_request_during_the_read_back_is_retried(x: Exchange) -> None:
    upload_until_last_item(x)
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]
    assert x.tick(count(3)) == [("MISSION_REQUEST_INT", 0)]
    assert x.tick(dt=1.5) == [("MISSION_REQUEST_INT", 0)]
    for _ in range(3):
        x.tick(dt=1.5)
    assert x.status.reason == "no MISSION_ITEM_INT 0 after 3 retries"


@pytest.mark.parametrize(
    ("after", "result", "reason"),
    [
        (0, m.MAV_MISSION_NO_SPACE, "the vehicle refused the upload: MAV_MISSION_NO_SPACE"),
        (2, m.MAV_MISSION_INVALID_PARAM5_X, "the vehicle refused the upload at item 1: MAV_MISSION_INVALID_PARAM5_X"),
        (1, m.MAV_MISSION_OPERATION_CANCELLED, "the vehicle refused the upload at item 0: MAV_MISSION_OPERATION_CANCELLED"),
    ],
)
def test_a_refusal_is_surfaced_by_name(x: Exchange, after: int, result: int, reason: str) -> None:
    """``after`` requests answered before the vehicle's MISSION_ACK."""
    x.transfer.upload(ITEMS, HOME)
    x.tick()
    for seq in range(after):
        x.tick(request(seq))
    x.tick(ack(result))
    assert (x.status.state, x.status.result, x.status.reason) == (TransferState.FAILED, result, reason)
    assert x.tick(dt=5.0) == []


def test_invalid_sequence_after_a_resend_is_not_fatal(x: Exchange) -> None:
    x.transfer.upload(ITEMS, HOME, verify=False)
    x.tick()
    x.tick(request(0))
    x.tick(dt=1.6)  # item 0 again: the vehicle's request for 1 was lost
    assert x.tick(ack(m.MAV_MISSION_INVALID_SEQUENCE), request(1)) == [("MISSION_ITEM_INT", 1)]
    assert x.status.state is TransferState.IN_PROGRESS
    x.tick(request(2))
    x.tick(ack())
    assert x.status.state is TransferState.DONE


def test_a_lost_final_ack_is_settled_by_the_read_back(x: Exchange) -> None:
    upload_until_last_item(x)
    assert x.tick(dt=1.6) == [("MISSION_ITEM_INT", 2)]  # no MISSION_ACK came: the last item again
    # ArduPilot, done receiving, answers an item with ERROR; only the read-back can tell
    assert x.tick(ack(m.MAV_MISSION_ERROR)) == [("MISSION_REQUEST_LIST",)]
    x.tick(count(3))
    x.tick(home_item())
    x.tick(held(ITEMS[0]))
    x.tick(held(ITEMS[1]))
    assert x.status.state is TransferState.DONE


def test_a_lost_final_ack_without_read_back_fails_saying_so(x: Exchange) -> None:
    upload_until_last_item(x, verify=False)
    x.tick(dt=1.6)
    x.tick(ack(m.MAV_MISSION_ERROR))
    assert x.status.state is TransferState.FAILED
    assert x.status.reason.startswith("the vehicle answered the last item with MAV_MISSION_ERROR: its MISSION_ACK may have been lost")


def test_a_stale_accepted_ack_does_not_end_an_upload(x: Exchange) -> None:
    x.transfer.upload(ITEMS, HOME, verify=False)
    x.tick()
    x.tick(ack(), request(0))  # e.g. the ack of an earlier clear, sent twice
    assert x.status.state is TransferState.IN_PROGRESS


def test_read_back_mismatch_is_reported_at_the_first_difference(x: Exchange) -> None:
    upload_until_last_item(x)
    x.tick(ack())
    x.tick(count(3))
    x.tick(home_item())
    x.tick(held(ITEMS[0]))
    moved = MissionItem.waypoint(2, POINTS[1][0] + 3e-7, POINTS[1][1], POINTS[1][2])
    x.tick(held(moved))
    assert x.status.state is TransferState.FAILED
    assert x.status.reason == "read-back mismatch: item 2 x (latitude): sent 47.3979220, the vehicle holds 47.3979223"
    assert bb("/vehicle/mission_items")[1].x == pytest.approx(47.3979223)  # what the vehicle holds, all the same


def test_read_back_within_storage_precision_passes(x: Exchange) -> None:
    items = waypoint_items([(47.39792204, 8.54559404, 12.345)])  # beyond 1e-7 degree and 1 cm
    upload_until_last_item(x, items)
    x.tick(ack())
    x.tick(count(2))
    x.tick(home_item())
    x.tick(held(items[0]))
    assert x.status.state is TransferState.DONE


def test_first_mismatch() -> None:
    sent = MissionItem.waypoint(1, 47.0, 8.0, 10.0, hold_s=2.5)
    assert first_mismatch([sent], [sent]) is None
    as_read = MissionItem(1, m.MAV_FRAME_GLOBAL_RELATIVE_ALT, 16, 1, 1, 2.5, 0, 0, 0, 47.0 + 1e-7, 8.0 - 1e-7, 10.0 + 0.01)
    assert first_mismatch([sent], [as_read]) is None  # the INT frame comes back in its float form; the current flag is state, not content
    assert first_mismatch([sent], [MissionItem.waypoint(1, 47.0, 8.0, 10.0, hold_s=2.0)]) == "item 1 param1: sent 2.5, the vehicle holds 2"
    assert first_mismatch([sent], [MissionItem.waypoint(1, 47.0, 8.0, 10.02)]).startswith("item 1 param1")  # the first difference only
    higher = MissionItem.waypoint(1, 47.0, 8.0, 10.02, hold_s=2.5)
    assert first_mismatch([sent], [higher]) == "item 1 z (altitude): sent 10.000, the vehicle holds 10.020"
    assert first_mismatch([sent], [replace(sent, frame=m.MAV_FRAME_GLOBAL)]) == "item 1 frame: sent 3, the vehicle holds 0"
    assert first_mismatch([sent], []) == "the vehicle holds 0 items, 1 were sent"
    nan_yaw = MissionItem(1, 6, 16, 0, 1, 0, 0, 0, math.nan, 47.0, 8.0, 0.0)
    assert first_mismatch([nan_yaw], [nan_yaw]) is None


def test_a_new_request_supersedes_the_transfer_in_progress(x: Exchange) -> None:
    first = x.transfer.upload(ITEMS, HOME)
    x.tick()
    superseded = x.status
    second = x.transfer.download()
    assert second != first
    assert (superseded.ticket, x.transfer.status.ticket) == (first, second)
    assert x.tick() == [("MISSION_REQUEST_LIST",)]
    assert x.tick(request(0)) == []  # the old upload's request is no longer answered
    assert x.status.ticket == second and x.status.state is TransferState.IN_PROGRESS


def test_the_superseded_transfer_is_reported_failed(x: Exchange, caplog) -> None:
    x.transfer.clear()
    x.transfer.set_current(1)
    assert "mission clear failed: superseded by a set-current request" in caplog.text
    assert x.status.operation is TransferOperation.SET_CURRENT and x.status.state is TransferState.IN_PROGRESS


def test_leftover_acks_do_not_fail_a_read_back_but_a_changed_count_does(x: Exchange) -> None:
    upload_until_last_item(x)
    x.tick(ack())
    # the vehicle got the last item twice (a late re-request crossed our answer): ERROR for the copy
    assert x.tick(ack(m.MAV_MISSION_ERROR), ack(m.MAV_MISSION_INVALID_SEQUENCE)) == []
    assert x.tick(count(3)) == [("MISSION_REQUEST_INT", 0)]
    assert x.tick(count(3), home_item()) == [("MISSION_REQUEST_INT", 1)]  # the answer to a resent list request
    x.tick(count(2), ack(m.MAV_MISSION_ERROR))  # what ArduPilot says to a request beyond its mission
    assert x.status.reason == "the mission changed during the download: 2 items, not 3"


def test_a_download_refused(x: Exchange) -> None:
    x.transfer.download()
    x.tick()
    x.tick(ack(m.MAV_MISSION_DENIED))  # ArduPilot, while someone uploads
    assert (x.status.state, x.status.reason) == (TransferState.FAILED, "the vehicle refused the download: MAV_MISSION_DENIED")


def test_only_replies_for_us_and_for_the_mission_count(x: Exchange) -> None:
    x.transfer.clear()
    x.tick()
    x.tick(AUTOPILOT.mission_ack(255, 190, m.MAV_MISSION_ACCEPTED, 0))  # the ground station's clear
    x.tick(AUTOPILOT.mission_ack(*US, m.MAV_MISSION_ACCEPTED, m.MAV_MISSION_TYPE_FENCE))  # a fence transfer
    x.tick(GCS.mission_ack(*US, m.MAV_MISSION_ACCEPTED, 0))  # not from the autopilot
    assert x.status.state is TransferState.IN_PROGRESS
    x.tick(AUTOPILOT.mission_ack(0, 0, m.MAV_MISSION_ACCEPTED, 0))  # broadcast counts
    assert x.status.state is TransferState.DONE


def test_reached_and_current_reach_the_blackboard_without_a_transfer(x: Exchange) -> None:
    x.tick(AUTOPILOT.mission_item_reached(3), AUTOPILOT.mission_current(4, 5, m.MISSION_STATE_ACTIVE, 1))
    assert bb("/vehicle/mission_reached") == MissionItemReached(3, x.clock.now(), 3)
    assert bb("/vehicle/mission_current").seq == 4
    assert bb("/link/mission_transfer") is None


def test_the_highest_item_reached_is_latched_until_the_mission_changes(x: Exchange) -> None:
    """Two reports drained in one tick (item 3, then a GUIDED arrival's item 0): the 3 is not lost."""
    x.tick(AUTOPILOT.mission_item_reached(3), AUTOPILOT.mission_item_reached(0))
    assert bb("/vehicle/mission_reached") == MissionItemReached(0, x.clock.now(), 3)
    x.transfer._hold(None, ())  # the vehicle's mission is another one now (an upload or a download found it)
    assert bb("/vehicle/mission_reached") is None
    x.tick(AUTOPILOT.mission_item_reached(1))
    assert bb("/vehicle/mission_reached").highest == 1


def test_targets_follow_the_adopted_autopilot(link, clock, commander, transfer) -> None:
    reader = MavlinkReader(link, clock, commander, mission=transfer)
    other = type(AUTOPILOT)(7, 1)
    link.incoming.append(other.heartbeat(m.MAV_TYPE_GROUND_ROVER, m.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, 4, m.MAV_STATE_STANDBY))
    reader.drain()
    transfer.download()
    transfer.flush()
    [sent] = link.take()
    assert (sent.target_system, sent.target_component) == (7, 1)


def test_px4_has_no_home_slot_the_route_goes_from_item_0_and_is_read_back_whole(x: Exchange) -> None:
    """PX4 flies item 0 as the first item (src/modules/mavlink/mavlink_mission.cpp); it asks with MISSION_REQUEST_INT."""
    x.transfer.home_slot = False
    x.transfer.upload(ITEMS, HOME)
    assert x.tick() == [("MISSION_COUNT", 2)]
    assert x.tick(request_int(0)) == [("MISSION_ITEM_INT", 0)]
    assert x.tick(request_int(1)) == [("MISSION_ITEM_INT", 1)]
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]
    assert x.tick(count(2)) == [("MISSION_REQUEST_INT", 0)]
    first, second = (replace(item, seq=seq) for seq, item in enumerate(ITEMS))
    assert x.tick(held(first)) == [("MISSION_REQUEST_INT", 1)]
    assert x.tick(held(second)) == [("MISSION_ACK", m.MAV_MISSION_ACCEPTED)]
    assert x.status.state is TransferState.DONE
    assert [i.seq for i in bb("/vehicle/mission_items")] == [0, 1] and bb("/vehicle/mission_home") is None


def read_back(x: Exchange, items: tuple[MissionItem, ...]) -> None:
    """The vehicle answers a read-back of home and ``items``."""
    assert x.tick(count(len(items) + 1)) == [("MISSION_REQUEST_INT", 0)]
    assert x.tick(home_item()) == [("MISSION_REQUEST_INT", 1)]
    for i, item in enumerate(items):
        assert x.tick(held(item)) == ([("MISSION_REQUEST_INT", i + 2)] if i + 1 < len(items) else [("MISSION_ACK", m.MAV_MISSION_ACCEPTED)])


def test_append_writes_one_item_at_the_end_by_a_partial_write_and_reads_back(x: Exchange, link) -> None:
    """drive: auto's horizon grows by MISSION_WRITE_PARTIAL_LIST count..count: only the new item is sent, the held ones stay."""
    upload_until_last_item(x, ITEMS[:1])
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]
    read_back(x, ITEMS[:1])
    x.tick(AUTOPILOT.mission_item_reached(1))
    ticket = x.transfer.append([ITEMS[1]])
    x.clock.advance(0.1)
    x.reader.drain()
    x.transfer.flush()
    [partial] = link.take()
    assert (partial.get_type(), partial.start_index, partial.end_index, partial.target_component) == ("MISSION_WRITE_PARTIAL_LIST", 2, 2, 1)
    assert x.tick(request(2)) == [("MISSION_ITEM_INT", 2)]
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]
    read_back(x, ITEMS)
    status = x.status
    assert (status.ticket, status.state) == (ticket, TransferState.DONE)
    assert [i.seq for i in bb("/vehicle/mission_items")] == [1, 2]
    assert bb("/vehicle/mission_reached").highest == 1  # the same mission, one item longer: its reports still count


def test_appending_several_items_writes_them_back_to_back_then_reads_back_once(x: Exchange) -> None:
    """drive: auto fills its horizon in one burst: each item by its own partial write (ArduPilot appends only at its count),
    the next as soon as the last is acknowledged, the whole mission read back once at the end."""
    upload_until_last_item(x, ITEMS[:1])
    x.tick(ack())
    read_back(x, ITEMS[:1])
    items = waypoint_items([*POINTS, (47.3981, 8.5461, 0.0)])
    ticket = x.transfer.append(items[1:])
    assert x.tick() == [("MISSION_WRITE_PARTIAL_LIST", 2)]  # 2..2: the vehicle's count
    assert x.tick(request(2)) == [("MISSION_ITEM_INT", 2)]
    assert x.tick(ack()) == [("MISSION_WRITE_PARTIAL_LIST", 3)]
    assert x.tick(request(3)) == [("MISSION_ITEM_INT", 3)]
    assert x.tick(ack()) == [("MISSION_REQUEST_LIST",)]
    read_back(x, items)
    assert (x.status.ticket, x.status.state) == (ticket, TransferState.DONE)
    assert [i.seq for i in bb("/vehicle/mission_items")] == [1, 2, 3]


def test_append_read_back_mismatch_fails(x: Exchange) -> None:
    upload_until_last_item(x, ITEMS[:1])
    x.tick(ack())
    read_back(x, ITEMS[:1])
    x.transfer.append([ITEMS[1]])
    x.tick()
    x.tick(request(2))
    x.tick(ack())
    read_back(x, (ITEMS[0], replace(ITEMS[1], x=ITEMS[1].x + 1e-4)))
    assert x.status.state is TransferState.FAILED and "read-back mismatch: item 2 x (latitude)" in x.status.reason


def test_a_sample_point_is_uploaded_as_a_stop_and_a_waypoint_held_there_does_not_count_as_the_route() -> None:
    """A sample point is a NAV_LOITER_UNLIM: the autopilot stops there until moved on (Rover/mode_auto.cpp verify_loiter_unlimited)."""
    route = [Waypoint(lat=47.0, lon=8.0), Waypoint(lat=47.001, lon=8.0, sample=True), Waypoint(lat=47.001, lon=8.001)]
    items = route_items(route)
    assert [i.command for i in items] == [m.MAV_CMD_NAV_WAYPOINT, m.MAV_CMD_NAV_LOITER_UNLIM, m.MAV_CMD_NAV_WAYPOINT]
    assert [(i.seq, i.x, i.y) for i in items] == [(1, 47.0, 8.0), (2, 47.001, 8.0), (3, 47.001, 8.001)]
    held_as_waypoints = waypoint_items((wp.lat, wp.lon) for wp in route)
    assert route_not_on_autopilot(route, held_as_waypoints) == "the autopilot's mission differs (item 2 command: sent 17, the vehicle holds 16)"
    assert route_not_on_autopilot(route, items) is None
