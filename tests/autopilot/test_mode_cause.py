"""Whose mode change is it (issue 23): the autopilot's own transitions by cause, per firmware; a person's never taken for them.

The rules first (each with a person's change in the same state beside it), then each transition of
README's table on the simulated firmware, with the runtime in lock-step: the change the firmware
makes is ``/vehicle/mode_set_by`` ``autopilot`` and pauses nothing; a ground station's is ``others``
and pauses the mission.
"""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import py_trees
import pytest

from executive.autopilot.mode_cause import ModeChange, autopilot_cause, facts_may_lag
from executive.behaviours import SetMode, TakeOff
from executive.mission.model import Mission
from executive.sim.faults import Fault, FaultInjector, LinkLoss
from executive.sim.firmware import FirmwareSim
from executive.testing import Lockstep
from executive.trees.parts import failsafe_guarded, mission_root, preflight, standard_guards
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink

PERSON = None  # autopilot_cause's answer for a person's change


def change(previous: str, mode: str, **facts: Any) -> ModeChange:
    """A change while armed in the air, ACTIVE, nothing else going on; ``facts`` override."""
    base = ModeChange(
        previous, mode, True, False, "IN_AIR", False, mavlink.MAV_STATE_ACTIVE, None, 20.0, takeoff_alt_msl_m=604.0, alt_msl_m=604.0
    )  # home 584 m above sea level, our take-off to 20 m above it
    return dataclasses.replace(base, **facts)


def why(firmware: str, vehicle: str, c: ModeChange) -> str | None:
    cause = autopilot_cause(firmware, vehicle, c)  # type: ignore[arg-type]
    return None if cause is None else cause.why


# -- the rules -------------------------------------------------------------------------------------


def test_px4_loiters_once_the_take_off_is_done_at_its_height_but_a_loiter_during_the_climb_is_a_persons() -> None:
    assert "take-off is done" in why("px4", "vtol", change("AUTO.TAKEOFF", "AUTO.LOITER", alt_msl_m=603.25))  # NAV_MC_ALT_RAD 0.8
    assert "take-off is done" in why("px4", "vtol", change("AUTO.TAKEOFF", "AUTO.MISSION"))  # COM_TAKEOFF_ACT 1
    assert why("px4", "vtol", change("AUTO.TAKEOFF", "AUTO.LOITER", alt_msl_m=592.0, alt_rel_m=8.0)) is PERSON  # IN_AIR all the same
    assert why("px4", "vtol", change("AUTO.TAKEOFF", "AUTO.LOITER", takeoff_alt_msl_m=None)) is PERSON  # not our take-off
    assert why("px4", "vtol", change("AUTO.TAKEOFF", "AUTO.RTL")) is PERSON


def test_px4s_take_off_end_is_judged_on_its_altitude_above_sea_level_not_on_the_height_above_its_moving_home() -> None:
    """The real SIH (tests/data/px4/vtol_takeoff_end_home_moved.tlog): NAV_TAKEOFF to 613.686 m (home 583.686 + 30), PX4
    loitered with GLOBAL_POSITION_INT at 612.984 m but 28.22 m above home: PX4 had moved its home up by 1.07 m in the air."""
    real = change("AUTO.TAKEOFF", "AUTO.LOITER", takeoff_alt_msl_m=613.686, alt_msl_m=612.984, alt_rel_m=28.22, climb_m_s=0.49, position_age_s=0.1)
    assert "take-off is done" in why("px4", "vtol", real)
    assert why("px4", "vtol", dataclasses.replace(real, alt_msl_m=609.0, alt_rel_m=29.9)) is PERSON  # 4.7 m under: a person's Hold


def test_px4s_take_off_end_is_judged_by_the_vehicles_own_altitude_acceptance() -> None:
    """NAV_MC_ALT_RAD as the vehicle answered it (None: not yet, its default 0.8 m, navigator/navigator_params.c)."""
    under = change("AUTO.TAKEOFF", "AUTO.LOITER", alt_msl_m=602.5)  # 1.5 m under the 604 m asked
    assert "take-off is done" in why("px4", "vtol", dataclasses.replace(under, takeoff_alt_rad_m=2.0))
    assert why("px4", "vtol", dataclasses.replace(under, takeoff_alt_rad_m=0.8)) is PERSON
    assert why("px4", "vtol", under) is PERSON  # not answered: its default


