"""Fault injection: the fault file, the injector on messages and on the autopilot, and over a real UDP link."""

from __future__ import annotations

import argparse
import contextlib
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.cli import main
from executive.cli import sim as sim_cli
from executive.sim import SimServer, make_autopilot
from executive.sim.faults import FaultFileError, FaultInjector, FaultPlan, GpsGlitch, LinkLoss, RcTakeover, load_faults
from executive.sim.firmware import FirmwareSim
from executive.world import geo
from executive.world.clock import ManualClock, ScaledClock
from executive.world.dialect import MAVLinkMessage, encoder, mavutil
from executive.world.dialect import mavlink as m
from tests_support import SteppedClock

ROOT = Path(__file__).parents[2]
EXAMPLES = sorted((ROOT / "missions" / "faults").glob("*.yaml"))
KINDS = {"link_loss", "ekf_degradation", "gps_glitch", "compass_bias", "compass_glitch", "rc_takeover", "rc_loss", "battery_sag"}
HOME = (47.397742, 8.545594, 0.0)
LAT, LON = HOME[0], HOME[1]
MAV = encoder(1, 1)
GCS = (255, 190)
EKF_READY = 831


def plan(*faults: dict[str, Any]) -> FaultPlan:
    return FaultPlan.model_validate({"version": 1, "faults": list(faults)})


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "faults.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def errors_of(path: Path, vehicle: str | None = None) -> list[str]:
    with pytest.raises(FaultFileError) as info:
        load_faults(path, vehicle)
    return [str(e) for e in info.value.errors]


# -- the fault file ------------------------------------------------------------------------------


def test_a_file_with_every_kind_loads_with_defaults(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "version: 1\nfaults:\n"
        "  - {kind: link_loss, at_s: 60, for_s: 8}\n"
        "  - {kind: ekf_degradation, at_s: 1, lose_position: true}\n"
        "  - {kind: gps_glitch, at_s: 2, offset_m: 15, bearing_deg: 90.0}\n"
        "  - {kind: compass_bias, at_s: 3, bias_deg: -20}\n"
        "  - {kind: compass_glitch, at_s: 4}\n"
        "  - {kind: rc_takeover, at_s: 5, mode: MANUAL, disarm: true}\n"
        "  - {kind: rc_loss, at_s: 6, failsafe_mode: HOLD}\n"
        "  - {kind: battery_sag, at_s: 7.5, drop_pct: 30}\n",
    )
    faults = load_faults(path, "rover").faults
    assert [f.kind for f in faults] == [
        "link_loss",
        "ekf_degradation",
        "gps_glitch",
        "compass_bias",
        "compass_glitch",
        "rc_takeover",
        "rc_loss",
        "battery_sag",
    ]
    link, ekf, glitch, bias, swing, takeover, loss, sag = faults
    assert (link.at_s, link.for_s, link.end_s, link.direction) == (60.0, 8.0, 68.0, "both")
    assert (ekf.variance, ekf.lose_position, ekf.for_s, ekf.end_s) == (1.0, True, None, math.inf)
    assert (glitch.offset_m, glitch.bearing_deg, bias.bias_deg) == (15.0, 90.0, -20.0)
    assert (swing.amplitude_deg, swing.period_s) == (45.0, 2.0)
    assert (takeover.channel, takeover.pwm, takeover.mode, takeover.disarm) == (6, 1900, "MANUAL", True)
    assert (loss.failsafe_mode, sag.drop_v, sag.drop_pct) == ("HOLD", 0.0, 30)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_shipped_example_loads_for_a_rover_and_a_boat(path: Path) -> None:
    assert load_faults(path, "rover") == load_faults(path, "boat")


def test_the_shipped_examples_cover_every_kind() -> None:
    assert {f.kind for path in EXAMPLES for f in load_faults(path).faults} == KINDS


KIND_TAGS = (
    "expected one of 'link_loss', 'ekf_degradation', 'gps_glitch', 'compass_bias', 'compass_glitch', "
    "'rc_takeover', 'rc_input', 'rc_loss', 'battery_sag', 'weak_battery', 'headwind'"
)
ROVER_MODES = "(known: MANUAL, ACRO, STEERING, HOLD, LOITER, FOLLOW, SIMPLE, DOCK, CIRCLE, AUTO, RTL, SMART_RTL, GUIDED)"


