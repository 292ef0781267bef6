"""Pre-flight refuses a mission whose RC switches use the autopilot's own mode-switch channel (ArduRover MODE_CH)."""

from __future__ import annotations

from pathlib import Path

import pytest
from py_trees.common import Status

from executive.autopilot_link.parameters import ParameterWatch
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.mission.rules import rc_switch_channels
from executive.testing import EKF_READY, Harness
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink

UGV = Path(__file__).parents[2] / "missions" / "ugv_rc_route.yaml"


def rover(**rc: object) -> Mission:
    return Mission.model_validate(
        {"version": 1, "name": "m", "vehicle": "rover", "auto_arm": True, "rc": rc, "waypoints": [{"lat": 1.0, "lon": 1.0}]}
    )


def test_the_mission_switch_channels():
    assert rc_switch_channels(rover()) == {6: "the take-over switch"}
    assert rc_switch_channels(rover(source="can")) == {}
    asv = load_mission(Path(__file__).parents[2] / "missions" / "asv_sampling.yaml")
    assert asv.rc.arm_channel == 5  # goto_sample: the ASV seed's arm switch, by default
    assert rc_switch_channels(asv) == {5: "the arm switch", 6: "the take-over switch"}
    ugv = load_mission(UGV)
    assert rc_switch_channels(ugv) == {5: "switch A", 6: "switch B", 7: "switch C", 8: "switch D", 9: "knob VRA"}


@pytest.mark.parametrize(
    ("params", "status", "feedback"),
    [
        ({"MODE_CH": 8.0}, Status.FAILURE, "RC channel 8 (switch D) is the autopilot's mode switch (MODE_CH = 8)"),
        ({"MODE_CH": 0.0}, Status.SUCCESS, "MODE_CH = 0: no mission switch on it"),
    ],
)
def test_the_ugv_mission_is_refused_before_arming_when_switch_d_is_the_mode_switch(params, status, feedback):
    """Issue 13: MODE_CH 8 is the UGV's arm switch D; switching D put the rover in MANUAL with no command from the executive."""
    h = Harness.build(load_mission(UGV))
    h.vehicle.set(link__up=True, vehicle__ekf=EKF_READY, vehicle__mode="MANUAL", vehicle__params=params)
    h.tick()
    node = h.node("Mode switch clear?")
    assert node.status == status
    assert feedback in node.feedback_message
    if status is Status.FAILURE:
        assert h.root.status == Status.FAILURE and h.asked() == []  # nothing armed or set
        assert "set MODE_CH to a channel the mission does not use (0: none)" in node.feedback_message


def test_pre_flight_checks_the_switch_before_arming(square_mission):
    clash = square_mission.model_copy(update={"rc": square_mission.rc.model_copy(update={"takeover_channel": 8})})
    h = Harness.build(clash)
    h.vehicle.set(link__up=True, vehicle__ekf=EKF_READY, vehicle__mode="HOLD", vehicle__params={"MODE_CH": 8.0})
    assert h.tick() == Status.FAILURE
    assert h.asked() == []
    assert "RC channel 8 (the take-over switch)" in h.node("Pre-flight/Mode switch clear?").feedback_message


def test_the_runtime_asks_for_the_parameter_until_it_answers(square_mission):
    h = Harness.build(square_mission)
    clock: ManualClock = h.clock
    watch = ParameterWatch(h.autopilot, clock, retry_s=1.0, tries=3)
    h.vehicle.set(link__up=True, vehicle__params=None)  # the harness's vehicle has told it: this one has not
    for _ in range(40):  # 4 s
        clock.advance(0.1)
        watch.service()
        h.commander.flush()
    asked = h.link.take("PARAM_REQUEST_READ")
    assert [m.param_id for m in asked if m.param_id == "MODE_CH"] == ["MODE_CH"] * 3  # once a second, 3 tries
    assert (asked[0].target_system, asked[0].param_index) == (1, -1)
    h.vehicle.set(vehicle__params={"MODE_CH": 8.0})
    watch.tries = 10
    clock.advance(2.0)
    watch.service()
    h.commander.flush()
    assert [m.param_id for m in h.link.take("PARAM_REQUEST_READ") if m.param_id == "MODE_CH"] == []  # answered: not asked again
    assert asked[0].get_msgId() == mavlink.MAVLINK_MSG_ID_PARAM_REQUEST_READ