def test_px4s_take_off_end_counts_the_climb_since_the_last_position_report_but_no_more() -> None:
    """PX4 tests its estimate of the moment; the report is up to 200 ms older: it may have climbed on that long, no more."""
    under = change("AUTO.TAKEOFF", "AUTO.LOITER", takeoff_alt_msl_m=613.686, alt_msl_m=612.80, climb_m_s=0.5)
    assert why("px4", "vtol", dataclasses.replace(under, position_age_s=0.0)) is PERSON  # 0.086 m short of 612.886 at the switch
    assert "take-off is done" in why("px4", "vtol", dataclasses.replace(under, position_age_s=0.2))  # 0.1 m climbed since
    assert why("px4", "vtol", dataclasses.replace(under, position_age_s=0.2, climb_m_s=-0.5)) is PERSON  # sinking: not since
    assert why("px4", "vtol", dataclasses.replace(under, alt_msl_m=613.5, position_age_s=2.0)) is PERSON  # too old to tell
    assert why("px4", "vtol", dataclasses.replace(under, alt_msl_m=None)) is PERSON  # no altitude above sea level reported


def test_px4_loiters_once_the_mission_is_finished_but_not_while_it_runs() -> None:
    assert "mission is finished" in why("px4", "rover", change("AUTO.MISSION", "AUTO.LOITER", mission_complete=True))
    assert why("px4", "rover", change("AUTO.MISSION", "AUTO.LOITER")) is PERSON


def test_px4_goes_back_to_the_users_mode_when_disarmed_but_never_to_one_that_prevents_arming() -> None:
    disarmed = {"armed": False, "disarmed_just_now": True, "landed_state": "ON_GROUND"}
    assert "disarmed" in why("px4", "vtol", change("AUTO.RTL", "AUTO.LOITER", **disarmed))
    assert "disarmed" in why("px4", "rover", change("AUTO.LAND", "OFFBOARD", **disarmed))
    assert why("px4", "vtol", change("AUTO.LOITER", "AUTO.RTL", **disarmed)) is PERSON  # RTL prevents arming: a person's
    assert why("px4", "vtol", change("AUTO.RTL", "AUTO.LOITER", armed=False, landed_state="ON_GROUND")) is PERSON  # long disarmed


def test_px4_failsafe_shows_critical_in_the_heartbeat_a_persons_change_does_not() -> None:
    cause = autopilot_cause("px4", "vtol", change("OFFBOARD", "POSCTL", system_status=mavlink.MAV_STATE_CRITICAL))
    assert cause is not None and cause.failsafe
    assert why("px4", "vtol", change("OFFBOARD", "AUTO.LOITER")) is PERSON
    assert why("px4", "vtol", change("OFFBOARD", "AUTO.RTL")) is PERSON


def test_an_announced_failsafe_is_the_autopilots_on_both_firmwares() -> None:
    for firmware in ("ardupilot", "px4"):
        cause = autopilot_cause(firmware, "rover", change("GUIDED", "HOLD", failsafe_text="EKF failsafe"))  # type: ignore[arg-type]
        assert cause is not None and cause.failsafe and cause.why == "EKF failsafe"
    assert why("ardupilot", "rover", change("GUIDED", "HOLD")) is PERSON


def test_ardusub_holds_its_depth_once_surface_reaches_the_surface_but_not_below_it() -> None:
    assert "surface" in why("ardupilot", "sub", change("SURFACE", "ALT_HOLD", alt_rel_m=-0.1, landed_state=None))
    assert why("ardupilot", "sub", change("SURFACE", "ALT_HOLD", alt_rel_m=-8.0, landed_state=None)) is PERSON
    assert why("ardupilot", "rover", change("SURFACE", "ALT_HOLD", alt_rel_m=0.0)) is PERSON


def test_ardusub_ends_its_mission_in_alt_hold_only_without_a_position() -> None:
    """Sub::exit_mission: AUTO loiters at the end unless auto_loiter_start fails (no position): then ALT_HOLD, said by nothing."""
    end = {"armed": True, "landed_state": None, "position_ok": False}
    assert "mission ended without a position" in why("ardupilot", "sub", change("AUTO", "ALT_HOLD", mission_end_reached=True, **end))
    assert "mission ended without a position" in why("ardupilot", "sub", change("AUTO", "ALT_HOLD", mission_complete=True, **end))
    assert why("ardupilot", "sub", change("AUTO", "ALT_HOLD", **end)) is PERSON  # mid-mission
    assert why("ardupilot", "sub", change("AUTO", "ALT_HOLD", mission_end_reached=True, **(end | {"position_ok": True}))) is PERSON
    assert why("ardupilot", "sub", change("AUTO", "ALT_HOLD", mission_end_reached=True, **(end | {"position_ok": None}))) is PERSON
    assert why("ardupilot", "rover", change("AUTO", "ALT_HOLD", mission_end_reached=True, **end)) is PERSON
    assert why("ardupilot", "sub", change("AUTO", "MANUAL", mission_end_reached=True, **end)) is PERSON