@pytest.mark.parametrize(
    ("fault", "at", "field", "message"),
    [
        ("{kind: link_loss, at_s: -1}", "-1", "at_s", "-1: Input should be greater than or equal to 0"),
        ("{kind: link_loss, at_s: 1, for_s: 0}", "0", "for_s", "0: Input should be greater than 0"),
        ("{kind: link_loss, at_s: 1, direction: up}", "up", "direction", "'up': Input should be 'both', 'uplink' or 'downlink'"),
        ("{kind: gps_glitch, at_s: 1, offset_m: -3}", "-3", "offset_m", "-3: Input should be greater than 0"),
        ("{kind: gps_glitch, at_s: 1}", "{", "offset_m", "required field is missing"),
        ("{kind: rc_takeover, at_s: 1, channel: 6.0}", "6.0", "channel", "expected an integer, got number 6.0"),
        ("{kind: rc_takeover, at_s: 1, disarm: 'yes'}", "'yes'", "disarm", "expected true or false, got string 'yes'"),
        ("{kind: rc_takeover, at_s: 1, mode: on}", "on}", "mode", "expected a string, got bool true (YAML 1.1 reads on as a boolean)"),
        (
            "{kind: compass_bias, at_s: 1, bias_deg: 20, bias: 20}",
            "bias:",
            "bias",
            "unknown field (did you mean bias_deg? allowed: at_s, for_s, kind, bias_deg)",
        ),
        ("{kind: battery_sag, at_s: 1}", "{", "", "a battery sag needs drop_v or drop_pct"),
        ("{kind: meteor, at_s: 1}", "meteor", "kind", f"'meteor': {KIND_TAGS}"),
        ("{kind: 5, at_s: 1}", "5", "kind", f"5: {KIND_TAGS}"),
        ("{at_s: 1, for_s: 2}", "{", "kind", "required field is missing"),
        ("{kind: rc_loss, at_s: 1, failsafe_mode: ALT_HOLD}", "ALT_HOLD", "failsafe_mode", f"'ALT_HOLD': not a rover mode {ROVER_MODES}"),
    ],
)
def test_a_bad_fault_is_located_at_its_value(tmp_path: Path, fault: str, at: str, field: str, message: str) -> None:
    """The second fault is bad; ``at`` is where in its line the error points (``{``: the fault itself)."""
    path = write(tmp_path, f"version: 1\nfaults:\n  - at_s: 0.5\n    kind: link_loss\n  - {fault}\n")
    located = f"faults[1].{field}" if field else "faults[1]"
    assert errors_of(path, "rover") == [f"{path}:5:{fault.index(at) + 5}: {located}: {message}"]


def test_modes_are_checked_against_any_firmware_without_a_vehicle(tmp_path: Path) -> None:
    path = write(tmp_path, "version: 1\nfaults:\n  - {kind: rc_takeover, at_s: 1, mode: QHOVER}\n")
    assert load_faults(path).faults[0].mode == "QHOVER"  # a VTOL's
    assert errors_of(path, "boat")[0].endswith(f"faults[0].mode: 'QHOVER': not a boat mode {ROVER_MODES}")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("- {kind: link_loss, at_s: 1}\n", "1:1: (fault list): expected a mapping of fault list fields, got a list"),
        ("version: 2\nfaults: []\n", "1:10: version: 2: Input should be 1"),
        ("version: 1\nfaults: []\n", "2:9: faults: List should have at least 1 item after validation, not 0"),
        ("version: 1\nfaults:\n  - link_loss\n", "3:5: faults[0]: expected a mapping, got string 'link_loss'"),
        ("version: 1\nfaults:\n  - {kind: link_loss, at_s: 1, at_s: 2}\n", "3:32: faults[0].at_s: duplicate key (an earlier one is ignored)"),
        ("", "1:1: (fault list): the file holds no YAML document (it is empty or only comments)"),
    ],
)
def test_a_bad_document_is_located(tmp_path: Path, text: str, expected: str) -> None:
    path = write(tmp_path, text)
    assert errors_of(path)[0] == f"{path}:{expected}"


