"""Our reading of what real ArduRover and PX4 said to the fence and rally transfers, the fence parameters and a fence breach.

The recordings (tests/data/zones/README.md): the zoned line mission of tests/behaviours/test_zones_on_autopilot.py with
``geofence.autopilot: enforce`` on ArduRover SITL, a VTOL mission's zones on PX4 SIH, and ArduRover's own fence
acting (its avoidance holding a ground station's Go-to off the pier, then a breach in MANUAL).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from tlog_replay import DATA, Replay, records

from executive import blackboard
from executive.autopilot.fence import fence_items, rally_items
from executive.clock import ManualClock
from executive.io.mavlink.mission_protocol import MissionTransfer, first_mismatch
from executive.mavlink_dialect import AUTOPILOT_COMPONENT, EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink
from executive.mission.loader import load_mission
from executive.state import TransferState
from executive.testing import FakeLink

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