def test_only_arduSubs_auto_to_alt_hold_waits_for_the_facts_streamed_after_the_heartbeat() -> None:
    assert facts_may_lag("ardupilot", "sub", change("AUTO", "ALT_HOLD"))
    assert not facts_may_lag("ardupilot", "sub", change("AUTO", "POSHOLD"))
    assert not facts_may_lag("ardupilot", "rover", change("AUTO", "ALT_HOLD"))
    assert not facts_may_lag("px4", "sub", change("AUTO", "ALT_HOLD"))


def test_ardupilot_has_no_disarm_or_take_off_rule() -> None:
    disarmed = {"armed": False, "disarmed_just_now": True, "landed_state": "ON_GROUND"}
    assert why("ardupilot", "vtol", change("QRTL", "QLOITER", **disarmed)) is PERSON
    assert why("ardupilot", "vtol", change("GUIDED", "QLOITER", system_status=mavlink.MAV_STATE_CRITICAL)) is PERSON


def test_ardupilots_fence_action_is_the_autopilots_and_pauses_the_mission_but_a_hold_without_a_breach_is_a_persons() -> None:
    rover = change("GUIDED", "HOLD", landed_state=None, alt_rel_m=0.0)
    cause = autopilot_cause("ardupilot", "rover", dataclasses.replace(rover, fence_breached=True))
    assert cause is not None and cause.pauses and not cause.failsafe and "its own fence breached (FENCE_STATUS)" in cause.why
    assert autopilot_cause("ardupilot", "rover", rover) is PERSON
    assert autopilot_cause("ardupilot", "rover", dataclasses.replace(rover, fence_breached=True, armed=False)) is PERSON


# -- on the simulated firmware ---------------------------------------------------------------------


class GroundStation(FaultInjector):
    """Faults, and at ``actions`` times (vehicle seconds after boot, or when ``when(autopilot)`` first holds) a ground station's mode."""

    def __init__(self, clock: Clock, faults: list[Fault], action: tuple[Callable[[FirmwareSim], bool], str] | None = None) -> None:
        super().__init__(faults, clock)
        self.action = action

    def update(self, autopilot: FirmwareSim) -> None:
        super().update(autopilot)
        if self.action is not None and self.action[0](autopilot):
            mode, self.action = self.action[1], None
            assert autopilot.set_mode(autopilot.profile.modes[mode])


class MovingHome(GroundStation):
    """PX4's home altitude corrected in the air (commander/HomePosition.cpp), as on the real SIH during the take-off
    (tests/data/px4/vtol_takeoff_end_home_moved.tlog): GLOBAL_POSITION_INT's relative altitude moves by ``STEPS`` (home's
    rise over the one known before arming, from the height climbed), its altitude above sea level not. The take-off is asked
    from the home known before arming, as on the SIH (its next HOME_POSITION came 3 s after NAV_TAKEOFF)."""

    #: (climbed m, home's rise m): the real SIH's HOME_POSITION altitudes during its climb (583.686 before arming, then
    #: 584.002, 584.097, 584.069, 584.760, 585.110), its relative altitude jumping by up to 1 m each time.
    STEPS = ((0.0, 0.316), (4.0, 0.411), (8.0, 0.383), (12.0, 1.074), (16.0, 1.424))
    rise = 0.0

    def update(self, autopilot: FirmwareSim) -> None:
        super().update(autopilot)
        self.rise = 0.0
        if autopilot.armed:
            self.rise = next(rise for climbed, rise in reversed(self.STEPS) if autopilot.vehicle.alt_m >= climbed)

    def transform(self, messages: Sequence[MAVLinkMessage]) -> list[MAVLinkMessage]:
        for msg in messages:
            if msg.get_type() == "GLOBAL_POSITION_INT":
                msg.relative_alt -= round(self.rise * 1000)
        return super().transform(messages)


