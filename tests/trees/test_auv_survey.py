"""The AUV survey tree (the Zeno mission manager's rules), tick by tick against a scripted ArduSub, and once on the simulator."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from py_trees.common import Status

from executive.io.mavlink.commander import Commander
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.runtime.loop import explain_failure
from executive.testing import EKF_READY, ScriptedAutopilot
from executive.tree import select as mission_tree
from executive.world.clock import ManualClock
from executive.world.dialect import mavlink
from executive.world.geo import destination, distance
from executive.world.state import EkfFlags, EkfStatus, GlobalPosition, Rangefinder
from executive.world.vehicles import PROFILES
from tests_support import AUV_SURVEY_RUN, SubRun, sub_run

EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
START = (44.0950000, 9.8630000)
SEABED_M = 30.0
SONAR_MIN_M, SONAR_MAX_M = 0.5, 30.0  # RNGFND1_MIN/RNGFND1_MAX
LIMITS = {
    "max_goal_distance_m": 1000.0,
    "speed_m_s": {"min": 0.1, "max": 1.0},
    "depth_m": {"min": 0.0, "max": 100.0},
    "altitude_m": {"min": 2.0, "max": 100.0},
    "acceptance_radius_m": 2.0,
    "leg_timeout_s": 60.0,
    "recovery_timeout_s": 30.0,
    "ekf_wait_s": 60.0,
}
ROOT = Path(__file__).parents[2]
_M = mavlink


def at(lat_lon: tuple[float, float], bearing_deg: float, metres: float) -> dict[str, float]:
    lat, lon = destination(*lat_lon, bearing_deg, metres)
    return {"lat": lat, "lon": lon}


def sub_mission(*waypoints: dict[str, Any], **limits: Any) -> Mission:
    return Mission.model_validate(
        {
            "version": 1,
            "name": "survey",
            "vehicle": "sub",
            "tree": "auv_survey",
            "auto_arm": True,
            "limits": {**LIMITS, **limits},
            "waypoints": list(waypoints),
        }
    )


NORTH = at(START, 0.0, 30.0)
EAST = at((NORTH["lat"], NORTH["lon"]), 90.0, 30.0)
BACK = at((EAST["lat"], EAST["lon"]), 180.0, 30.0)
#: a depth leg, an altitude leg, and a depth leg without a speed
SURVEY = (
    {**NORTH, "name": "north", "control_mode": "depth", "depth_m": 5.0, "speed_m_s": 0.5},
    {**EAST, "name": "east", "control_mode": "altitude", "altitude_m": 20.0, "speed_m_s": 0.8},
    {**BACK, "name": "back", "control_mode": "depth", "depth_m": 3.0},
)


class ScriptedSub(ScriptedAutopilot):
    """An ArduSub that obeys at once: modes, arming, speed; in GUIDED it steps toward its setpoint, horizontally and vertically.

    ``commands`` is what it was told, readable: ``("mode", "GUIDED")``, ``("speed", 0.5)``,
    ``("depth", 5.0, "north")`` (a setpoint, named by the waypoint it is at or ``"in place"``;
    re-sent setpoints are listed once). SURFACE climbs and hands over to ALT_HOLD at the surface.
    Refusals are DENIED.
    """

    def __init__(self, harness: Any, mission: Mission, start: tuple[float, float] = START) -> None:
        self.mission = mission
        self.depth, self.seabed_m, self.speed_over_m_s = 0.0, SEABED_M, 0.0
        self.dz_m = 1.0
        self.depth_target: float | None = None
        self.position_known = True
        self.sonar = True
        self.sonar_silent = False  # the sonar stops reporting: the last reading stays on the blackboard and ages
        super().__init__(harness, start, step_m=8.0)
        self.refusal = _M.MAV_RESULT_DENIED

    @property
    def altitude(self) -> float:
        return self.seabed_m - self.depth

    def facts(self) -> dict[str, object]:
        facts: dict[str, object] = {"vehicle__mode": self.mode, "vehicle__armed": self.armed}
        if self.position_known:
            facts["vehicle__position"] = GlobalPosition(self.lat, self.lon, -self.depth, self.speed_over_m_s, 0, 0, 0, 0)
        good = self.sonar and SONAR_MIN_M <= self.altitude <= SONAR_MAX_M
        facts["vehicle__rangefinder"] = (
            Rangefinder(self.altitude, SONAR_MIN_M, SONAR_MAX_M, "good" if good else "invalid", self.h.clock.now()) if self.sonar else None
        )
        facts["vehicle__altitude_above_bottom_m"] = self.altitude if good else None
        if self.sonar_silent:
            del facts["vehicle__rangefinder"], facts["vehicle__altitude_above_bottom_m"]
        return facts

    def _where(self, lat: float, lon: float) -> str:
        return next((wp.name for wp in self.mission.waypoints if distance(lat, lon, wp.lat, wp.lon) < 0.05), "in place")

    def _record(self, entry: tuple[Any, ...]) -> None:
        if self.commands and self.commands[-1] == entry:
            return
        self.commands.append(entry)

    def enter_mode(self, mode: str) -> bool:
        self.mode = mode
        self.target = self.depth_target = None
        return True

    def on_command(self, msg: Any) -> int | None:
        if msg.command == _M.MAV_CMD_DO_CHANGE_SPEED:
            self.commands.append(("speed", round(msg.param2, 3)))
            return self.result_for("speed")
        if msg.command in (_M.MAV_CMD_DO_SET_MODE, _M.MAV_CMD_COMPONENT_ARM_DISARM):
            return super().on_command(msg)
        raise AssertionError(f"unexpected command {msg.command}")

    def on_setpoint(self, msg: Any) -> None:
        if msg.get_type() != "SET_POSITION_TARGET_GLOBAL_INT" or self.mode != "GUIDED":  # ignored silently elsewhere
            return
        lat, lon = msg.lat_int / 1e7, msg.lon_int / 1e7
        if msg.coordinate_frame == _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT:
            self._record(("depth", round(-msg.alt, 3), self._where(lat, lon)))
            self.depth_target = -msg.alt
        else:  # the terrain frame among them: ArduSub drops it without terrain data (GCS_MAVLink_Sub.cpp), never send it
            raise AssertionError(f"unexpected frame {msg.coordinate_frame}")
        self.target = (lat, lon)

    def move(self) -> None:
        if self.armed and self.mode == "GUIDED" and self.target is not None:
            super().move()
            if self.depth_target is not None:
                self.depth += max(-self.dz_m, min(self.dz_m, self.depth_target - self.depth))
        elif self.armed and self.mode == "SURFACE":
            self.depth = max(0.0, self.depth - self.dz_m)
            if self.depth <= 0.1:
                self.mode = "ALT_HOLD"  # ModeReason::SURFACE_COMPLETE


class Survey:
    """A mission's tree, started, over a scripted sub (at START unless told) with the EKF ready; notes the depths each leg ends at."""

    def __init__(self, harness: Any, vehicle: Any, clock: ManualClock, state: MissionState, mission: Mission, start: tuple[float, float]) -> None:
        self.clock, self.state, self.vehicle = clock, state, vehicle
        state.upload(mission)
        state.start()
        self.root = mission_tree.build(mission)
        self.h = harness(self.root)
        vehicle.set(link__up=True, vehicle__ekf=EKF_READY, rc__channels=(1500,) * 8)
        self.sub = ScriptedSub(self.h, mission, start)
        self.depths_at_leg_end: list[tuple[float, float]] = []
        advance = state.advance_leg

        def note_and_advance() -> None:
            self.depths_at_leg_end.append((self.sub.depth, self.sub.altitude))
            advance()

        state.advance_leg = note_and_advance  # type: ignore[method-assign]

    def run(self, ticks: int, until: Callable[[], bool] | None = None) -> list[Status]:
        return self.sub.run(ticks, until)

    def run_to_leg(self, index: int) -> None:
        assert self.run(500, until=lambda: self.state.legs.leg_index >= index)[-1] == Status.RUNNING
        assert self.state.legs.leg_index == index

    def under_way(self, kind: str, value: float, waypoint: str) -> None:
        """Run until the sub is going to ``waypoint`` at its depth or altitude, a step out."""
        assert self.run(100, until=lambda: self.sub.commands[-1] == (kind, value, waypoint))[-1] == Status.RUNNING
        self.run(1)