def test_a_missing_file(tmp_path: Path) -> None:
    assert errors_of(tmp_path / "none.yaml") == [f"{tmp_path / 'none.yaml'}:1:1: (file): No such file or directory"]


# -- the injector on messages (manual clock) -----------------------------------------------------


def telemetry() -> list[MAVLinkMessage]:
    """Fresh telemetry as the autopilot sends it: heading 10°, EKF ready, RC centred, 12 V 80 %."""
    sensors = m.MAV_SYS_STATUS_SENSOR_RC_RECEIVER | m.MAV_SYS_STATUS_SENSOR_GPS
    lat, lon = round(LAT * 1e7), round(LON * 1e7)
    return [
        MAV.heartbeat_encode(m.MAV_TYPE_GROUND_ROVER, m.MAV_AUTOPILOT_ARDUPILOTMEGA, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15, m.MAV_STATE_ACTIVE),
        MAV.attitude_encode(0, 0.0, 0.0, math.radians(10.0), 0.0, 0.0, 0.0),
        MAV.vfr_hud_encode(1.0, 1.0, 10, 20, 0.0, 0.0),
        MAV.global_position_int_encode(0, lat, lon, 0, 0, 100, 0, 0, 1000),
        MAV.gps_raw_int_encode(0, m.GPS_FIX_TYPE_3D_FIX, lat, lon, 0, 121, 200, 100, 1000, 10),
        MAV.ekf_status_report_encode(EKF_READY, 0.02, 0.01, 0.01, 0.03, 0.0),
        MAV.rc_channels_encode(0, 16, *[1500] * 16, 0, 0, 255),
        MAV.sys_status_encode(sensors, sensors, sensors, 150, 12000, 250, 80, 0, 0, 0, 0, 0, 0),
    ]


def fields(messages: list[MAVLinkMessage]) -> dict[str, dict[str, Any]]:
    return {msg.get_type(): msg.to_dict() for msg in messages}


def seen_at(injector: FaultInjector, clock: ManualClock, t: float) -> dict[str, dict[str, Any]]:
    """What leaves the vehicle ``t`` seconds after boot."""
    clock.sleep_until(t)
    return fields(injector.transform(telemetry()))


def _ekf_degraded(seen: dict[str, dict[str, Any]]) -> None:
    ekf = seen["EKF_STATUS_REPORT"]
    variances = [ekf[k] for k in ("velocity_variance", "pos_horiz_variance", "pos_vert_variance", "compass_variance")]
    assert variances == pytest.approx([1.5] * 4)
    assert (ekf["terrain_alt_variance"], ekf["flags"]) == (0.0, EKF_READY)


def _position_lost(seen: dict[str, dict[str, Any]]) -> None:
    flags = seen["EKF_STATUS_REPORT"]["flags"]
    assert not flags & m.EKF_POS_HORIZ_ABS and flags & m.EKF_CONST_POS_MODE and flags & m.EKF_ATTITUDE


def _glitched(seen: dict[str, dict[str, Any]]) -> None:
    for kind in ("GLOBAL_POSITION_INT", "GPS_RAW_INT"):
        distance, bearing = geo.distance_bearing(LAT, LON, seen[kind]["lat"] / 1e7, seen[kind]["lon"] / 1e7)
        assert (distance, bearing) == (pytest.approx(15.0, abs=0.02), pytest.approx(135.0, abs=0.1))
    ekf = seen["EKF_STATUS_REPORT"]
    assert ekf["flags"] == EKF_READY | m.EKF_GPS_GLITCHING and ekf["pos_horiz_variance"] >= 1.0 and ekf["velocity_variance"] < 0.1