class Changes:
    """Each change of the heartbeat's mode the runtime saw: (mode, whose, the mission's state at that tick)."""

    def __init__(self) -> None:
        self.bb = blackboard.reader("mode cause test", ["/vehicle/mode", "/vehicle/mode_set_by", "/mission/state", "/mission/reason"])
        self.seen: list[tuple[str, str | None, str]] = []

    def __call__(self, sim: Lockstep) -> None:
        mode = self.bb.get("/vehicle/mode")
        if mode is not None and (not self.seen or self.seen[-1][0] != mode):
            self.seen.append((mode, self.bb.get("/vehicle/mode_set_by"), self.bb.get("/mission/state")))

    def of(self, mode: str) -> tuple[str, str | None, str]:
        return next(seen for seen in self.seen if seen[0] == mode)


def simulate(
    mission: Mission,
    work: py_trees.behaviour.Behaviour,
    *,
    autopilot: str,
    faults: list[Fault] | None = None,
    action: tuple[Callable[[FirmwareSim], bool], str] | None = None,
    until: Callable[[Lockstep], bool],
    limit_s: float = 120.0,
    station: type[GroundStation] = GroundStation,
) -> tuple[Lockstep, Changes]:
    """``work`` guarded after the pre-flight, on the simulated ``autopilot``, until ``until(sim)``."""
    root = mission_root(mission, preflight(mission), failsafe_guarded(work, standard_guards(mission), mission, name="Work"))
    sim = Lockstep(mission, root=root, autopilot=autopilot, injector=lambda _, clock: station(clock, faults or [], action))
    _OPEN.append(sim)
    changes = Changes()
    sim.observers.append(changes)
    sim.run(limit_s, until=lambda: until(sim))
    return sim, changes


def vtol(**changes: Any) -> Mission:
    fields: dict[str, Any] = {
        "version": 1,
        "name": "mode cause",
        "vehicle": "vtol",
        "auto_arm": True,
        "home": {"lat": -35.363261, "lon": 149.165230},
        "limits": {"acceptance_radius_m": 100, "leg_timeout_s": 120, "recovery_timeout_s": 60},
        "simulator": {"ekf_ready_after_s": 5},
        "waypoints": [{"lat": -35.3625, "lon": 149.165230, "alt_m": 20}],
    }
    return Mission.model_validate(fields | changes)


def take_off_and_stay() -> py_trees.behaviour.Behaviour:
    return py_trees.composites.Sequence("Up", memory=True, children=[SetMode("GUIDED"), TakeOff(20.0), py_trees.behaviours.Running("Stay")])


_OPEN: list[Lockstep] = []


@pytest.fixture
def clean() -> Iterator[None]:
    """A fresh blackboard; the simulations made, closed after the test."""
    blackboard.reset()
    yield
    while _OPEN:
        _OPEN.pop().close()


def test_px4_vtol_take_off_done_then_auto_loiter_is_the_autopilots_and_pauses_nothing(clean: None) -> None:
    sim, changes = simulate(vtol(), take_off_and_stay(), autopilot="px4", until=lambda s: s.clock.now() > 40.0)
    assert changes.of("AUTO.TAKEOFF")[1] == "us"
    assert changes.seen[-1] == ("AUTO.LOITER", "autopilot", "RUNNING")
    assert sim.autopilot.vehicle.alt_m == pytest.approx(20.0, abs=1.0)


def test_px4_vtol_a_ground_stations_loiter_during_the_climb_is_a_persons(clean: None) -> None:
    climbing = (lambda ap: ap.mode == "AUTO.TAKEOFF" and 5.0 < ap.vehicle.alt_m < 10.0, "AUTO.LOITER")
    sim, changes = simulate(vtol(), take_off_and_stay(), autopilot="px4", action=climbing, until=lambda s: s.clock.now() > 40.0)
    assert changes.seen[-1] == ("AUTO.LOITER", "others", "PAUSED")
    assert sim.runtime.mission_state.reason == "AUTO.LOITER set by the ground station"
    assert sim.autopilot.vehicle.alt_m < 11.0  # it held where the person stopped it


def test_px4_vtol_take_off_done_while_home_moves_up_is_still_the_autopilots(clean: None) -> None:
    """The real SIH's case: its take-off ended under 20 m, reported 1.4 m lower still (home moved up): not a person's."""
    sim, changes = simulate(vtol(), take_off_and_stay(), autopilot="px4", station=MovingHome, until=lambda s: s.clock.now() > 40.0)
    assert changes.seen[-1] == ("AUTO.LOITER", "autopilot", "RUNNING")
    assert sim.autopilot.vehicle.alt_m == pytest.approx(20.0, abs=1.0)


