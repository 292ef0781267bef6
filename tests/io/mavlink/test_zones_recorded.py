"""Our reading of what real ArduRover and PX4 said to the fence and rally transfers, the fence parameters and a fence breach.

The recordings (tests/data/zones/README.md): the zoned line mission of tests/behaviours/test_zones_on_autopilot.py with
``geofence.autopilot: enforce`` on ArduRover SITL, a VTOL mission's zones on PX4 SIH, and ArduRover's own fence
acting (its avoidance holding a ground station's Go-to off the pier, then a breach in MANUAL).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from tlog_replay import DATA, Replay, records

from executive.autopilot.fence import fence_items, rally_items
from executive.io.mavlink.mission_protocol import MissionTransfer, first_mismatch
from executive.mission.loader import load_mission
from executive.testing import FakeLink
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import AUTOPILOT_COMPONENT, EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink
from executive.world.geo import distance
from executive.world.state import TransferState

ZONES = DATA / "zones"
_M = mavlink
FENCE, RALLY = _M.MAV_MISSION_TYPE_FENCE, _M.MAV_MISSION_TYPE_RALLY
_WIRE = ("seq", "frame", "command", "param1", "x", "y", "z", "autocontinue")


def _mission_messages(path: Path, component: int, mission_type: int) -> list[MAVLinkMessage]:
    return [
        m for _, m in records(path)
        if m.get_srcComponent() == component and m.get_type().startswith("MISSION_") and getattr(m, "mission_type", 0) == mission_type
    ]  # fmt: skip


def replay_transfer(path: Path, mission_type: int, items: tuple) -> tuple[MissionTransfer, list[MAVLinkMessage]]:
    """Our upload of ``items`` answered by what the vehicle said in the recording, in order; what we sent."""
    blackboard.reset()
    clock, link = ManualClock(), FakeLink()
    transfer = MissionTransfer(link, clock)
    theirs = _mission_messages(path, AUTOPILOT_COMPONENT, mission_type)
    transfer.target_system = theirs[0].get_srcSystem()
    transfer.upload(items, verify=True, mission_type=mission_type)
    transfer.flush()
    handlers = {
        "MISSION_REQUEST": transfer.on_request, "MISSION_REQUEST_INT": transfer.on_request, "MISSION_ACK": transfer.on_ack,
        "MISSION_COUNT": transfer.on_count, "MISSION_ITEM_INT": transfer.on_item,
    }  # fmt: skip
    for msg in theirs:
        clock.advance(0.1)
        handlers[msg.get_type()](msg, clock.now())
        transfer.flush()
    return transfer, link.take()


def _zoned_line_mission():  # the mission recorded on ArduRover (tests/behaviours/test_zones_on_autopilot.py's, enforce)
    return load_mission(ZONES / "zones-line.yaml")


def _vtol_mission():
    return load_mission(ZONES / "zones-vtol.yaml")


@pytest.mark.parametrize(
    ("tlog", "mission", "count"),
    [("ardurover-fence-rally-enforce.tlog", _zoned_line_mission, 9), ("px4-vtol-fence-rally-enforce.tlog", _vtol_mission, 9)],
)
def test_the_fence_the_firmware_read_back_is_the_one_we_send_and_counts(tlog: str, mission, count: int) -> None:
    path = ZONES / tlog
    items = fence_items(mission().geofence).items
    transfer, sent = replay_transfer(path, FENCE, items)
    assert transfer.status is not None and transfer.status.state is TransferState.DONE, transfer.status
    held = blackboard.reader("t", ["/vehicle/fence_items"]).get("/vehicle/fence_items")
    assert len(held) == count and first_mismatch(items, held) is None
    # what we send now is, field by field, what went to the firmware in the recording
    recorded = [m for m in _mission_messages(path, EXECUTIVE_COMPONENT, FENCE) if m.get_type() == "MISSION_ITEM_INT"]
    ours = [m for m in sent if m.get_type() == "MISSION_ITEM_INT"]
    assert [tuple(getattr(m, f) for f in _WIRE) for m in ours] == [tuple(getattr(m, f) for f in _WIRE) for m in recorded]


@pytest.mark.parametrize("tlog", ["ardurover-fence-rally-enforce.tlog", "px4-vtol-fence-rally-enforce.tlog"])
def test_the_rally_points_the_firmware_read_back_are_the_ones_we_send(tlog: str) -> None:
    mission = _zoned_line_mission() if tlog.startswith("ardurover") else _vtol_mission()
    items = rally_items(mission.rally_points).items
    transfer, _ = replay_transfer(ZONES / tlog, RALLY, items)
    assert transfer.status is not None and transfer.status.state is TransferState.DONE, transfer.status
    held = blackboard.reader("t", ["/vehicle/rally_items"]).get("/vehicle/rally_items")
    assert len(held) == 2 and first_mismatch(items, held) is None


def test_px4_reads_back_its_fence_items_in_int_frames_that_count_as_the_same() -> None:
    frames = {
        m.frame
        for m in _mission_messages(ZONES / "px4-vtol-fence-rally-enforce.tlog", AUTOPILOT_COMPONENT, FENCE)
        if m.get_type() == "MISSION_ITEM_INT"
    }
    assert frames == {_M.MAV_FRAME_GLOBAL_INT}  # sent as MAV_FRAME_GLOBAL (0): the read-back compares them alike


@pytest.mark.parametrize(
    ("tlog", "vehicle", "wanted"),
    [
        ("ardurover-fence-rally-enforce.tlog", "rover", {"FENCE_ENABLE": 1.0, "FENCE_TYPE": 4.0, "FENCE_ACTION": 2.0, "FENCE_RADIUS": 300.0}),
        ("px4-vtol-fence-rally-enforce.tlog", "vtol", {"GF_ACTION": 2.0, "GF_MAX_HOR_DIST": 800.0}),
    ],
)
def test_the_fence_parameters_read_back_after_enforce(tlog: str, vehicle: str, wanted: dict[str, float]) -> None:
    Replay(vehicle=vehicle).play(ZONES / tlog)  # PX4's INT32 GF_ACTION arrives as raw bytes in the float
    params = blackboard.reader("t", ["/vehicle/params"]).get("/vehicle/params")
    assert {name: params[name] for name in wanted} == wanted


def test_ardurovers_avoidance_kept_a_go_to_off_the_pier_and_a_manual_drive_in_breached_its_fence() -> None:
    replay = Replay(vehicle="rover", watch=("/vehicle/mode", "/vehicle/mode_set_by", "/vehicle/fence_status")).play(
        ZONES / "ardurover-goto-avoided-then-manual-breach.tlog"
    )
    statuses = [(t, s) for t, k, s in replay.seen if k == "/vehicle/fence_status" and s is not None]
    breach_t, breach = next((t, s) for t, s in statuses if s.breached)
    assert (breach.count, breach.breach_type) == (1, _M.FENCE_BREACH_BOUNDARY)
    assert not any(s.breached for t, s in statuses if t < breach_t)  # the Go-to into the pier did not breach: avoidance held it
    hold_t = next(t for t, k, mode in replay.seen if k == "/vehicle/mode" and mode == "HOLD" and t >= breach_t)
    assert hold_t - breach_t < 0.5  # FENCE_ACTION 2 within a heartbeat of the breach report
    assert ("/vehicle/mode_set_by", "autopilot") in [(k, v) for t, k, v in replay.seen if t >= hold_t - 0.01]


def _after(path: Path, text: str) -> list[tuple[float, MAVLinkMessage]]:
    """The recording from the executive's STATUSTEXT starting with ``text`` on, with times."""
    messages = list(records(path))
    start = next(i for i, (_, m) in enumerate(messages) if m.get_type() == "STATUSTEXT" and m.text.startswith(text))
    return messages[start:]