def _heading(offset_deg: float) -> Callable[[dict[str, dict[str, Any]]], None]:
    def check(seen: dict[str, dict[str, Any]]) -> None:
        expected = (10.0 + offset_deg) % 360.0
        assert math.degrees(seen["ATTITUDE"]["yaw"]) % 360.0 == pytest.approx(expected, abs=0.01)
        assert seen["GLOBAL_POSITION_INT"]["hdg"] == round(expected * 100)
        assert seen["VFR_HUD"]["heading"] == round(expected) % 360
        assert seen["GPS_RAW_INT"]["cog"] == 1000  # the GPS course over ground knows nothing of the compass

    return check


def _rc_lost(seen: dict[str, dict[str, Any]]) -> None:
    rc = seen["RC_CHANNELS"]
    assert (rc["chancount"], rc["rssi"]) == (0, 0) and not any(rc[f"chan{n}_raw"] for n in range(1, 19))
    assert not seen["SYS_STATUS"]["onboard_control_sensors_health"] & m.MAV_SYS_STATUS_SENSOR_RC_RECEIVER


def _sagged(seen: dict[str, dict[str, Any]]) -> None:
    assert (seen["SYS_STATUS"]["voltage_battery"], seen["SYS_STATUS"]["battery_remaining"]) == (10500, 50)


@pytest.mark.parametrize(
    ("fault", "check"),
    [
        ({"kind": "ekf_degradation", "variance": 1.5}, _ekf_degraded),
        ({"kind": "ekf_degradation", "variance": 0.0, "lose_position": True}, _position_lost),
        ({"kind": "gps_glitch", "offset_m": 15.0, "bearing_deg": 135.0}, _glitched),
        ({"kind": "compass_bias", "bias_deg": -20.0}, _heading(-20.0)),
        ({"kind": "compass_glitch", "amplitude_deg": 45.0, "period_s": 8.0}, _heading(45.0)),  # a quarter period in: the top of the swing
        ({"kind": "rc_loss"}, _rc_lost),
        ({"kind": "battery_sag", "drop_v": 1.5, "drop_pct": 30}, _sagged),
    ],
    ids=lambda v: v["kind"] if isinstance(v, dict) else "",
)
def test_each_kind_transforms_telemetry_only_while_active(fault: dict[str, Any], check: Callable[[dict[str, dict[str, Any]]], None]) -> None:
    clock = ManualClock(100.0)
    injector = FaultInjector(plan({**fault, "at_s": 10.0, "for_s": 5.0}), clock)
    untouched = fields(telemetry())
    assert seen_at(injector, clock, 109.9) == untouched
    seen = seen_at(injector, clock, 112.0)
    check(seen)
    assert seen["HEARTBEAT"] == untouched["HEARTBEAT"]
    assert seen_at(injector, clock, 115.1) == untouched


def test_a_compass_glitch_swings_both_ways() -> None:
    clock = ManualClock()
    injector = FaultInjector(plan({"kind": "compass_glitch", "at_s": 10.0, "amplitude_deg": 30.0, "period_s": 4.0}), clock)
    assert [round(injector.heading_offset_deg(t), 6) for t in (9.0, 10.0, 11.0, 12.0, 13.0, 1000.0)] == [0.0, 0.0, 30.0, 0.0, -30.0, 0.0]


def test_overlapping_compass_faults_add_up() -> None:
    clock = ManualClock()
    injector = FaultInjector(
        plan({"kind": "compass_bias", "at_s": 0.0, "bias_deg": 20.0}, {"kind": "compass_bias", "at_s": 5.0, "bias_deg": 350.0 - 360}), clock
    )
    assert (injector.heading_offset_deg(1.0), injector.heading_offset_deg(6.0)) == (20.0, 10.0)


@pytest.mark.parametrize(("direction", "receiving", "sending"), [("both", False, False), ("uplink", False, True), ("downlink", True, False)])
def test_link_loss_silences_its_direction_only_while_active(direction: str, receiving: bool, sending: bool) -> None:
    clock = ManualClock()
    injector = FaultInjector(plan({"kind": "link_loss", "at_s": 10.0, "for_s": 5.0, "direction": direction}), clock)
    during = []
    for t in (9.9, 12.0, 15.0):
        clock.sleep_until(t)
        during.append((injector.receiving, injector.sending, len(injector.transform(telemetry()))))
    assert during == [(True, True, 8), (receiving, sending, 8 if sending else 0), (True, True, 8)]
    assert [type(f) for f in injector.active(12.0)] == [LinkLoss]