def test_px4_vtol_a_ground_stations_loiter_during_the_climb_is_a_persons_while_home_moves_too(clean: None) -> None:
    climbing = (lambda ap: ap.mode == "AUTO.TAKEOFF" and 13.0 < ap.vehicle.alt_m < 15.0, "AUTO.LOITER")
    sim, changes = simulate(vtol(), take_off_and_stay(), autopilot="px4", station=MovingHome, action=climbing, until=lambda s: s.clock.now() > 40.0)
    assert changes.seen[-1] == ("AUTO.LOITER", "others", "PAUSED")
    assert sim.autopilot.vehicle.alt_m < 16.0  # it held where the person stopped it


def test_px4_vtol_offboard_failsafe_is_the_autopilots_and_pauses_nothing(clean: None) -> None:
    """Setpoints lost on the way up (uplink only: the heartbeats still come): PX4's offboard failsafe, POSCTL, CRITICAL."""
    work = py_trees.composites.Sequence(
        "Hold", memory=True, children=[SetMode("GUIDED"), TakeOff(20.0), SetMode("GUIDED", name="OFFBOARD again"), py_trees.behaviours.Running()]
    )  # OFFBOARD holding where it is: the port streams that point
    loss = LinkLoss(kind="link_loss", at_s=25.0, for_s=60.0, direction="uplink")
    _sim, changes = simulate(vtol(), work, autopilot="px4", faults=[loss], until=lambda s: s.clock.now() > 30.0)
    assert [seen[:2] for seen in changes.seen[-3:]] == [("AUTO.LOITER", "autopilot"), ("OFFBOARD", "us"), ("POSCTL", "autopilot")]
    assert changes.seen[-1][2] == "RUNNING"


def test_px4_rover_offboard_failsafe_then_landing_then_disarm_are_all_the_autopilots(clean: None) -> None:
    """PX4 rover: setpoints lost -> POSCTL, then AUTO.LAND (CRITICAL: failsafe.cpp), "Disarmed by landing" (RoverLandDetector:
    AUTO.LAND is landed), then back to the user's OFFBOARD (UserModeIntention::onDisarm). None of it pauses the mission."""
    mission = Mission.model_validate(
        {
            "version": 1, "name": "px4 rover", "vehicle": "rover", "auto_arm": True, "home": {"lat": -35.363261, "lon": 149.165230},
            "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60, "recovery_timeout_s": 60}, "simulator": {"ekf_ready_after_s": 5},
            "waypoints": [{"lat": -35.3630, "lon": 149.165230}],
        }
    )  # fmt: skip
    work = py_trees.composites.Sequence("Hold", memory=True, children=[SetMode("GUIDED"), py_trees.behaviours.Running()])
    loss = LinkLoss(kind="link_loss", at_s=15.0, for_s=60.0, direction="uplink")
    sim, changes = simulate(mission, work, autopilot="px4", faults=[loss], until=lambda s: s.clock.now() > 30.0)
    assert [seen[:2] for seen in changes.seen[1:]] == [
        ("OFFBOARD", "us"),
        ("POSCTL", "autopilot"),
        ("AUTO.LAND", "autopilot"),
        ("OFFBOARD", "autopilot"),
    ]
    assert {seen[2] for seen in changes.seen[1:]} == {"RUNNING"} and not sim.autopilot.armed


def test_px4_rover_finished_mission_loiters_by_itself(clean: None) -> None:
    """Commander::checkForMissionUpdate: a finished mission (MISSION_CURRENT mission_state 5), still armed, goes to AUTO.LOITER."""
    from executive.behaviours import DriveRouteInAuto, KeepRouteOnAutopilot

    mission = Mission.model_validate(
        {
            "version": 1, "name": "px4 route", "vehicle": "rover", "auto_arm": True, "home": {"lat": -35.363261, "lon": 149.165230},
            "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60, "recovery_timeout_s": 60}, "simulator": {"ekf_ready_after_s": 5},
            "waypoints": [{"lat": -35.36317, "lon": 149.165230}, {"lat": -35.36317, "lon": 149.16534}],
        }
    )  # fmt: skip
    read_back = py_trees.common.ComparisonExpression("/vehicle/mission_items", None, operator.is_not)  # None until read back
    held = py_trees.behaviours.WaitForBlackboardVariableValue("Route held?", read_back)
    drive = py_trees.composites.Sequence(
        "Drive", memory=True, children=[held, SetMode("AUTO"), DriveRouteInAuto(60.0), py_trees.behaviours.Running("Stay")]
    )
    work = py_trees.composites.Parallel("Route", policy=py_trees.common.ParallelPolicy.SuccessOnOne(), children=[KeepRouteOnAutopilot(), drive])
    _sim, changes = simulate(mission, work, autopilot="px4", until=lambda s: s.clock.now() > 60.0)
    assert [seen[:2] for seen in changes.seen[1:]] == [("AUTO.MISSION", "us"), ("AUTO.LOITER", "autopilot")]
    assert changes.seen[-1][2] == "RUNNING"


