"""SYS_STATUS of the simulated ArduPilots: every bit follows the firmware's own state, as GCS.cpp computes it (issue 12 item 4)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from executive.sim import make_autopilot
from executive.sim.faults import EkfDegradation, FaultInjector
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage
from executive.world.dialect import mavlink as m
from sim_support import EKF_READY_S, HOME, Gcs

if TYPE_CHECKING:
    MakeGcs = Callable[..., Gcs]

PREARM, AHRS, RC = m.MAV_SYS_STATUS_PREARM_CHECK, m.MAV_SYS_STATUS_AHRS, m.MAV_SYS_STATUS_SENSOR_RC_RECEIVER
RATE_ATTITUDE = m.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL | m.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
YAW, XY, Z = m.MAV_SYS_STATUS_SENSOR_YAW_POSITION, m.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL, m.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL


def status(gcs: Gcs) -> MAVLinkMessage:
    """The SYS_STATUS the autopilot sends now."""
    gcs.run(1.0)
    return gcs.last("SYS_STATUS")


def bits(gcs: Gcs, flag: int) -> tuple[bool, bool, bool]:
    """(present, enabled, healthy) of one SYS_STATUS bit now."""
    msg = status(gcs)
    fields = (msg.onboard_control_sensors_present, msg.onboard_control_sensors_enabled, msg.onboard_control_sensors_health)
    return tuple(bool(field & flag) for field in fields)  # type: ignore[return-value]


@pytest.mark.parametrize("kind", ["rover", "boat", "sub", "vtol", "bunker"])
def test_prearm_is_unhealthy_exactly_while_arming_is_refused(make_gcs: MakeGcs, kind: str) -> None:
    gcs = make_gcs(kind, run_s=EKF_READY_S - 2.0)
    assert bits(gcs, PREARM) == (True, True, False)
    assert gcs.arm() == m.MAV_RESULT_FAILED
    gcs.run(2.0)  # the EKF uses GPS now: the checks pass
    assert bits(gcs, PREARM) == (True, True, True)
    assert gcs.arm() == m.MAV_RESULT_ACCEPTED
    assert bits(gcs, PREARM) == (True, True, True)  # armed: healthy


def test_prearm_is_unhealthy_in_a_mode_that_cannot_arm(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("rover", ekf_ready=True)
    assert gcs.set_mode("RTL") == m.MAV_RESULT_ACCEPTED
    assert bits(gcs, PREARM)[2] is False
    assert gcs.arm() == m.MAV_RESULT_FAILED  # "PreArm: Mode not armable"
    assert gcs.set_mode("HOLD") == m.MAV_RESULT_ACCEPTED
    assert bits(gcs, PREARM)[2] is True


def test_sensors_are_present_enabled_and_healthy_once_booted(make_gcs: MakeGcs) -> None:
    gcs = make_gcs("rover")
    msg = status(gcs)
    for flag in (m.MAV_SYS_STATUS_SENSOR_3D_GYRO, m.MAV_SYS_STATUS_SENSOR_3D_ACCEL, AHRS, m.MAV_SYS_STATUS_SENSOR_GPS, RC):
        assert msg.onboard_control_sensors_present & msg.onboard_control_sensors_enabled & msg.onboard_control_sensors_health & flag


@pytest.mark.parametrize(
    ("kind", "mode", "enabled"),
    [
        ("rover", "MANUAL", 0),
        ("rover", "HOLD", 0),  # Rover's HOLD does not stabilise the heading
        ("rover", "GUIDED", RATE_ATTITUDE | YAW | XY),
        ("vtol", "MANUAL", 0),
        ("vtol", "QLOITER", RATE_ATTITUDE),
        ("vtol", "GUIDED", RATE_ATTITUDE | YAW | XY | Z),
        ("sub", "MANUAL", RATE_ATTITUDE | YAW),
        ("sub", "POSHOLD", RATE_ATTITUDE | YAW | XY | Z),
    ],
)
def test_controller_bits_follow_the_mode(make_gcs: MakeGcs, kind: str, mode: str, enabled: int) -> None:
    gcs = make_gcs(kind, ekf_ready=True)
    assert gcs.set_mode(mode) == m.MAV_RESULT_ACCEPTED
    msg = status(gcs)
    controls = RATE_ATTITUDE | YAW | XY | (Z if kind != "rover" else 0)
    assert msg.onboard_control_sensors_present & controls == controls
    assert msg.onboard_control_sensors_enabled & controls == enabled
    assert msg.onboard_control_sensors_health & controls == enabled


@pytest.mark.parametrize(("variance", "healthy"), [(1.5, False), (1.0, True)])
def test_ahrs_is_unhealthy_when_every_ekf_test_ratio_is_over_one(variance: float, healthy: bool) -> None:
    clock = ManualClock()
    ap = make_autopilot("rover", clock, HOME, ekf_ready_after_s=EKF_READY_S)
    faults = FaultInjector([EkfDegradation(kind="ekf_degradation", at_s=EKF_READY_S + 1.0, for_s=5.0, variance=variance)], clock)
    faults.attach(ap)
    seen: list[tuple[float, MAVLinkMessage]] = []  # (seconds after boot, SYS_STATUS)
    for _ in range(round((EKF_READY_S + 8.0) / 0.1)):
        clock.advance(0.1)
        faults.update(ap)
        seen += [(ap.elapsed_s, msg) for msg in faults.transform(ap.update()) if msg.get_type() == "SYS_STATUS"]
    during = [msg for t, msg in seen if EKF_READY_S + 1.0 <= t < EKF_READY_S + 6.0]
    assert len(during) >= 4 and all(bool(msg.onboard_control_sensors_health & AHRS) is healthy for msg in during)
    assert seen[-1][1].onboard_control_sensors_health & AHRS  # the fault is over