# -- the injector on the autopilot -----------------------------------------------------------------


def armed_rover(clock: ManualClock, mode: str = "GUIDED") -> FirmwareSim:
    ap = make_autopilot("rover", clock, HOME, ekf_ready_after_s=1.0)
    ap.update()
    for _ in range(20):
        clock.advance(0.1)
        ap.update()
    assert ap.set_mode(ap.profile.modes[mode])
    ap.handle(command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1))
    assert ap.armed
    return ap


def command(cmd: int, *params: float) -> MAVLinkMessage:
    msg = encoder(*GCS).command_long_encode(1, 1, cmd, 0, *(list(params) + [0.0] * 7)[:7])
    msg.pack(encoder(*GCS))
    return msg


def run(injector: FaultInjector, ap: FirmwareSim, until: float, step: float = 0.1) -> list[MAVLinkMessage]:
    """As the server does: effects, the autopilot, the link; until ``until`` seconds of injector time."""
    out: list[MAVLinkMessage] = []
    clock = injector.clock
    assert isinstance(clock, ManualClock)
    while injector.elapsed_s < until - 1e-9:
        clock.advance(step)
        injector.update(ap)
        out += injector.transform(ap.update())
    return out


def test_rc_takeover_flips_the_channel_switches_the_mode_and_disarms_then_puts_the_switch_back() -> None:
    clock = ManualClock()
    ap = armed_rover(clock)
    injector = FaultInjector(plan({"kind": "rc_takeover", "at_s": 1.0, "for_s": 2.0, "mode": "MANUAL", "disarm": True}), clock)
    injector.attach(ap)
    run(injector, ap, 0.9)
    assert (ap.rc_channels[5], ap.mode, ap.armed) == (1000, "GUIDED", True)
    out = run(injector, ap, 1.5)
    assert (ap.rc_channels[5], ap.mode, ap.armed) == (1900, "MANUAL", False)
    assert any(msg.get_type() == "RC_CHANNELS" and msg.chan6_raw == 1900 for msg in out)
    assert "Throttle disarmed" in [msg.text for msg in out if msg.get_type() == "STATUSTEXT"]
    run(injector, ap, 3.5)
    assert (ap.rc_channels[5], ap.mode, ap.armed) == (1000, "MANUAL", False)  # the mode stays where the pilot left it


def test_rc_takeover_on_another_channel_leaves_the_mode_alone() -> None:
    clock = ManualClock()
    ap = armed_rover(clock)
    injector = FaultInjector(plan({"kind": "rc_takeover", "at_s": 1.0, "channel": 8, "pwm": 1100}), clock)
    run(injector, ap, 2.0)
    assert (ap.rc_channels[7], ap.rc_channels[5], ap.mode, ap.armed) == (1100, 1000, "GUIDED", True)
    assert isinstance(injector.faults[0], RcTakeover)


@pytest.mark.parametrize(("armed", "mode_after"), [(True, "HOLD"), (False, "GUIDED")])
def test_rc_loss_failsafe_acts_after_fs_timeout_on_an_armed_vehicle_only(armed: bool, mode_after: str) -> None:
    clock = ManualClock()
    ap = armed_rover(clock)
    if not armed:
        ap.disarm()
    injector = FaultInjector(plan({"kind": "rc_loss", "at_s": 1.0, "for_s": 3.0, "failsafe_mode": "HOLD"}), clock)
    run(injector, ap, 2.4)
    assert ap.mode == "GUIDED"  # FS_TIMEOUT (1.5 s) not over yet
    run(injector, ap, 2.6)
    assert ap.mode == mode_after
    assert ap.set_mode(ap.profile.modes["GUIDED"])
    run(injector, ap, 6.0)
    assert ap.mode == "GUIDED"  # once per loss


