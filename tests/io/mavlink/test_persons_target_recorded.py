"""What the real firmware said when a ground station paused or moved the vehicle without a mode change (issue 42), replayed.

Each recording (tests/data/ardurover/README.md, tests/data/px4/README.md) is the executive's link during a real run of an
example mission, merged with what a second MAVLink client sent as QGroundControl (system 255) on the autopilot's
ground-station port, and what the autopilot answered it. The executive's link never carried the ground station's
command nor its COMMAND_ACK: the first message that told is the next POSITION_TARGET_GLOBAL_INT. The replay goes
through the MAVLink reader, the autopilot port and the intervention watch (tests/tlog_replay.py).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from tlog_replay import DATA, PX4, Replay, records

from executive.mission.lifecycle import MissionStatus
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage

HELD = "a ground station held the vehicle (reposition to its position)"
OUR_COMMANDS = ("COMMAND_LONG", "COMMAND_INT", "SET_POSITION_TARGET_GLOBAL_INT")
WATCH = ("/vehicle/mode", "/vehicle/mode_set_by", "/vehicle/target_set_by", "/mission/reason")


def ground_station_command(path: Path) -> tuple[float, MAVLinkMessage]:
    """The ground station's command (replay time, from the first record) and the message."""
    first = None
    for t, msg in records(path):
        first = t if first is None else first
        if msg.get_srcSystem() == 255 and msg.get_type() in ("COMMAND_INT", "COMMAND_LONG"):
            return t - first, msg
    raise AssertionError("no ground station command recorded")


def first_report_after(path: Path, after_s: float) -> tuple[float, MAVLinkMessage]:
    first = None
    for t, msg in records(path):
        first = t if first is None else first
        if t - first > after_s and msg.get_type() == "POSITION_TARGET_GLOBAL_INT":
            return t - first, msg
    raise AssertionError("no POSITION_TARGET_GLOBAL_INT after the command")


def ours_between(path: Path, start_s: float, end_s: float) -> list[str]:
    """What the executive sent the autopilot (commands, setpoints) between two replay times."""
    first, sent = None, []
    for t, msg in records(path):
        first = t if first is None else first
        kind = msg.get_type()
        if start_s < t - first < end_s and msg.get_srcComponent() == EXECUTIVE_COMPONENT and kind in OUR_COMMANDS:
            sent.append(kind)
    return sent


def test_ardurover_a_go_to_in_guided_shows_in_the_next_target_report_and_pauses_hands_off() -> None:
    """rover_square, leg 2, GUIDED: QGC's Go-to (DO_REPOSITION, COMMAND_INT) ~32 m off the route; ArduRover ACCEPTED it."""
    path = DATA / "ardurover" / "rover_square-rover-guided-gcs-goto.tlog"
    sent_s, command = ground_station_command(path)
    replay = Replay(vehicle="rover", watch=WATCH).play(path)
    reported_s, report = first_report_after(path, sent_s)
    assert (report.lat_int, report.lon_int) == (command.x, command.y)  # the person's point, in the very next report
    assert reported_s - sent_s == pytest.approx(0.2, abs=0.05)  # measured 0.199 s: the 5 Hz stream
    paused_s = replay.when("/vehicle/target_set_by", "others")
    assert paused_s == pytest.approx(reported_s, abs=1e-6)  # the tick that read it
    reason = f"a ground station sent it to {command.x * 1e-7:.5f}, {command.y * 1e-7:.5f}"
    assert (replay.state.status, replay.state.reason) == (MissionStatus.PAUSED, reason)
    assert replay.values("/vehicle/mode")[-1] == "GUIDED" and replay.values("/vehicle/mode_set_by") == [None, "us"]
    resent_s = next(t for t, k, v in replay.seen if k == "/vehicle/target_set_by" and v == "us" and t > paused_s)
    assert resent_s - sent_s > 25.0  # the leg's target again only after `ctl resume`, 25 s on
    assert ours_between(path, sent_s, resent_s - 0.5) == []  # hands off meanwhile: nothing sent to the rover


