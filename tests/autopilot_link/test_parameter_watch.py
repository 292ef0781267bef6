"""The parameters read at pre-flight: the mode-switch channel and, for ArduRover, those of its driving (the look-ahead's)."""

from __future__ import annotations

import logging

import pytest

from executive.autopilot.ardupilot import ArduPilotPort
from executive.autopilot.px4 import Px4Port
from executive.autopilot.rover_motion import MOTION_PARAMS, vehicle_motion
from executive.autopilot_link.parameters import ParameterWatch, wanted_parameters
from executive.testing import Harness
from executive.world.dialect import mavlink
from executive.world.vehicles import PROFILES


def run(watch: ParameterWatch, h: Harness, seconds: float) -> list[str]:
    for _ in range(round(seconds / 0.1)):
        h.clock.advance(0.1)
        watch.service()
        h.commander.flush()
    return [m.param_id for m in h.link.take("PARAM_REQUEST_READ")]


def test_an_ardurover_is_asked_its_driving_parameters_until_each_answers(square_mission, caplog: pytest.LogCaptureFixture) -> None:
    h = Harness.build(square_mission)
    battery = ("BATT_MONITOR", "BATT_CAPACITY", "BATT_ARM_MAH", "BATT_ARM_VOLT")  # the energy rule's
    assert wanted_parameters(h.autopilot) == ("MODE_CH", *MOTION_PARAMS, *battery)
    watch = ParameterWatch(h.autopilot, h.clock, retry_s=1.0, tries=3)
    h.vehicle.set(link__up=True, vehicle__params=None)  # an autopilot that has answered nothing yet
    asked = run(watch, h, 1.0)
    assert sorted(asked) == sorted(["MODE_CH", *MOTION_PARAMS, *battery])  # all at once, one each
    h.vehicle.set(vehicle__params={"MODE_CH": 8.0, "WP_SPEED": 5.0, "WP_RADIUS": 3.0} | dict.fromkeys(battery, 0.0))
    asked = run(watch, h, 1.0)
    assert "WP_SPEED" not in asked and "MODE_CH" not in asked and "ATC_ACCEL_MAX" in asked  # the rest again
    with caplog.at_level(logging.WARNING, logger="executive.autopilot_link.parameters"):
        asked += run(watch, h, 10.0)
    assert asked.count("ATC_ACCEL_MAX") == 2  # 3 tries in all, then given up
    (record,) = caplog.records
    assert record.getMessage().startswith("the autopilot never answered WP_ACCEL, WP_JERK, WP_PIVOT_ANGLE, ATC_ACCEL_MAX")
    assert "the look-ahead takes the firmware's defaults (WP_ACCEL 0, WP_JERK 0, WP_PIVOT_ANGLE 60, ATC_ACCEL_MAX 1" in record.getMessage()
    assert run(watch, h, 5.0) == []  # said once, never asked again


def test_the_look_ahead_drives_by_what_the_vehicle_said_and_the_defaults_for_the_rest(square_mission) -> None:
    h = Harness.build(square_mission)
    motion = vehicle_motion(h.autopilot.capabilities, {"WP_SPEED": 5.0, "ATC_ACCEL_MAX": 2.0, "SERVO1_FUNCTION": 73.0, "SERVO3_FUNCTION": 74.0})
    assert motion is not None
    assert (motion.speed_m_s, motion.accel_max_m_s2, motion.radius_m, motion.skid_steering) == (5.0, 2.0, 2.0, True)
    assert "WP_RADIUS" in motion.defaulted and "WP_SPEED" not in motion.defaulted


def test_an_autopilot_whose_driving_is_not_modelled_is_asked_only_its_mode_channel(square_mission) -> None:
    h = Harness.build(square_mission)
    h.autopilot.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_GROUND_ROVER)
    assert vehicle_motion(h.autopilot.capabilities, {"WP_SPEED": 5.0}) is None
    assert set(wanted_parameters(h.autopilot)) <= {"MODE_CH", "BAT1_CAPACITY", "BAT1_N_CELLS", "BAT1_V_EMPTY", "BAT1_V_CHARGED", "RTL_RETURN_ALT"}


@pytest.mark.parametrize(("port", "asked"), [(Px4Port, ["NAV_MC_ALT_RAD"]), (ArduPilotPort, [])])
def test_a_px4_vtol_is_asked_its_take_off_altitude_acceptance_and_an_ardupilot_one_is_not(square_mission, port, asked) -> None:
    """NAV_MC_ALT_RAD judges whose the loiter after PX4's take-off is (executive.autopilot.mode_cause); ArduPilot has none."""
    h = Harness.build(square_mission)
    vtol = port(h.commander, None, PROFILES["vtol"])
    h.vehicle.set(link__up=True, vehicle__params=None)
    assert [name for name in run(ParameterWatch(vtol, h.clock), h, 1.0) if name.startswith("NAV_")] == asked


def test_the_simulated_ardurover_answers_them_as_the_firmware_types_them() -> None:
    from executive.sim import make_autopilot
    from executive.world.clock import ManualClock
    from executive.world.dialect import encoder

    ap = make_autopilot("bunker", ManualClock(), ekf_ready_after_s=1.0)
    ap.update()
    mav = encoder(255, 190)
    ap.clock.advance(2.0)  # type: ignore[attr-defined]
    ap.update()
    answers = {}
    for name in ("WP_SPEED", "WP_PIVOT_ANGLE", "SERVO1_FUNCTION", "SERVO3_FUNCTION", "ATC_TURN_MAX_G"):
        msg = mav.param_request_read_encode(1, 1, name.encode(), -1)
        msg.pack(mav)
        (value,) = ap.handle(msg)
        answers[name] = (value.param_value, value.param_type)
    assert answers["WP_SPEED"] == (1.0, mavlink.MAV_PARAM_TYPE_REAL32)  # set for the Bunker's 1.5 m/s tracks
    assert answers["WP_PIVOT_ANGLE"] == (60.0, mavlink.MAV_PARAM_TYPE_INT8)
    assert (answers["SERVO1_FUNCTION"][0], answers["SERVO3_FUNCTION"][0]) == (73.0, 74.0)  # ThrottleLeft, ThrottleRight
    assert answers["ATC_TURN_MAX_G"][0] == pytest.approx(0.6)