def test_losing_the_ekf_position_refuses_position_modes_until_the_firmware_latch_clears() -> None:
    # Rover/ekf_check.cpp at 10 Hz: 10 bad checks latch failsafe.ekf, 10 good ones count down to clear it, and
    # Mode::enter (Rover/mode.cpp) refuses a position mode meanwhile: about 1 s after the EKF is good again
    clock = ManualClock()
    ap = armed_rover(clock, "HOLD")
    injector = FaultInjector(plan({"kind": "ekf_degradation", "at_s": 1.0, "for_s": 2.0, "lose_position": True}), clock)
    out = run(injector, ap, 2.5)
    assert not ap.position_ok and ap.failsafe_ekf
    # in HOLD, a mode that needs no position: latched, not announced (failsafe_ekf_event returns first)
    assert "EKF failsafe" not in [msg.text for msg in out if msg.get_type() == "STATUSTEXT"]
    assert not ap.set_mode(ap.profile.modes["LOITER"])
    out = run(injector, ap, 3.5)  # the EKF is good again for 0.5 s: still latched
    assert ap.position_ok and ap.failsafe_ekf
    assert not ap.set_mode(ap.profile.modes["LOITER"])
    out += run(injector, ap, 4.5)
    assert not ap.failsafe_ekf
    assert "EKF failsafe cleared" in [msg.text for msg in out if msg.get_type() == "STATUSTEXT"]
    assert ap.set_mode(ap.profile.modes["LOITER"])


def test_a_biased_compass_makes_the_vehicle_steer_off_while_the_telemetry_shows_it_on_course() -> None:
    clock = ManualClock()
    ap = armed_rover(clock)
    injector = FaultInjector(plan({"kind": "compass_bias", "at_s": 0.0, "for_s": 10.0, "bias_deg": 30.0}), clock)
    target = geo.destination(LAT, LON, 0.0, 200.0)
    ap.vehicle.drive_to(*target)
    out = run(injector, ap, 8.0)
    bearing = ap.vehicle.bearing_to(*target)
    assert ap.vehicle.heading_deg == pytest.approx((bearing - 30.0) % 360.0, abs=3.0)  # really heading 30° off
    reported = [msg for msg in out if msg.get_type() == "ATTITUDE"][-1]
    assert math.degrees(reported.yaw) % 360.0 == pytest.approx(bearing, abs=3.0)  # yet the compass says "on course"
    run(injector, ap, 16.0)
    assert ap.vehicle.heading_deg == pytest.approx(ap.vehicle.bearing_to(*target), abs=3.0)  # steers straight again


# -- over a real UDP link ------------------------------------------------------------------------


@contextlib.contextmanager
def serve(*faults: dict[str, Any]) -> Iterator[SimServer]:
    """The rover served lock-step: it steps (:func:`step`) when the reader finds nothing to read, its thread never started.

    On a 50x clock of its own its thread, starved 0.4 s on a busy machine, stepped from 2 s to 22 s of vehicle time at once:
    the test had stopped reading before the heartbeats after the loss were sent."""
    clock = SteppedClock(50.0)
    sim = SimServer("rover", clock=clock, home=HOME, ekf_ready_after_s=2.0, faults=FaultInjector(plan(*faults), clock))
    clock.servers.append(sim)
    try:
        yield sim
    finally:
        sim.stop()


def step(sim: SimServer) -> None:
    """Nothing to read: the simulated world moves on a step (and says what it has to say)."""
    sim.clock.sleep_until(sim.clock.now() + SteppedClock.STEP_S)


def test_the_server_and_the_injector_must_share_a_clock() -> None:
    with pytest.raises(ValueError, match="share one clock"):
        SimServer("rover", clock=ScaledClock(), faults=FaultInjector(plan({"kind": "rc_loss", "at_s": 1.0}), ScaledClock()))


