"""A ground station's Pause or Go-to, the mode unchanged, end to end (issue 42): the runtime against the simulated PX4 and ArduRover.

The ground station is a second MAVLink client on the simulated autopilot (system 255, as QGroundControl):
its DO_REPOSITION goes to the autopilot, whose COMMAND_ACK answers it alone; the executive sees only what the
autopilot then reports (POSITION_TARGET_GLOBAL_INT). The operator's resume is the request ``executive ctl
resume`` makes. Lock-step, in vehicle time; messages packed and parsed as over a link (``as_bytes``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.observers.journal import Journal, journal_recorder
from executive.testing import Lockstep
from executive.world import blackboard, geo
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from tests_support import line_mission

ROOT = Path(__file__).resolve().parents[2]
_M = mavlink
_ENCODER = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
HELD = "a ground station held the vehicle (reposition to its position)"


def qgc_pause(system: int) -> MAVLinkMessage:
    """QGroundControl's Pause on PX4 (PX4FirmwarePlugin::pauseVehicle): DO_REPOSITION, change mode, no position (NaN)."""
    return _ENCODER.command_long_encode(
        system, 1, _M.MAV_CMD_DO_REPOSITION, 0, -1.0, _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0.0, math.nan, math.nan, math.nan, math.nan
    )


def qgc_go_to(system: int, lat: float, lon: float, alt_amsl_m: float) -> MAVLinkMessage:
    """QGroundControl's Go-to (guidedModeGotoLocation): DO_REPOSITION as COMMAND_INT, MAV_FRAME_GLOBAL, change mode, the point."""
    return _ENCODER.command_int_encode(
        system, 1, _M.MAV_FRAME_GLOBAL, _M.MAV_CMD_DO_REPOSITION, 0, 0,
        -1.0, _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0.0, math.nan, round(lat * 1e7), round(lon * 1e7), alt_amsl_m,
    )  # fmt: skip


@dataclass
class GroundStationPlay:
    """At the first step ``when`` says yes, the ground station sends ``command(sim)``; ``hold_s`` after the pause, the operator resumes."""

    when: object  # Callable[[Lockstep], bool]
    command: object  # Callable[[Lockstep], MAVLinkMessage]
    hold_s: float
    sent_at: float | None = None
    paused_at: float | None = None
    resumed: object = None
    reasons: list[str] = field(default_factory=list)  # each mission reason while PAUSED, at each step
    modes_while_paused: set[str] = field(default_factory=set)
    targets_while_paused: list[tuple[float, float]] = field(default_factory=list)  # what the autopilot reported steering to
    sent_while_paused: list[str] = field(default_factory=list)  # what the executive sent the autopilot while paused
    texts: list[str] = field(default_factory=list)  # STATUSTEXT the executive sent
    ctl_status: dict | None = None  # what `executive ctl status` said at the resume

    def __call__(self, sim: Lockstep) -> None:
        if self.sent_at is None and self.when(sim):  # type: ignore[operator]
            sim.send_from_ground_station(self.command(sim))  # type: ignore[operator]
            self.sent_at = sim.clock.now()
        status = sim.status
        if status is MissionStatus.PAUSED and self.resumed is None:
            if self.paused_at is None:
                self.paused_at = sim.clock.now()
            bb = blackboard.reader("ground station play", ["/mission/reason", "/vehicle/mode", "/vehicle/position_target"])
            self.reasons.append(bb.get("/mission/reason"))
            self.modes_while_paused.add(bb.get("/vehicle/mode"))
            target = bb.get("/vehicle/position_target")
            if target is not None:
                self.targets_while_paused.append((target.lat, target.lon))
            if sim.clock.now() >= self.paused_at + self.hold_s:
                self.ctl_status = sim.runtime.operator.request("status", source="ctl").to_dict()
                self.resumed = sim.runtime.operator.request("resume", source="ctl")