def rover_line(**changes: Any) -> Mission:
    from tests_support import line_mission

    return line_mission("mode cause", **changes)


def test_ardurover_ekf_failsafe_hold_is_the_autopilots(clean: None) -> None:
    """Rover/ekf_check.cpp: "EKF failsafe", GUIDED -> HOLD. With the mission's own reaction hands off, the firmware acts first."""
    from executive.sim.faults import EkfDegradation

    mission = rover_line(failsafe={"ekf_loss": {"reaction": "wait", "recovery": "resume", "timeout_s": 60}})
    work = py_trees.composites.Sequence("Hold", memory=True, children=[SetMode("GUIDED"), py_trees.behaviours.Running()])
    fault = EkfDegradation(kind="ekf_degradation", at_s=12.0, for_s=30.0, variance=1.2, lose_position=True)
    _sim, changes = simulate(mission, work, autopilot="ardupilot", faults=[fault], until=lambda s: s.clock.now() > 16.0)
    assert [seen[:2] for seen in changes.seen[-2:]] == [("GUIDED", "us"), ("HOLD", "autopilot")]
    assert changes.seen[-1][2] == "RUNNING"


def test_ardurover_rc_failsafe_mode_is_the_autopilots_and_a_ground_stations_hold_is_a_persons(clean: None) -> None:
    """Rover/failsafe.cpp: the transmitter lost, FS_ACTION's mode (HOLD) once armed; its RC_CHANNELS read 0 from then on."""
    from executive.sim.faults import RcLoss

    mission = rover_line(failsafe={"rc_loss": {"reaction": "wait", "recovery": "resume", "timeout_s": 60}})
    work = py_trees.composites.Sequence("Hold", memory=True, children=[SetMode("GUIDED"), py_trees.behaviours.Running()])
    fault = RcLoss(kind="rc_loss", at_s=12.0, for_s=30.0, failsafe_mode="HOLD")
    _sim, changes = simulate(mission, work, autopilot="ardupilot", faults=[fault], until=lambda s: s.clock.now() > 14.0)
    assert [seen[:2] for seen in changes.seen[-2:]] == [("GUIDED", "us"), ("HOLD", "autopilot")]
    assert changes.seen[-1][2] == "RUNNING"
    blackboard.reset()
    work = py_trees.composites.Sequence("Hold", memory=True, children=[SetMode("GUIDED"), py_trees.behaviours.Running()])
    person = (lambda ap: ap.elapsed_s >= 12.0, "HOLD")
    _sim, changes = simulate(mission, work, autopilot="ardupilot", action=person, until=lambda s: s.clock.now() > 14.0)
    assert changes.seen[-1] == ("HOLD", "others", "PAUSED")


def test_ardusub_surface_then_alt_hold_at_the_surface_is_the_autopilots(clean: None) -> None:
    """ArduSub/mode_surface.cpp: SURFACE hands over to ALT_HOLD at the surface (SURFACE_COMPLETE); the survey's end asks SURFACE."""
    mission = Mission.model_validate(
        {
            "version": 1, "name": "dip", "vehicle": "sub", "tree": "auv_survey", "auto_arm": True, "home": {"lat": 44.095, "lon": 9.863},
            "limits": {"acceptance_radius_m": 2.0, "leg_timeout_s": 90, "recovery_timeout_s": 60, "link_timeout_s": 3},
            "simulator": {"ekf_ready_after_s": 5}, "waypoints": [{"lat": 44.09505, "lon": 9.863, "depth_m": 3.0, "speed_m_s": 0.5}],
        }
    )  # fmt: skip
    changes = Changes()
    with Lockstep(mission) as sim:
        sim.observers.append(changes)
        outcome = sim.run_to_end(limit_s=300)
    assert str(outcome.status) == "COMPLETED", outcome.reason
    modes = [seen[:2] for seen in changes.seen]
    assert modes[modes.index(("SURFACE", "us")) :][:2] == [("SURFACE", "us"), ("ALT_HOLD", "autopilot")]
    assert "PAUSED" not in {seen[2] for seen in changes.seen}