def test_link_loss_stops_heartbeats_for_its_duration_and_loses_what_is_sent_meanwhile() -> None:
    loss = (6.0, 16.0)  # vehicle seconds: 0.2 s of wall time at 50x
    with serve({"kind": "link_loss", "at_s": loss[0], "for_s": loss[1] - loss[0]}) as sim:
        assert sim.faults is not None
        conn = mavutil.mavlink_connection(sim.url_for_client, source_system=GCS[0], source_component=GCS[1], dialect="ardupilotmega")
        try:
            conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)  # udpin answers peers it has heard
            # (vehicle time it was sent at: the stamp of the ATTITUDE before it in the stream, not when this thread got to it; custom mode)
            heartbeats: list[tuple[float, int]] = []
            stamps: list[float] = []  # vehicle time each ATTITUDE was sent at, by its own stamp
            sent_during_loss = False
            while sim.faults.elapsed_s < loss[1] + 6.0:
                if not sent_during_loss and loss[0] + 2.0 <= sim.faults.elapsed_s < loss[1] - 2.0:
                    conn.mav.command_long_send(1, 1, m.MAV_CMD_DO_SET_MODE, 0, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 0, 0, 0, 0, 0)
                    sent_during_loss = True
                msg = conn.recv_msg()
                if msg is None:
                    step(sim)
                elif msg.get_type() == "HEARTBEAT":
                    heartbeats.append((stamps[-1] if stamps else 0.0, msg.custom_mode))
                elif msg.get_type() == "ATTITUDE":
                    stamps.append(msg.time_boot_ms / 1000.0)
        finally:
            conn.close()
    received = [t for t, _ in heartbeats]
    assert any(t < loss[0] for t in received), received
    # by the vehicle's own stamps, a heartbeat carrying the ATTITUDE's before it: a step or two of margin at both ends (seen: the
    # first heartbeat after the loss stamped 15.988, its ATTITUDE sent in the loss's last step)
    assert not [t for t in received if loss[0] + 0.2 < t < loss[1] - 0.2], received
    assert not [t for t in stamps if loss[0] + 0.1 < t < loss[1] - 0.1], stamps
    after = [mode for t, mode in heartbeats if t >= loss[1]]
    assert after, received
    assert sent_during_loss and set(after) == {0}  # still MANUAL: the mode change sent during the loss was lost, not queued


def test_rc_takeover_shows_in_rc_channels_and_the_mode() -> None:
    with serve({"kind": "rc_takeover", "at_s": 3.0, "for_s": 6.0, "mode": "HOLD"}) as sim:
        conn = mavutil.mavlink_connection(sim.url_for_client, source_system=GCS[0], source_component=GCS[1], dialect="ardupilotmega")
        try:
            conn.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            want = [
                ("RC_CHANNELS", lambda msg: msg.chan6_raw == 1900),
                ("HEARTBEAT", lambda msg: msg.custom_mode == 4),
                ("RC_CHANNELS", lambda msg: msg.chan6_raw == 1000),
            ]
            while want and sim.clock.now() < 30.0:  # vehicle time: the take-over is over at 9 s
                msg = conn.recv_msg()
                if msg is None:
                    step(sim)
                elif msg.get_type() == want[0][0] and want[0][1](msg):
                    want.pop(0)
        finally:
            conn.close()
    assert not want, f"never saw {want[0][0]} as expected"


# -- the command line ----------------------------------------------------------------------------


BAD = "version: 1\nfaults:\n  - kind: link_loss\n    at_s: -5\n"