def play(sim: Lockstep, ground_station: GroundStationPlay) -> tuple[object, GroundStationPlay]:
    send = sim.link.send

    def spy(msg: MAVLinkMessage) -> None:
        if sim.status is MissionStatus.PAUSED and msg.get_type() in ("COMMAND_LONG", "COMMAND_INT", "SET_POSITION_TARGET_GLOBAL_INT"):
            ground_station.sent_while_paused.append(msg.get_type() + (f" {msg.command}" if hasattr(msg, "command") else ""))
        if msg.get_type() == "STATUSTEXT":
            ground_station.texts.append(msg.text)
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    sim.observers.append(ground_station)
    return sim.run_to_end(limit_s=900), ground_station


def _leg_and_distance(sim: Lockstep) -> tuple[int, float] | None:
    state = sim.runtime.mission_state
    target, v = state.legs.target, sim.autopilot.vehicle
    if target is None or state.status is not MissionStatus.RUNNING:
        return None
    return state.legs.leg_index, geo.distance(v.lat, v.lon, target.lat, target.lon)


def _mid_leg(leg_index: int, farther_than_m: float, closer_than_m: float) -> object:
    """Under way on the leg: the autopilot reports its target as ours, the vehicle between the two distances from it."""
    bb = blackboard.reader("mid leg", ["/vehicle/target_set_by"])

    def when(sim: Lockstep) -> bool:
        at = _leg_and_distance(sim)
        under_way = at is not None and at[0] == leg_index and farther_than_m < at[1] < closer_than_m
        return under_way and bb.get("/vehicle/target_set_by") == "us"

    return when


@pytest.fixture
def transit_on_px4() -> Lockstep:
    with Lockstep(load_mission(ROOT / "missions" / "vtol_transit.yaml"), autopilot="px4", as_bytes=True) as sim:
        yield sim


def test_qgcs_pause_on_px4_mid_leg_pauses_hands_off_longer_than_the_leg_timeout_then_resume_completes(transit_on_px4: Lockstep) -> None:
    """The issue's run: Pause mid-leg 2 of vtol_transit (PX4 stays in AUTO.LOITER); held 150 s, past the 120 s leg timeout."""
    sim = transit_on_px4
    gcs = GroundStationPlay(when=_mid_leg(1, 150.0, 230.0), command=lambda s: qgc_pause(s.autopilot.system_id), hold_s=150.0)
    outcome, gcs = play(sim, gcs)
    assert str(outcome.status) == "COMPLETED", outcome.reason  # the run finished as if never paused: no timeout
    assert gcs.sent_at is not None and gcs.paused_at is not None
    assert gcs.paused_at - gcs.sent_at <= 2.0  # the next POSITION_TARGET_GLOBAL_INT (5 Hz) said it
    assert set(gcs.reasons) == {HELD}
    assert gcs.modes_while_paused == {"AUTO.LOITER"}  # the mode never changed: only the target told
    assert gcs.sent_while_paused == []  # hands off: nothing re-sent while the person held it
    leg_target = sim.mission.waypoints[1]
    assert all(geo.distance(lat, lon, leg_target.lat, leg_target.lon) > 150.0 for lat, lon in gcs.targets_while_paused)
    assert gcs.resumed is not None and gcs.resumed.ok  # type: ignore[attr-defined]
    assert f"mission PAUSED: {HELD}"[:50] in gcs.texts  # the ground-station report
    assert [a.result for a in sim.ground_station_heard] == [_M.MAV_RESULT_ACCEPTED]  # PX4 took it; its ack went to QGC alone


def test_qgcs_go_to_on_px4_mid_leg_is_reported_with_its_point_and_resume_flies_the_leg_again(transit_on_px4: Lockstep) -> None:
    sim = transit_on_px4
    there: list[tuple[float, float]] = []

    def go_to(s: Lockstep) -> MAVLinkMessage:
        v = s.autopilot.vehicle
        there.append(geo.destination(v.lat, v.lon, 180.0, 400.0))  # 400 m south of the aircraft
        return qgc_go_to(s.autopilot.system_id, *there[0], s.autopilot.home_amsl_m + v.alt_m)  # type: ignore[attr-defined]

    outcome, gcs = play(sim, GroundStationPlay(when=_mid_leg(1, 150.0, 230.0), command=go_to, hold_s=20.0))
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert gcs.sent_at is not None and gcs.paused_at is not None and gcs.paused_at - gcs.sent_at <= 2.0
    assert set(gcs.reasons) == {f"a ground station sent it to {there[0][0]:.5f}, {there[0][1]:.5f}"}
    assert gcs.modes_while_paused == {"AUTO.LOITER"} and gcs.sent_while_paused == []
    assert all(geo.distance(lat, lon, *there[0]) < 1.0 for lat, lon in gcs.targets_while_paused)  # the person's point, kept
    wp = sim.mission.waypoints[1]
    assert sim.runtime.mission_state.legs.leg_index >= 1 and wp is not None