def test_ardurover_before_the_go_to_every_target_report_was_ours() -> None:
    path = DATA / "ardurover" / "rover_square-rover-guided-gcs-goto.tlog"
    sent_s, _ = ground_station_command(path)
    replay = Replay(vehicle="rover", watch=WATCH).play(path, until_s=sent_s)
    assert replay.state.status is MissionStatus.RUNNING and "others" not in replay.values("/vehicle/target_set_by")
    assert replay.values("/vehicle/target_set_by")[-1] == "us"


def test_px4_qgcs_pause_mid_leg_shows_in_the_next_target_report_as_the_aircrafts_position_and_pauses_hands_off() -> None:
    """vtol_transit, leg 2, wing-borne in AUTO.LOITER: QGC's Pause (DO_REPOSITION, COMMAND_LONG, NaN position); PX4 ACCEPTED it."""
    path = PX4 / "vtol_transit-gcs-pause.tlog"
    sent_s, command = ground_station_command(path)
    assert command.param5 != command.param5  # NaN: "here"
    replay = Replay(watch=WATCH).play(path)
    reported_s, _ = first_report_after(path, sent_s)  # the aircraft's position (a fixed wing's pause: navigator_main.cpp)
    assert reported_s - sent_s == pytest.approx(0.2, abs=0.05)  # measured 0.195 s: the 5 Hz stream we asked
    paused_s = replay.when("/vehicle/target_set_by", "others")
    assert paused_s == pytest.approx(reported_s, abs=1e-6)
    assert (replay.state.status, replay.state.reason) == (MissionStatus.PAUSED, HELD)
    assert replay.values("/vehicle/mode")[-1] == "AUTO.LOITER" and replay.values("/vehicle/mode_set_by")[-1] == "us"
    resent_s = next(t for t, k, v in replay.seen if k == "/vehicle/target_set_by" and v == "us" and t > paused_s)
    assert resent_s - sent_s > 20.0  # the leg's DO_REPOSITION again only after `ctl resume`, 20 s on
    assert ours_between(path, sent_s, resent_s - 0.5) == []


def test_px4_before_the_pause_the_take_off_transitions_and_legs_were_all_ours() -> None:
    """NAV_TAKEOFF's own setpoint, the hover point, both legs' DO_REPOSITION: nothing taken for a person's."""
    path = PX4 / "vtol_transit-gcs-pause.tlog"
    sent_s, _ = ground_station_command(path)
    replay = Replay(watch=WATCH).play(path, until_s=sent_s)
    assert replay.state.status is MissionStatus.RUNNING and "others" not in replay.values("/vehicle/target_set_by")
    assert replay.values("/vehicle/target_set_by")[-1] == "us"


def test_px4_qgcs_go_to_mid_leg_shows_in_the_next_target_report_with_its_point() -> None:
    """vtol_transit, leg 2: QGC's Go-to (DO_REPOSITION, COMMAND_INT, MAV_FRAME_GLOBAL) 300 m south; PX4 ACCEPTED it."""
    path = PX4 / "vtol_transit-gcs-goto.tlog"
    sent_s, command = ground_station_command(path)
    replay = Replay(watch=WATCH).play(path)
    reported_s, report = first_report_after(path, sent_s)
    assert abs(report.lat_int - command.x) <= 1 and abs(report.lon_int - command.y) <= 1  # PX4's float setpoint, to 1e-7
    assert reported_s - sent_s < 0.25  # measured 0.097 s
    assert replay.when("/vehicle/target_set_by", "others") == pytest.approx(reported_s, abs=1e-6)
    reason = f"a ground station sent it to {command.x * 1e-7:.5f}, {command.y * 1e-7:.5f}"
    assert (replay.state.status, replay.state.reason) == (MissionStatus.PAUSED, reason)
    assert replay.values("/vehicle/mode")[-1] == "AUTO.LOITER"