def test_run_refuses_a_bad_fault_file_before_anything_starts(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = write(tmp_path, BAD)
    assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--faults", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:4:11: faults[0].at_s: -5: Input should be greater than or equal to 0" in err
    assert "simulated" not in err


def test_run_checks_modes_against_the_missions_vehicle(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = write(tmp_path, "version: 1\nfaults:\n  - {kind: rc_takeover, at_s: 1, mode: QHOVER}\n")
    assert main(["run", str(ROOT / "missions/rover_square.yaml"), "--faults", str(bad)]) == 2
    assert f"{bad}:3:40: faults[0].mode: 'QHOVER': not a rover mode" in capsys.readouterr().err


def test_run_refuses_faults_with_a_real_vehicle(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", str(ROOT / "missions/rover_square.yaml"), "--mavlink", "udpout:127.0.0.1:9", "--faults", str(EXAMPLES[0])]
    assert main(argv) == 2
    assert "--faults applies to the built-in simulator only; it cannot be used with --mavlink" in capsys.readouterr().err


def parse_sim(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="executive")
    sim_cli.register(parser.add_subparsers())
    return parser.parse_args(["sim", *argv])


def test_sim_refuses_a_bad_fault_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = write(tmp_path, BAD)
    args = parse_sim("--mavlink", "udpin:127.0.0.1:0", "--faults", str(bad))
    assert args.func(args) == 2
    captured = capsys.readouterr()
    assert f"{bad}:4:11: faults[0].at_s:" in captured.err and "listening" not in captured.out


def test_sim_injects_a_good_fault_file(capsys: pytest.CaptureFixture[str]) -> None:
    path = ROOT / "missions/faults/gps_glitch.yaml"
    args = parse_sim("--mavlink", "udpin:127.0.0.1:0", "--speedup", "50", "--duration", "1", "--faults", str(path))
    assert args.func(args) == 0
    assert f"injecting 1 fault(s) from {path}" in capsys.readouterr().out
    assert isinstance(load_faults(path).faults[0], GpsGlitch)


def test_rc_input_moves_sticks_and_switches_then_puts_them_back(tmp_path):
    from executive.sim.faults import FaultInjector, load_faults
    from executive.sim.registry import make_autopilot
    from executive.world.clock import ManualClock

    path = tmp_path / "operator.yaml"
    events = ["{kind: rc_input, at_s: 5, for_s: 3, channels: {3: 1900, 7: 1000}}", "{kind: rc_input, at_s: 6, channels: {8: 2000}}"]
    path.write_text("version: 1\nfaults:\n" + "".join(f"  - {e}\n" for e in events))
    clock = ManualClock()
    autopilot = make_autopilot("rover", clock)
    injector = FaultInjector(load_faults(path), clock)
    injector.attach(autopilot)
    seen = []
    for _ in range(10):
        clock.advance(1.0)
        injector.update(autopilot)
        seen.append((autopilot.rc_channels[2], autopilot.rc_channels[6], autopilot.rc_channels[7]))
    assert seen[3] == (1500, 1500, 1500)  # 4 s
    assert seen[4] == (1900, 1000, 1500)  # 5 s: sticks and switch C moved
    assert seen[6] == (1900, 1000, 2000)  # 7 s: switch D too, for good
    assert seen[8] == (1500, 1500, 2000)  # 9 s: the first input is over, switch D stays


def test_rc_input_is_validated(tmp_path):
    from executive.mission.errors import MissionError
    from executive.sim.faults import load_faults

    path = tmp_path / "bad.yaml"
    path.write_text("version: 1\nfaults:\n  - {kind: rc_input, at_s: 5, channels: {17: 1900}}\n")
    with pytest.raises(MissionError) as refused:
        load_faults(path)
    assert any("channels" in str(e) and ":3:" in str(e) for e in refused.value.errors)


def test_px4_mode_names_are_checked_against_px4_and_steer_a_simulated_px4(tmp_path: Path) -> None:
    bad = write(tmp_path, "version: 1\nfaults:\n  - {kind: rc_takeover, at_s: 4, mode: QLAND}\n")
    with pytest.raises(FaultFileError, match="'QLAND': not a PX4 mode"):
        load_faults(bad, "vtol", autopilot="px4")
    path = write(tmp_path, "version: 1\nfaults:\n  - {kind: rc_takeover, at_s: 4, mode: AUTO.LAND}\n")
    assert "not a vtol mode" in errors_of(path, "vtol")[0]  # ArduPlane has no such mode
    clock = ManualClock()
    ap = make_autopilot("vtol", clock, HOME, autopilot="px4")
    injector = FaultInjector(load_faults(path, "vtol", autopilot="px4"), clock)
    injector.attach(ap)
    for _ in range(50):  # 5 s: the estimator has a position at 3 s, the pilot switches at 4 s
        clock.advance(0.1)
        injector.update(ap)
        ap.update()
    assert ap.mode == "AUTO.LAND"