def test_qgcs_go_to_on_ardurover_in_guided_mid_leg_the_rover_goes_there_paused_and_resume_completes(lockstep, tmp_path) -> None:
    """The issue's ArduRover run: a Go-to ~33 m off the route mid-leg 2; the rover drives there, nothing of ours overwrites it."""
    journals: list[Journal] = []

    def journal_plug(clock: Clock) -> dict[str, object]:
        journals.append(Journal(tmp_path / "journal.db", clock))
        return {"plugs": [journal_recorder(journals[0])]}

    sim = lockstep(line_mission("go-to"), as_bytes=True, options_for_clock=journal_plug)
    there: list[tuple[float, float]] = []

    def go_to(s: Lockstep) -> MAVLinkMessage:
        v = s.autopilot.vehicle
        there.append(geo.destination(v.lat, v.lon, 90.0, 33.0))
        return qgc_go_to(s.autopilot.system_id, *there[0], 584.0)

    outcome, gcs = play(sim, GroundStationPlay(when=_mid_leg(1, 8.0, 20.0), command=go_to, hold_s=40.0))
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert gcs.sent_at is not None and gcs.paused_at is not None and gcs.paused_at - gcs.sent_at <= 1.0
    reason = f"a ground station sent it to {there[0][0]:.5f}, {there[0][1]:.5f}"
    assert set(gcs.reasons) == {reason}
    assert gcs.modes_while_paused == {"GUIDED"} and gcs.sent_while_paused == []
    assert all(geo.distance(lat, lon, *there[0]) < 0.1 for lat, lon in gcs.targets_while_paused)
    assert gcs.ctl_status is not None and gcs.ctl_status["status"]["state"] == "PAUSED"
    assert gcs.ctl_status["reason"] == reason and geo.distance(gcs.ctl_status["status"]["lat"], gcs.ctl_status["status"]["lon"], *there[0]) < 2.0
    report = journals[0].report()  # what `executive report` prints
    assert ("RUNNING", "PAUSED", reason) in [(t["before"], t["after"], t["reason"]) for t in report["transitions"]]
    assert report["outcome"] == "COMPLETED"


def test_a_ground_stations_guided_setpoint_on_ardurover_is_a_persons_too(lockstep) -> None:
    """SET_POSITION_TARGET_GLOBAL_INT from a ground station in GUIDED (ArduRover takes it from anyone, unacknowledged)."""
    sim = lockstep(line_mission("setpoint"), as_bytes=True)
    there: list[tuple[float, float]] = []

    def setpoint(s: Lockstep) -> MAVLinkMessage:
        v = s.autopilot.vehicle
        there.append(geo.destination(v.lat, v.lon, 90.0, 30.0))
        lat, lon = (round(x * 1e7) for x in there[0])
        return _ENCODER.set_position_target_global_int_encode(
            0, s.autopilot.system_id, 1, _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0x0DF8, lat, lon, 0.0, 0, 0, 0, 0, 0, 0, 0, 0
        )

    outcome, gcs = play(sim, GroundStationPlay(when=_mid_leg(1, 8.0, 20.0), command=setpoint, hold_s=10.0))
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    assert gcs.paused_at is not None and gcs.sent_at is not None and gcs.paused_at - gcs.sent_at <= 1.0
    assert set(gcs.reasons) == {f"a ground station sent it to {there[0][0]:.5f}, {there[0][1]:.5f}"}
    assert gcs.sent_while_paused == [] and sim.ground_station_heard == []  # no ack exists for a setpoint