def test_ardurover_took_and_read_back_the_replacing_missions_zones_before_its_route_was_driven() -> None:
    path = ZONES / "ardurover-replaced-zones.tlog"
    new = load_mission(ZONES / "zones-v2.yaml")
    for mission_type, items, key, count in (
        (FENCE, fence_items(new.geofence).items, "/vehicle/fence_items", 8),  # the inclusion polygon and 'moorings': 'pier' and 'buoy' gone
        (RALLY, rally_items(new.rally_points).items, "/vehicle/rally_items", 1),
    ):
        transfer, _ = replay_transfer(path, mission_type, items)
        assert transfer.status is not None and transfer.status.state is TransferState.DONE, transfer.status
        held = blackboard.reader("t", [key]).get(key)
        assert len(held) == count and first_mismatch(items, held) is None
    ours = [(t, m) for t, m in _after(path, "mission replaced: zones-v2") if m.get_srcComponent() == EXECUTIVE_COMPONENT]
    read_back = max(t for t, m in ours if m.get_type() == "MISSION_ACK" and m.mission_type in (FENCE, RALLY))
    resumed = next(t for t, m in ours if m.get_type() == "STATUSTEXT" and m.text.startswith("mission RUNNING"))
    driven = next(t for t, m in ours if m.get_type() in ("COMMAND_LONG", "SET_POSITION_TARGET_GLOBAL_INT"))
    assert read_back < resumed <= driven  # nothing commanded of the new mission before its zones were read back


def test_ardurover_took_an_empty_fence_and_rally_list_from_a_replacing_mission_without_zones() -> None:
    path = ZONES / "ardurover-replaced-without-zones.tlog"
    for mission_type, key in ((FENCE, "/vehicle/fence_items"), (RALLY, "/vehicle/rally_items")):
        transfer, sent = replay_transfer(path, mission_type, ())
        assert transfer.status is not None and transfer.status.state is TransferState.DONE, transfer.status
        assert [m.count for m in sent if m.get_type() == "MISSION_COUNT"] == [0]  # the count alone: ArduPilot ACCEPTED it
        assert blackboard.reader("t", [key]).get(key) == ()


def test_ardurover_refused_the_replacing_missions_fence_kept_the_old_one_and_nothing_was_commanded() -> None:
    path = ZONES / "ardurover-replaced-fence-refused.tlog"
    transfer, _ = replay_transfer(path, FENCE, fence_items(load_mission(ZONES / "ring.yaml").geofence).items)  # 95 items
    assert transfer.status is not None and transfer.status.state is TransferState.FAILED
    assert transfer.status.reason == "the vehicle refused the upload: MAV_MISSION_NO_SPACE"
    after = _after(path, "mission replaced: ring")
    said = [m.text for _, m in after if m.get_type() == "STATUSTEXT"]
    assert said[-2:] == ["Only 84 items are supported", "zones refused: mission stays paused"]
    commanded = [m for _, m in after if m.get_srcComponent() == EXECUTIVE_COMPONENT and m.get_type().startswith(("COMMAND_", "SET_POSITION"))]
    assert commanded == []  # paused, held in HOLD: nothing of the new mission sent
    fixes = [(m.lat / 1e7, m.lon / 1e7) for _, m in after if m.get_type() == "GLOBAL_POSITION_INT"]
    assert len(fixes) > 10 and max(distance(*fixes[0], *fix) for fix in fixes) < 0.05  # the rover did not move (1e-7 deg of jitter)