@pytest.fixture
def commander(link: Any, clock: ManualClock) -> Commander:
    """Replaces the shared rover's: ArduSub's mode numbers."""
    return Commander(link, clock, PROFILES["sub"])


@pytest.fixture
def mission_state() -> MissionState:
    """Replaces the shared square: each test uploads its own survey."""
    return MissionState()


MakeSurvey = Callable[..., Survey]


@pytest.fixture
def make_survey(harness: Any, vehicle: Any, clock: ManualClock, mission_state: MissionState) -> MakeSurvey:
    """``make_survey(mission, start=START)``: the :class:`Survey` of a mission (one per test)."""

    def make(mission: Mission, start: tuple[float, float] = START) -> Survey:
        return Survey(harness, vehicle, clock, mission_state, mission, start)

    return make


# -- the whole survey ----------------------------------------------------------------------------


def test_each_leg_sets_its_speed_reaches_its_depth_or_altitude_goes_there_then_the_sub_surfaces_and_holds(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    statuses = survey.run(400)
    assert statuses[-1] == Status.SUCCESS and set(statuses[:-1]) == {Status.RUNNING}
    assert survey.sub.commands == [
        ("arm", 1.0),
        ("mode", "GUIDED"),
        ("speed", 0.5), ("depth", 5.0, "in place"), ("depth", 5.0, "north"),
        # first where the sub is (it stopped on north), 20 m above the seabed as a depth: 5 m deep + 25 m measured - 20 m
        ("speed", 0.8), ("depth", 10.0, "north"), ("depth", 10.0, "east"),
        ("depth", 3.0, "east"), ("depth", 3.0, "back"),  # no speed on this leg: none is sent
        ("mode", "SURFACE"),
        ("mode", "POSHOLD"),
    ]  # fmt: skip
    assert survey.depths_at_leg_end == [(5.0, SEABED_M - 5.0), (SEABED_M - 20.0, 20.0), (3.0, SEABED_M - 3.0)]
    assert (survey.sub.mode, survey.sub.depth, survey.sub.armed) == ("POSHOLD", 0.0, True)  # held at the surface, armed for the pick-up
    assert survey.state.legs.leg_index == 3


@pytest.mark.parametrize(
    ("waypoint", "setpoints"),
    [
        ({"control_mode": "depth", "depth_m": 5.0}, [("depth", 5.0, "in place"), ("depth", 5.0, "wp")]),
        ({"depth_m": 5.0}, [("depth", 5.0, "in place"), ("depth", 5.0, "wp")]),  # no control mode: a depth
        ({"control_mode": "altitude", "altitude_m": 20.0}, [("depth", 10.0, "in place"), ("depth", 10.0, "wp")]),  # 30 m measured - 20 m
        ({"control_mode": "depth"}, [("depth", 0.0, "wp")]),  # no depth: at the surface
        ({"control_mode": "depth", "depth_m": 0.0}, [("depth", 0.0, "in place"), ("depth", 0.0, "wp")]),
    ],
    ids=["depth", "depth-by-default", "altitude", "depth-missing-surface", "depth-0"],
)
def test_the_control_mode_decides_the_setpoints_of_a_leg(make_survey: MakeSurvey, waypoint: dict[str, Any], setpoints: list[tuple[Any, ...]]) -> None:
    survey = make_survey(sub_mission({**NORTH, "name": "wp", **waypoint}))
    assert survey.run(100)[-1] == Status.SUCCESS
    assert [c for c in survey.sub.commands if c[0] == "depth"] == setpoints


def test_a_last_leg_at_the_surface_needs_no_surfacing(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission({**NORTH, "name": "wp", "control_mode": "depth", "depth_m": 0.0}))
    assert survey.run(100)[-1] == Status.SUCCESS
    assert survey.sub.commands[-2:] == [("depth", 0.0, "wp"), ("mode", "POSHOLD")]


# -- the 1 km rule: the whole mission, against the live position, once ---------------------------


@pytest.mark.parametrize(
    ("vehicle_at", "far", "refusal"),
    [
        (START, 999.0, None),
        (START, 1001.0, "waypoint 2 'far' is 1001 m away, over 1000 m"),
        (destination(*START, 180.0, 1100.0), 0.0, "waypoint 1 'north' is 1130 m away, over 1000 m"),  # the live position, not the plan
    ],
    ids=["999-m-accepted", "1001-m-refused", "vehicle-1.1-km-off"],
)
def test_a_waypoint_over_1_km_from_the_live_position_refuses_the_whole_mission_before_anything_is_sent(
    make_survey: MakeSurvey, vehicle_at: tuple[float, float], far: float, refusal: str | None
) -> None:
    far_leg = {"leg_timeout_s": 3600.0}  # refused for its distance, not for its time (issue 40)
    survey = make_survey(sub_mission(SURVEY[0], {**at(START, 90.0, far), "name": "far", "depth_m": 2.0}, **far_leg), start=vehicle_at)
    statuses = survey.run(1)
    if refusal is None:
        assert statuses == [Status.RUNNING]
        assert survey.sub.commands == [("arm", 1.0)]
        return
    assert statuses == [Status.FAILURE]
    assert (survey.sub.commands, survey.sub.received) == ([], 0)  # nothing at all went to the vehicle
    assert explain_failure(survey.root) == f"All waypoints within 1000 m?: {refusal}"


def test_acceptance_waits_for_the_ekf_then_for_a_position(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.vehicle.set(vehicle__ekf=EKF_LOST)
    assert survey.run(20) == [Status.RUNNING] * 20
    survey.sub.position_known = False
    survey.vehicle.set(vehicle__ekf=EKF_READY, vehicle__position=None)
    assert survey.run(20) == [Status.RUNNING] * 20
    assert survey.sub.received == 0
    survey.sub.position_known = True
    survey.sub.publish()
    assert survey.run(1) == [Status.RUNNING]
    assert survey.sub.commands == [("arm", 1.0)]


def test_no_position_within_the_ekf_wait_fails_the_mission(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.sub.position_known = False
    survey.vehicle.set(vehicle__position=None)
    statuses = survey.run(700)
    assert statuses[-1] == Status.FAILURE and len(statuses) == 602  # ekf_wait_s = 60 s at 10 Hz, then the tick that gives up
    assert explain_failure(survey.root) == "Wait until Position known?: gave up after 60 s: no position"
    assert survey.sub.received == 0


def test_the_1_km_rule_is_checked_once_so_resuming_far_from_the_first_waypoint_carries_on(make_survey: MakeSurvey) -> None:
    """900 m out and 1.8 km back: accepted at the start (both within 1 km); from the turn the second is 1.8 km away."""
    out, back = at(START, 0.0, 900.0), at(START, 180.0, 900.0)
    survey = make_survey(sub_mission({**out, "name": "out", "depth_m": 2.0}, {**back, "name": "back", "depth_m": 2.0}, leg_timeout_s=3600.0))
    survey.sub.step_m = 100.0
    survey.run_to_leg(1)
    survey.state.pause("operator: pause")
    survey.run(5)
    survey.state.resume()
    statuses = survey.run(100)
    assert statuses[-1] == Status.SUCCESS
    assert survey.state.legs.leg_index == 2


# -- guards: hold in POSHOLD and wait; the same leg afterwards ------------------------------------


def _depth(survey: Survey, metres: float) -> None:
    survey.sub.depth = metres


def _seabed_rises(survey: Survey, altitude_m: float) -> None:
    survey.sub.seabed_m = survey.sub.depth + altitude_m


GUARD_CASES = [
    # (leg, what goes wrong, put it right, the mode the executive holds the vehicle in, if it does)
    pytest.param(0, lambda s: _depth(s, 101.0), lambda s: _depth(s, 5.0), "POSHOLD", id="deeper-than-100-m"),
    pytest.param(0, lambda s: setattr(s.sub, "speed_over_m_s", 1.5), lambda s: setattr(s.sub, "speed_over_m_s", 0.0), "POSHOLD", id="too-fast"),
    pytest.param(1, lambda s: _seabed_rises(s, 1.0), lambda s: _seabed_rises(s, 20.0), "POSHOLD", id="altitude-leg-1-m-above-the-seabed"),
    pytest.param(1, lambda s: setattr(s.sub, "sonar", False), lambda s: setattr(s.sub, "sonar", True), "POSHOLD", id="altitude-leg-no-sonar"),
    pytest.param(0, lambda s: _seabed_rises(s, 1.0), lambda s: _seabed_rises(s, 25.0), None, id="depth-leg-1-m-above-the-seabed-not-judged"),
    pytest.param(0, lambda s: s.vehicle.set(vehicle__ekf=EKF_LOST), lambda s: s.vehicle.set(vehicle__ekf=EKF_READY), "ALT_HOLD", id="ekf-lost"),
    # ^ ArduSub refuses POSHOLD without a position (ArduSub/mode.cpp Sub::set_mode): ALT_HOLD at once, as its own terrain failsafe does
    pytest.param(0, lambda s: s.vehicle.set(link__up=False), lambda s: s.vehicle.set(link__up=True), "POSHOLD", id="link-lost"),
]  # fmt: skip


@pytest.mark.parametrize(("leg", "break_it", "mend_it", "held_in"), GUARD_CASES)
def test_a_failed_guard_holds_the_sub_until_it_recovers_then_the_same_leg_goes_on(
    make_survey: MakeSurvey, leg: int, break_it: Callable[[Survey], None], mend_it: Callable[[Survey], None], held_in: str | None
) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    wp = SURVEY[leg]
    survey.run_to_leg(leg)
    survey.under_way("depth", wp["depth_m"] if "depth_m" in wp else SEABED_M - wp["altitude_m"], wp["name"])  # an altitude leg: as a depth
    before = len(survey.sub.commands)
    # stuck (a current, a thruster): what goes wrong lasts past the guard's hold time, and the leg does not end meanwhile
    step, dz = survey.sub.step_m, survey.sub.dz_m
    holds = held_in is not None
    if holds:
        survey.sub.step_m = survey.sub.dz_m = 0.0
    break_it(survey)
    survey.sub.publish()
    if holds:
        assert survey.run(30) == [Status.RUNNING] * 30  # (a guard may wait up to 2 s of a bad reading before it holds)
        held = survey.sub.commands.index(("mode", held_in), before)
        assert [c for c in survey.sub.commands[before:] if c[0] == "mode"] == [("mode", held_in)]
        assert survey.sub.commands[held + 1 :] == []  # asked once, then waited
        assert survey.state.legs.leg_index == leg
    else:  # not judged on this leg: the leg goes on to its end
        assert survey.run(30, until=lambda: survey.state.legs.leg_index > leg)[-1] == Status.RUNNING
        assert ("mode", "POSHOLD") not in survey.sub.commands[before:]
        assert survey.state.legs.leg_index == leg + 1
    mend_it(survey)
    survey.sub.step_m, survey.sub.dz_m = step, dz
    survey.sub.publish()
    if holds:
        survey.run(31, until=lambda: len(survey.sub.commands) > held + 1)  # the guard's resume time: up to 3 s of good readings
        assert survey.sub.commands[held + 1] == ("mode", "GUIDED")
        assert survey.state.legs.leg_index == leg
    assert survey.run(400)[-1] == Status.SUCCESS


def test_a_take_over_sends_nothing_while_the_pilot_has_the_sub(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.under_way("depth", 5.0, "north")
    before = len(survey.sub.commands)
    survey.vehicle.set(rc__channels=(1500,) * 5 + (1900,))  # the pilot flips the take-over switch and drives
    survey.sub.mode = "MANUAL"
    assert survey.run(30) == [Status.RUNNING] * 30
    assert survey.sub.commands[before:] == []  # no POSHOLD, no GUIDED while the pilot has it
    assert survey.state.legs.leg_index == 0
    survey.vehicle.set(rc__channels=(1500,) * 8)
    survey.run(20, until=lambda: len(survey.sub.commands) == before + 4)  # the switch back for 1 s first
    assert survey.sub.commands[before:] == [("mode", "GUIDED"), ("speed", 0.5), ("depth", 5.0, "in place"), ("depth", 5.0, "north")]
    assert survey.state.legs.leg_index == 0
    assert survey.run(400)[-1] == Status.SUCCESS


def test_a_guard_that_never_recovers_fails_the_mission_with_its_reason(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.under_way("depth", 5.0, "north")
    survey.sub.depth, survey.sub.dz_m, survey.sub.step_m = 101.0, 0.0, 0.0  # stuck down there
    survey.sub.publish()
    statuses = survey.run(400)
    assert statuses[-1] == Status.FAILURE and len(statuses) == 312  # DepthWithin's 1 s hold time, then recovery_timeout_s = 30 s
    assert explain_failure(survey.root) == "Wait for guards: not recovered after 30 s: Depth within [0, 100] m? depth 101.0 m outside [0, 100] m"


# -- what ends a survey early --------------------------------------------------------------------


def _refuse(what: str) -> Callable[[ScriptedSub], None]:
    return lambda sub: sub.refuse.add(what)


FAILURES = [
    # (what goes wrong, the runtime's reason, when (s after the start))
    pytest.param(_refuse("speed"), "For each leg: leg 1/3 failed: Change speed: refused: DENIED", 0.4, id="speed-refused"),
    pytest.param(lambda sub: setattr(sub, "dz_m", 0.0), "For each leg: leg 1/3 failed: Change depth: depth 0.0 m, target 5 m, not reached after 60 s",
                 60.5, id="depth-never-reached"),
    pytest.param(lambda sub: setattr(sub, "step_m", 0.01),
                 "For each leg: leg 1/3 failed: Go to waypoint: leg 1/3: timed out after 60 s, 24.0 m short", 61.0, id="waypoint-never-reached"),
    pytest.param(_refuse("SURFACE"), "Surface: refused: DENIED", None, id="surface-refused"),
]  # fmt: skip


@pytest.mark.parametrize(("break_it", "reason", "after_s"), FAILURES)
def test_a_refusal_or_a_timeout_ends_the_survey_with_its_reason(
    make_survey: MakeSurvey, break_it: Callable[[ScriptedSub], None], reason: str, after_s: float | None
) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    break_it(survey.sub)
    statuses = survey.run(2000)
    assert statuses[-1] == Status.FAILURE and set(statuses[:-1]) <= {Status.RUNNING}
    assert explain_failure(survey.root) == reason
    if after_s is not None:
        assert survey.clock.now() - 100.0 == pytest.approx(after_s, abs=0.05)


def test_a_sub_that_does_not_come_up_fails_after_the_climb_time_and_a_margin(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.run_to_leg(2)
    assert survey.run(400, until=lambda: survey.sub.commands[-1] == ("mode", "SURFACE"))[-1] == Status.RUNNING
    started = survey.clock.now()
    survey.sub.dz_m = 0.0  # stuck 2 m down (it came up 1 m on the first tick)
    statuses = survey.run(1000)
    assert statuses[-1] == Status.FAILURE
    assert survey.clock.now() - started == pytest.approx(30.0 + 3.0 / 0.5, abs=0.15)
    assert explain_failure(survey.root) == "Surface: not confirmed after 36 s: depth 2.0 m in SURFACE"


# -- the seabed floor: never closer to the seabed than limits.altitude_m.min, as the sonar reads it (issue 44) ----------


def test_a_depth_leg_deeper_than_the_water_is_held_at_the_seabed_floor_and_judged_there(
    make_survey: MakeSurvey, caplog: pytest.LogCaptureFixture
) -> None:
    survey = make_survey(sub_mission({**NORTH, "name": "deep", "control_mode": "depth", "depth_m": 80.0}, SURVEY[2]))
    statuses = survey.run(400)
    assert statuses[-1] == Status.SUCCESS
    sent = [c[1] for c in survey.sub.commands if c[0] == "depth"]
    assert max(sent) == SEABED_M - 2.0  # 80 m never sent: 2 m (limits.altitude_m.min) above the 30 m seabed
    assert survey.depths_at_leg_end[0] == (SEABED_M - 2.0, 2.0)  # the leg judged where it could be flown
    warnings = [r.getMessage() for r in caplog.records if r.name == "executive.behaviours.seabed"]
    assert warnings[0] == (
        "Change depth: depth 80 m deeper than the water holds: seabed at 30.0 m by the sonar (30.0 m below), 2 m above it is 28.0 m: "
        "held there (limits.altitude_m.min)"
    )
    assert warnings[1].startswith("Change depth: leg judged at the seabed floor: depth 28.0 m (target 28 m)")


def test_a_mission_whose_policy_is_fail_fails_the_too_deep_leg_once_the_sonar_shows_the_seabed(make_survey: MakeSurvey) -> None:
    mission = sub_mission({**NORTH, "name": "deep", "control_mode": "depth", "depth_m": 80.0})
    survey = make_survey(mission.model_copy(update={"limits": mission.limits.model_copy(update={"seabed_floor": "fail"})}))
    statuses = survey.run(100)
    assert statuses[-1] == Status.FAILURE
    assert explain_failure(survey.root) == (
        "For each leg: leg 1/1 failed: Change depth: depth 80 m deeper than the water holds: seabed at 30.0 m by the sonar "
        "(30.0 m below), 2 m above it is 28.0 m (limits.seabed_floor: fail)"
    )
    assert [c for c in survey.sub.commands if c[0] == "depth"] == []  # nothing sent toward the seabed


def test_losing_the_sonar_on_the_way_down_stops_the_descent_until_it_is_back(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission({**NORTH, "name": "down", "control_mode": "depth", "depth_m": 25.0}))
    survey.sub.dz_m = 0.5  # 5 m/s
    survey.run(200, until=lambda: survey.sub.depth >= 5.0)
    survey.sub.sonar_silent = True  # the last reading (25 m above the seabed) stays and ages
    survey.run(40)
    stopped = survey.sub.depth
    assert 15.0 <= stopped <= 16.0  # 2 s of silence (SONAR_STALE_S) at 5 m/s, then no deeper than where it was
    assert survey.run(100) == [Status.RUNNING] * 100 and survey.sub.depth == stopped
    assert survey.state.legs.leg_index == 0
    survey.sub.sonar_silent = False
    assert survey.run(200)[-1] == Status.SUCCESS
    assert survey.depths_at_leg_end == [(25.0, SEABED_M - 25.0)]


def test_losing_the_sonar_on_an_altitude_leg_holds_the_depth_the_sub_is_at(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission({**NORTH, "name": "over", "control_mode": "altitude", "altitude_m": 10.0}))
    survey.sub.dz_m = 0.5
    survey.run(200, until=lambda: survey.sub.depth >= 5.0)
    survey.sub.sonar_silent = True
    survey.run(40)
    stopped = survey.sub.depth
    assert 15.0 <= stopped <= 18.0 and ("depth", stopped, "in place") in survey.sub.commands  # not on to 20 m
    assert survey.run(50) == [Status.RUNNING] * 50 and survey.sub.depth == stopped


def test_a_seabed_rising_under_a_depth_leg_lifts_the_sub_to_the_floor(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.under_way("depth", 5.0, "north")
    survey.sub.step_m = 1.0
    survey.sub.seabed_m = 6.0  # a rock 1 m under the sub
    survey.run(15)  # the next setpoint (one a second)
    assert ("depth", 4.0, "north") in survey.sub.commands and survey.sub.depth == 4.0  # 2 m above it
    survey.sub.seabed_m = SEABED_M
    survey.sub.step_m = 8.0
    assert survey.run(400)[-1] == Status.SUCCESS


# -- the lifecycle: pause holds, resume carries on with the same leg at the same depth -----------


def test_pausing_mid_leg_holds_and_resuming_continues_the_same_leg_at_the_same_depth(make_survey: MakeSurvey) -> None:
    survey = make_survey(sub_mission(*SURVEY))
    survey.under_way("depth", 5.0, "north")
    before = len(survey.sub.commands)
    survey.state.pause("operator: pause")
    assert survey.run(20) == [Status.RUNNING] * 20
    assert survey.sub.commands[before:] == [("mode", "POSHOLD")]  # asked once
    held = (survey.sub.lat, survey.sub.lon, survey.sub.depth)
    survey.run(10)
    assert (survey.sub.lat, survey.sub.lon, survey.sub.depth) == held == (*held[:2], 5.0)
    assert (survey.state.status, survey.state.legs.leg_index) == (MissionStatus.PAUSED, 0)
    survey.state.resume()
    survey.run(100, until=lambda: survey.state.legs.leg_index == 1)
    assert survey.sub.commands[before + 1 :][:4] == [("mode", "GUIDED"), ("speed", 0.5), ("depth", 5.0, "in place"), ("depth", 5.0, "north")]
    assert survey.depths_at_leg_end == [(5.0, SEABED_M - 5.0)]
    assert survey.run(400)[-1] == Status.SUCCESS


# -- the simulator: ArduSub over a modelled seabed, in the lock-step simulation ----------------------


@AUV_SURVEY_RUN
def test_the_example_survey_on_the_simulated_ardusub_reaches_each_waypoint_at_its_depth_or_altitude(auv_survey_run: SubRun) -> None:
    mission = load_mission(ROOT / "missions" / "auv_survey.yaml")
    outcome, legs, end = auv_survey_run.outcome, auv_survey_run.legs, auv_survey_run.end
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert len(legs) == len(mission.waypoints) == 4
    for wp, leg in zip(mission.waypoints, legs, strict=True):
        assert leg["off_m"] <= mission.limits.acceptance_radius_m
        if wp.control_mode == "altitude":
            assert leg["altitude"] == pytest.approx(wp.altitude_m, abs=0.5), wp.name
        else:
            assert leg["depth"] == pytest.approx(wp.depth_m, abs=0.5), wp.name
    # 24 m above a seabed ~50 m deep (ArduSub's SITL), out of the sonar's 30 m from 5 m deep: dived to blind, then followed
    assert legs[2]["depth"] > 25.0
    assert (end["mode"], end["armed"]) == ("POSHOLD", True) and end["depth"] < 0.2  # surfaced, holding for the pick-up
    assert end["vehicle_s"] < 300.0


def test_on_the_simulator_a_sub_1_km_off_refuses_the_survey_without_arming_or_moving() -> None:
    mission = load_mission(ROOT / "missions" / "auv_survey.yaml")
    assert mission.home is not None
    home = (*destination(mission.home.lat, mission.home.lon, 270.0, 1200.0), 0.0)
    run = sub_run(mission, home)
    outcome, legs, end = run.outcome, run.legs, run.end
    assert str(outcome.status) == "ABORTED"
    # the runtime's distance rule, before the tree's own (the same rule, repeated at its start) ever ticks
    assert outcome.reason.startswith("refused before anything was commanded: Within reach: waypoints[0] (start): 1200 m from the vehicle")
    assert (legs, end["armed"]) == ([], False) and end["moved_m"] < 0.01


def test_on_the_simulated_ardusub_a_leg_deeper_than_the_water_is_held_2_m_above_the_seabed_and_the_survey_completes() -> None:
    """Issue 44's repro: the example's last leg at 80 m over the simulator's 50 m seabed drove onto the bottom (50.2 m deep)."""
    example = load_mission(ROOT / "missions" / "auv_survey.yaml")
    assert example.home is not None
    last = example.waypoints[-1].model_copy(update={"depth_m": 80.0})
    limits = example.limits.model_copy(update={"leg_timeout_s": 240.0, "water_depth_m": None})  # validate would refuse it
    mission = example.model_copy(update={"waypoints": [*example.waypoints[:-1], last], "limits": limits})
    run = sub_run(mission, (example.home.lat, example.home.lon, example.home.heading_deg))
    outcome, legs, end = run.outcome, run.legs, run.end
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert legs[3]["altitude"] == pytest.approx(2.0, abs=0.5) and legs[3]["depth"] < 48.6  # the floor, not the 80 m (nor the bottom)
    assert re.search(r"  depth 4[78]\.\d m, seabed [12]\.\d m below  GUIDED armed", str(legs[3]["status"])), legs[3]["status"]
    assert re.search(r"  depth 2\d\.\d m, seabed 2[345]\.\d m below  ", str(legs[2]["status"])), legs[2]["status"]  # 24 m above it
    assert (end["mode"], end["armed"]) == ("POSHOLD", True) and end["depth"] < 0.2
