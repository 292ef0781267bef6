"""The Failsafe behaviour tick by tick on a fake link: the reaction leaves in the tick its guard fails (its condition bad for the guard's
hold time: most hold at once), then the recovery (the condition good again for the guard's resume time)."""

from __future__ import annotations

import dataclasses
import logging
import re
from collections.abc import Callable
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours import Failsafe, SetMode
from executive.behaviours.failsafe import failsafe_mode
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.modes import PX4_MODES
from executive.mission.events import Announcement
from executive.mission.failsafes import FailsafePolicy
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission
from executive.testing import EKF_READY, FakeLink, Harness, ScriptedAutopilot, Vehicle
from executive.tree import select as mission_tree
from executive.trees.parts import failsafe_guarded, mission_root, standard_guards
from executive.world.clock import ManualClock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.geo import destination
from executive.world.state import Battery, EkfFlags, EkfStatus, GlobalPosition
from executive.world.vehicles import PROFILES

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE
HOME = (47.397742, 8.545594)
EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
EKF_GLITCH = EkfStatus(EkfFlags(831) | EkfFlags.GPS_GLITCHING, 0.1, 1.0, 0.1, 0.1, 0.0, 0.0)
RC_OK = (1500,) * 8
RC_TAKEOVER = (1500,) * 5 + (1900, 1500, 1500)


def make_mission(vehicle: str = "rover", **changes: Any) -> Mission:
    fields: dict[str, Any] = {
        "version": 1,
        "name": "failsafe",
        "vehicle": vehicle,
        "home": {"lat": HOME[0], "lon": HOME[1]},
        "limits": {"recovery_timeout_s": 30.0, **({"acceptance_radius_m": 80.0} if vehicle == "vtol" else {})},
        "waypoints": [{"lat": HOME[0] + 0.0002, "lon": HOME[1]}],
    }
    return Mission.model_validate(fields | changes)


def position(north_m: float = 0.0) -> GlobalPosition:
    lat, lon = destination(*HOME, 0.0, north_m)
    return GlobalPosition(lat, lon, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class Obeying(ScriptedAutopilot):
    """The autopilot behind the guarded tree: it acks each command at once (a mode in :attr:`refuse` FAILED; nothing with ``acks`` off).

    It publishes nothing but what it accepts: the mode it enters and its arming, as its heartbeat would (not with ``shows`` off: a
    vehicle that acks and stays as it was); the other facts are the test's to write (healthy until a test breaks them).
    """

    def __init__(self, h: Harness) -> None:
        super().__init__(h)
        self.acks = True
        self.shows = True

    def publish(self) -> None:
        """Nothing: the test writes the vehicle's facts (the heartbeat's, as accepted, in :meth:`on_command`)."""

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        result = super().on_command(msg)
        if result == mavlink.MAV_RESULT_ACCEPTED and self.acks and self.shows:
            if msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                self.h.vehicle.set(vehicle__mode=self.mode)
            elif msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
                self.h.vehicle.set(vehicle__armed=self.armed)
        return result if self.acks else None

    def tick(self, n: int = 1) -> list[Status]:
        """Up to ``n`` ticks, stopping at the first that is not RUNNING, each answered."""
        return self.run(n)

    def sent(self) -> list[tuple[str, Any]]:
        """What it was asked since the last call: ("mode", name) or ("arm", 1.0 / 0.0)."""
        return [c for c in self.take() if c[0] in ("mode", "arm")]


def failsafe(r: Obeying) -> Failsafe:
    return next(n for n in r.h.root.iterate() if isinstance(n, Failsafe))


def work(r: Obeying) -> py_trees.behaviour.Behaviour:
    """The guarded work (the guarded route's last child)."""
    return r.h.root.children[0].children[-1]


@pytest.fixture
def rig(clock: ManualClock) -> Callable[..., Obeying]:
    """``rig(kind, work, **changes)``: ``failsafe_guarded(work, standard guards, mission)`` for one vehicle kind, on a Harness, obeyed."""

    def make(vehicle_kind: str = "rover", work_: py_trees.behaviour.Behaviour | None = None, **changes: Any) -> Obeying:
        mission = make_mission(vehicle_kind, **changes)
        state = MissionState()
        state.upload(mission)
        state.start()
        root = failsafe_guarded(work_ or py_trees.behaviours.Running("Work"), standard_guards(mission), mission)
        link = FakeLink()
        r = Obeying(Harness(root, clock, link, Commander(link, clock, PROFILES[mission.vehicle]), state))
        r.h.vehicle.set(
            link__up=True, vehicle__armed=True, vehicle__mode="GUIDED", vehicle__ekf=EKF_READY, rc__channels=RC_OK, rc__connected=True,
            vehicle__battery=Battery(12.4, 2.0, 80, 0.0), vehicle__position=position(), heading__ok=True,
        )  # fmt: skip
        assert r.tick() == [R] and work(r).status == R and r.sent() == []  # healthy: the work runs, nothing is asked
        return r

    return make


FENCE = {"geofence": {"max_distance_from_home_m": 50.0}}
FW = {"vehicle__vtol_state": "FW"}
TO_FW = {"vehicle__vtol_state": "TRANSITION_TO_FW"}
WING_BORNE_STILL_SAID_MC = {"vehicle__vtol_state": "MC", "vehicle__ground_speed_m_s": 18.0}
HOVERING_ALONG = {"vehicle__vtol_state": "MC", "vehicle__ground_speed_m_s": 5.0}
LOW = {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}

# (vehicle, mission changes, facts before, what breaks, the commands of that very tick, the status of that tick)
REACTIONS = [
    pytest.param("rover", {}, {}, {"link__up": False}, [("mode", "HOLD")], R, id="rover-link_loss-hold"),
    pytest.param("boat", {}, {}, {"link__up": False}, [("mode", "LOITER")], R, id="boat-link_loss-loiter"),
    pytest.param("sub", {}, {}, {"link__up": False}, [("mode", "SURFACE")], R, id="sub-link_loss-surface"),
    pytest.param("vtol", {}, {}, {"link__up": False}, [("mode", "QLOITER")], R, id="vtol-link_loss-qloiter"),
    pytest.param("vtol", {}, FW, {"link__up": False}, [("mode", "LOITER")], R, id="vtol-as-a-plane-link_loss-loiter"),
    pytest.param("rover", {}, {}, {"rc__channels": RC_TAKEOVER}, [], R, id="rover-rc_takeover-wait"),
    pytest.param("rover", {}, {}, {"vehicle__armed": False}, [], R, id="rover-disarmed-wait"),
    pytest.param("rover", {}, {}, {"rc__connected": False}, [("mode", "HOLD")], R, id="rover-rc_loss-hold"),
    pytest.param("boat", {}, {}, {"rc__connected": False}, [("mode", "LOITER")], R, id="boat-rc_loss-loiter"),
    pytest.param("rover", {}, {}, {"vehicle__ekf": EKF_LOST}, [("mode", "HOLD")], R, id="rover-ekf_loss-hold"),
    pytest.param("boat", {}, {}, {"vehicle__ekf": EKF_LOST}, [("mode", "HOLD")], R, id="boat-ekf_loss-hold-needs-no-position"),
    pytest.param("rover", {}, {}, {"vehicle__ekf": EKF_GLITCH}, [("mode", "HOLD")], R, id="rover-gps_glitch-hold"),
    # the autopilot's own EKF failsafe (its HOLD and notice before a report shows the EKF bad): the work stops, it never asks GUIDED back
    pytest.param("rover", {}, {}, {"vehicle__ekf_failsafe": True}, [("mode", "HOLD")], R, id="rover-autopilots-ekf_failsafe-hold"),
    pytest.param("boat", {}, {}, {"heading__ok": False}, [("mode", "HOLD")], R, id="boat-heading_insane-hold"),
    pytest.param("sub", {}, {}, {"heading__ok": False}, [], S, id="sub-heading-not-judged"),  # a sub's course says nothing of its heading
    pytest.param("rover", {}, {}, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [("mode", "RTL")], F, id="rover-battery_low-rtl-abort"),
    pytest.param("boat", {}, {}, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [("mode", "RTL")], F, id="boat-battery_low-rtl-abort"),
    pytest.param("sub", {}, {}, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [("mode", "SURFACE")], F, id="sub-battery_low-surface-abort"),
    pytest.param("vtol", {}, {}, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [("mode", "QRTL")], F, id="vtol-battery_low-qrtl-abort"),
    pytest.param("vtol", {}, FW, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [("mode", "RTL")], F, id="vtol-as-a-plane-battery_low-rtl"),
    # issue 33: QRTL asked with the lift motors running hovers the whole way home (ArduPlane/mode_qrtl.cpp): a return is RTL from the
    # transition's start, and at a wing-borne speed EXTENDED_SYS_STATE has not caught up with; a hold mid-transition stays QLOITER
    pytest.param("vtol", {}, TO_FW, LOW, [("mode", "RTL")], F, id="vtol-transitioning-to-a-plane-battery_low-rtl"),
    pytest.param("vtol", {}, WING_BORNE_STILL_SAID_MC, LOW, [("mode", "RTL")], F, id="vtol-wing-borne-still-said-mc-battery_low-rtl"),
    pytest.param("vtol", {}, HOVERING_ALONG, LOW, [("mode", "QRTL")], F, id="vtol-hovering-along-qrtl"),
    pytest.param("vtol", {}, TO_FW, {"link__up": False}, [("mode", "QLOITER")], R, id="vtol-transitioning-link_loss-qloiter"),
    pytest.param("rover", FENCE, {}, {"vehicle__position": position(60.0)}, [("mode", "HOLD")], F, id="rover-geofence_breach-hold-abort"),
    pytest.param("boat", FENCE, {}, {"vehicle__position": position(60.0)}, [("mode", "RTL")], F, id="boat-geofence_breach-rtl-abort"),
    pytest.param("rover", {"failsafe": {"link_loss": {"reaction": "loiter"}}}, {}, {"link__up": False}, [("mode", "LOITER")], R, id="mission-policy"),
    pytest.param("rover", {"limits": {"battery_min_pct": None}}, {}, {"vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, [], S, id="no-battery-floor"),
]  # fmt: skip


@pytest.mark.parametrize(("kind", "changes", "before", "breaks", "commands", "status"), REACTIONS)
def test_the_reaction_leaves_in_the_tick_the_guard_fails(rig, kind, changes, before, breaks, commands, status) -> None:
    """The condition bad for its guard's hold time (0 s: the tick it becomes true); ``status`` S: no failsafe at all, the work goes on."""
    r = rig(kind, **changes)
    r.h.vehicle.set(**before)
    assert r.tick() == [R] and r.sent() == []
    r.h.vehicle.set(**breaks)
    hold_s = max((g.hold_after_s for g in failsafe(r).guards if g.check() is not None), default=0.0)
    for _ in range(round(hold_s / 0.1)):  # a shorter bad spell is noise: the work goes on, nothing is sent
        assert r.tick() == [R] and work(r).status == R and r.sent() == []
    assert r.tick() == [R if status == S else status]
    assert r.sent() == commands  # flushed at the end of that very tick: zero ticks of delay
    assert work(r).status == (R if status == S else Status.INVALID)  # the work stopped while the failsafe acts
    if status == F:
        assert failsafe_mode(r.h.root) == commands[0][1]  # where the runtime leaves the vehicle


@pytest.mark.parametrize(
    ("condition", "reaction", "breaks"),
    [("rc_takeover", "hold", {"rc__channels": RC_TAKEOVER}), ("disarmed", "rtl", {"vehicle__armed": False})],
)
def test_a_persons_act_is_not_fought_even_under_a_policy_the_loader_refuses(rig, condition, reaction, breaks, caplog) -> None:
    """A person's precedence is not a policy: the loader refuses any reaction but wait (test_failsafe_policy); a tree given one anyway
    (built in code) keeps its hands off too."""
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover", failsafe={"disarmed": {"reaction": "wait"}} if condition == "disarmed" else {})
    fs = failsafe(r)
    fs.policy[condition] = FailsafePolicy(condition, reaction, "resume", 30.0)
    r.h.vehicle.set(**breaks)
    assert r.tick(20) == [R] * 20 and r.sent() == []
    assert f"failsafe {condition}: " in caplog.text and "-> wait: hands off (" in caplog.text


def test_resume_cancels_the_reaction_and_logs_cause_and_recovery(rig, caplog) -> None:
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover")
    r.acks = False  # the autopilot does not answer: the failsafe asks the hold again every 1.5 s...
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    assert r.tick(10) == [R] * 10 and r.sent() == [("mode", "HOLD")]
    r.h.vehicle.set(vehicle__ekf=EKF_READY)
    assert r.tick(30) == [R] * 30 and work(r).status != R  # ...the guard recovers: the EKF must stay sane for 3 s
    assert set(r.sent()) == {("mode", "HOLD")}  # (meanwhile the unanswered hold is retried: still held)
    assert r.tick() == [R] and work(r).status == R  # then the work resumes, in that tick
    assert r.tick(30) == [R] * 30 and r.sent() == []  # and the hold is not retried over it
    assert r.commander.idle
    assert [rec.getMessage() for rec in caplog.records] == [
        "failsafe ekf_loss: EKF has no position estimate (flags 0x81) -> hold (HOLD), resume when it recovers (within 30 s)",
        "failsafe ekf_loss: HOLD no answer -> asked again every 1.5 s",
        "failsafe ekf_loss: recovered after 4.0 s -> resume leg 1/1",
    ]
    assert {rec.name for rec in caplog.records} == {"executive.behaviours.failsafe"}  # the journal's event kind: "failsafe"


def test_a_condition_that_lasts_past_its_own_time_limit_aborts(rig, caplog) -> None:
    r = rig("rover", failsafe={"gps_glitch": {"timeout_s": 5.0}})
    r.h.vehicle.set(link__up=False)
    assert r.tick(20) == [R] * 20  # 2 s of link loss (limit 30 s)
    r.h.vehicle.set(vehicle__ekf=EKF_GLITCH)
    statuses = r.tick(100)
    assert statuses == [R] * 51 + [F]  # over the glitch's own 5 s
    assert failsafe(r).feedback_message == (
        "not recovered after 5 s: Link alive? no heartbeat from the autopilot; GPS not glitching? the EKF flags a GPS glitch (GPS_GLITCHING)"
    )
    assert failsafe_mode(r.h.root) == "HOLD"
    assert caplog.records[-1].getMessage() == "failsafe gps_glitch: not recovered within 5 s -> abort the mission"


def test_while_holding_the_feedback_counts_toward_the_nearest_limit(rig) -> None:
    r = rig("rover")
    r.h.vehicle.set(link__up=False)
    r.tick(31)
    assert failsafe(r).feedback_message == "in HOLD (3/30 s): Link alive? no heartbeat from the autopilot"  # accepted, and seen


def test_a_stronger_condition_replaces_the_reaction_in_force_and_a_weaker_one_does_not(rig, caplog) -> None:
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("sub")
    r.h.vehicle.set(link__up=False)
    assert r.tick() == [R] and r.sent() == [("mode", "SURFACE")]
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)  # hold (POSHOLD) would stop the surfacing
    assert r.tick(5) == [R] * 5 and r.sent() == []
    assert caplog.records[-1].getMessage() == (
        "failsafe ekf_loss: EKF has no position estimate (flags 0x81) -> hold (POSHOLD) not commanded: surface (SURFACE) for link_loss in force, "
        "resume when it recovers (within 30 s)"
    )
    r.h.vehicle.set(vehicle__battery=Battery(11.0, 2.0, 15, 1.0))  # surface, abort: already surfacing (low for 2 s: a sag is not low)
    assert r.tick(25) == [R] * 20 + [F] and r.sent() == []
    assert failsafe_mode(r.h.root) == "SURFACE"


def test_an_abort_during_a_hold_commands_its_own_reaction_at_once(rig) -> None:
    r = rig("rover")
    r.h.vehicle.set(link__up=False)
    assert r.tick() == [R] and r.sent() == [("mode", "HOLD")]
    r.h.vehicle.set(link__up=True, vehicle__battery=Battery(11.0, 2.0, 15, 1.0))
    assert r.tick(25) == [R] * 20 + [F] and r.sent() == [("mode", "RTL")]  # the battery low for 2 s


def test_nothing_is_commanded_while_a_person_has_the_vehicle_and_the_reaction_comes_when_they_let_go(rig) -> None:
    r = rig("rover")
    r.h.vehicle.set(rc__channels=RC_TAKEOVER, vehicle__mode="MANUAL", vehicle__mode_set_by="others")
    r.tick()
    r.h.vehicle.set(link__up=False, vehicle__ekf=EKF_LOST)
    assert r.tick(20) == [R] * 20 and r.sent() == []  # the pilot drives: not fought
    r.h.vehicle.set(rc__channels=RC_OK)  # the switch goes back, the link is still down, the vehicle still in MANUAL: a person drives it
    assert r.tick(20) == [R] * 20 and r.sent() == []
    r.h.vehicle.set(vehicle__mode="GUIDED")  # out of the person's mode (and the switch back for over 1 s): the reaction at once
    assert r.tick() == [R] and r.sent() == [("mode", "HOLD")]


@pytest.mark.parametrize("mode", ["MANUAL", "ACRO", "STEERING"])
def test_no_failsafe_changes_the_mode_while_a_person_drives_in_a_pilot_mode(rig, mode: str, caplog) -> None:
    """A pilot mode (set by a ground station, the RC or us at the operator's request), no take-over switch: RC loss is the autopilot's job."""
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover")
    r.h.vehicle.set(vehicle__mode=mode, vehicle__mode_set_by="others")
    r.tick()
    r.h.vehicle.set(rc__connected=False, rc__channels=(0,) * 8)  # the operator's transmitter drops out
    assert r.tick(10) == [R] * 10 and r.sent() == []
    said = f"failsafe rc_loss: RC transmitter gone (every channel 0) -> wait: hands off (the vehicle is in {mode}: a person drives it; "
    assert said in caplog.text
    assert "RC loss is the autopilot's own RC failsafe's job" in caplog.text
    r.h.vehicle.set(rc__connected=True, rc__channels=RC_OK)  # back: the work goes on, nothing was commanded
    assert r.tick() == [R] and r.sent() == []


def test_a_person_with_the_vehicle_is_not_fought_by_an_abort_either(rig) -> None:
    r = rig("rover")
    r.h.vehicle.set(rc__channels=RC_TAKEOVER, vehicle__battery=Battery(11.0, 2.0, 15, 1.0))
    assert r.tick(25) == [R] * 20 + [F] and r.sent() == []  # the battery low for 2 s
    assert failsafe_mode(r.h.root) is None  # the runtime then sees the take-over switch and keeps its hands off too


def test_disarm_puts_the_vehicle_in_manual_disarmed_then_re_arms_it_and_the_work_resumes(rig, caplog) -> None:
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("boat", failsafe={"ekf_loss": {"reaction": "disarm"}})
    r.shows = False  # the test writes what the heartbeat shows
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    assert r.tick() == [R] and r.sent() == [("mode", "MANUAL"), ("arm", 0.0)]  # both in the tick the EKF fails
    r.h.vehicle.set(vehicle__mode="MANUAL", vehicle__armed=False)
    assert r.tick(30) == [R] * 30 and r.sent() == []  # its own disarm is not a person's: no hands-off, no time-out of "disarmed"
    r.h.vehicle.set(vehicle__ekf=EKF_READY)
    assert r.tick(30) == [R] * 30 and r.sent() == []  # the EKF sane for 3 s before it counts as recovered
    assert r.tick() == [R] and r.sent() == [("arm", 1.0)]
    assert r.tick(18) == [R] * 18 and r.sent() == []  # the autopilot has not armed yet: asked again 2 s later
    assert r.tick(3) == [R] * 3 and r.sent() == [("arm", 1.0)]
    r.h.vehicle.set(vehicle__armed=True)
    assert r.tick() == [R] and work(r).status == R
    assert [m.getMessage() for m in caplog.records] == [
        "failsafe ekf_loss: EKF has no position estimate (flags 0x81) -> disarm in MANUAL, resume when it recovers (within 30 s)",
        "failsafe ekf_loss: recovered -> re-arm, then resume",
    ]


def test_a_disarm_reaction_brings_an_armed_guard_with_it() -> None:
    from executive.behaviours import Armed, LinkAlive, RcFresh
    from executive.trees.parts import failsafe_guards

    plain, disarming = make_mission(), make_mission(failsafe={"link_loss": {"reaction": "disarm"}})
    assert not any(isinstance(g, Armed) for g in failsafe_guards(plain, [LinkAlive(), RcFresh()]))
    assert any(isinstance(g, Armed) for g in failsafe_guards(disarming, [LinkAlive(), RcFresh()]))


def test_the_runtime_leaves_the_vehicle_in_the_mode_of_the_failsafe_that_ended_the_mission(runtime_on_link, vehicle: Vehicle) -> None:
    mission = make_mission()
    root = mission_root(mission, failsafe_guarded(py_trees.behaviours.Running("Work"), standard_guards(mission), mission))
    on_link = runtime_on_link(mission, root=root, safe_timeout_s=2.0)
    runtime, rover = on_link.runtime, on_link.autopilot
    runtime.mission_state.start()
    original = runtime.tick

    def tick() -> Status:  # the vehicle's facts the fake link does not carry, as the readers would write them
        vehicle.set(vehicle__ekf=EKF_READY, rc__channels=RC_OK, vehicle__position=position())
        vehicle.set(vehicle__battery=Battery(11.0, 2.0, 15 if runtime.ticks >= 5 else 80, 0.0))
        return original()

    runtime.tick = tick  # type: ignore[method-assign]
    outcome = runtime.run(start=False)
    assert (outcome.status, outcome.reason) == (MissionStatus.ABORTED, "Battery above floor?: battery 15% below 20%")
    assert rover.mode == "RTL"  # not HOLD, the rover's safe mode


def test_the_asv_ekf_rule_is_journalled_and_another_ekf_policy_replaces_it(clock: ManualClock, vehicle: Vehicle, caplog) -> None:
    from executive.trees.goto_sample import ekf_or_wait_in_manual

    caplog.set_level(logging.WARNING, logger="executive")
    sampling = {"tree": "goto_sample", "waypoints": [{"lat": HOME[0] + 0.0002, "lon": HOME[1], "sample": True}]}
    mission = make_mission("boat", **sampling)
    link = FakeLink()
    commander = Commander(link, clock, PROFILES["boat"])
    h = Harness(ekf_or_wait_in_manual(mission), clock, link, commander, MissionState())
    vehicle.set(vehicle__armed=True, vehicle__ekf=EKF_LOST)
    assert h.tick() == R
    assert [m.command for m in link.take("COMMAND_LONG")] == [mavlink.MAV_CMD_DO_SET_MODE]  # MANUAL, in that tick
    assert caplog.records[-1].getMessage() == (
        "failsafe ekf_loss: EKF has no position estimate (flags 0x81) -> disarm in MANUAL, resume when it recovers (within 30 s)"
    )
    names = {n.name for n in mission_tree.build(make_mission("boat", **sampling, failsafe={"ekf_loss": {"reaction": "hold"}})).iterate()}
    assert "EKF ok, else wait in MANUAL" not in names and "EKF ok?" in names  # then the EKF is one of the path's guards
    assert "EKF ok, else wait in MANUAL" in {n.name for n in mission_tree.build(mission).iterate()}


def test_two_rangefinder_sources_alternating_do_not_flap_the_altitude_failsafe(clock: ManualClock, vehicle: Vehicle, caplog) -> None:
    """Issue 14's 915 flaps, at the failsafe: the height above the seabed None / 45.2 m turn by turn (every 0.2 s) for 400 s.

    Undebounced (hold and resume at once) that is a hold and a resume every 0.4 s; debounced, a bad spell shorter than
    AltitudeWithin's 2 s is noise: the survey goes on, nothing is commanded.
    """
    from executive.behaviours import AltitudeWithin
    from executive.mission.model import Range

    def holds_and_resumes(hold_after_s: float, resume_after_s: float) -> tuple[int, int, int]:
        mission = make_mission("sub")
        link, state = FakeLink(), MissionState()
        state.upload(mission)
        state.start()
        altitude = AltitudeWithin(Range(min=2.0, max=100.0))
        altitude.hold_after_s, altitude.resume_after_s = hold_after_s, resume_after_s
        root = failsafe_guarded(py_trees.behaviours.Running("Survey"), [*standard_guards(mission), altitude], mission)
        commander = Commander(link, clock, PROFILES["sub"])
        h = Harness(root, clock, link, commander, state)
        vehicle.set(
            link__up=True, vehicle__armed=True, vehicle__mode="GUIDED", vehicle__ekf=EKF_READY, rc__channels=RC_OK, rc__connected=True,
            vehicle__battery=Battery(16.0, 2.0, 80, 0.0), vehicle__position=position(), vehicle__altitude_above_bottom_m=45.2,
        )  # fmt: skip
        caplog.clear()
        for tick in range(4000):  # 400 s at 10 Hz
            if tick % 2 == 0:
                vehicle.set(vehicle__altitude_above_bottom_m=None if tick % 4 == 2 else 45.2)
            assert h.tick() == R
        texts = [r.getMessage() for r in caplog.records if r.name == "executive.behaviours.failsafe"]
        modes = [m for m in link.take("COMMAND_LONG") if m.command == mavlink.MAV_CMD_DO_SET_MODE]
        return sum("-> hold" in t for t in texts), sum("recovered" in t for t in texts), len(modes)

    caplog.set_level(logging.WARNING, logger="executive")
    undebounced = holds_and_resumes(0.0, 0.0)
    assert undebounced[0] > 900 and undebounced[1] > 900  # the bug, reproduced: the guard flaps
    assert holds_and_resumes(AltitudeWithin.hold_after_s, AltitudeWithin.resume_after_s) == (0, 0, 0)


def leg_in_guided() -> py_trees.behaviour.Behaviour:
    return py_trees.composites.Sequence("Leg", memory=True, children=[SetMode("GUIDED"), py_trees.behaviours.Running("Drive")])


def test_a_mode_refused_after_a_recovery_is_asked_again_until_the_recovery_s_time_limit(rig, caplog) -> None:
    """The defect (ArduRover SITL, GPS off 8 s): the EKF healthy again, GUIDED refused while the firmware's own EKF failsafe
    stayed latched (~1 s), and the mission aborted at once: 'leg 3/4 failed: Set GUIDED: refused: FAILED'."""
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover", work_=leg_in_guided())
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    assert r.tick() == [R] and r.sent() == [("mode", "HOLD")]
    r.h.vehicle.set(vehicle__mode="HOLD")
    r.tick(20)
    r.refuse.add("GUIDED")  # the firmware's EKF failsafe is still latched
    r.h.vehicle.set(vehicle__ekf=EKF_READY)
    assert r.tick(60) == [R] * 60  # the guard counts as recovered after 3 s of a healthy EKF, then GUIDED is asked for 3 s
    asked = r.sent()
    assert asked.count(("mode", "GUIDED")) >= 5 and set(asked) == {("mode", "GUIDED")}
    assert "failsafe ekf_loss: recovered, but Set GUIDED: refused: FAILED -> asked again until the recovery's time limit" in caplog.text
    r.refuse.clear()  # "EKF failsafe cleared"
    assert r.tick(2) == [R] * 2 and r.sent() == [("mode", "GUIDED")]
    r.h.vehicle.set(vehicle__mode="GUIDED")
    assert r.tick(5) == [R] * 5 and r.h.node("Leg/Drive").status == R  # the leg drives again


def test_a_mode_still_refused_at_the_recovery_s_time_limit_ends_the_mission(rig) -> None:
    r = rig("rover", work_=leg_in_guided())
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    r.tick()
    r.h.vehicle.set(vehicle__mode="HOLD", vehicle__ekf=EKF_READY)
    r.refuse.add("GUIDED")
    statuses = r.tick(400)
    assert statuses[-1] == F and 280 <= len(statuses) <= 310  # 30 s (limits.recovery_timeout_s) from the EKF loss


def test_the_boot_mode_is_nobodys_the_failsafe_reacts(rig) -> None:
    """MANUAL as the autopilot booted (no one chose it): not a person driving."""
    r = rig("rover")
    r.h.vehicle.set(vehicle__mode="MANUAL", vehicle__mode_set_by=None, link__up=False)
    assert r.tick() == [R] and r.sent() == [("mode", "HOLD")]


# -- every reaction verified: asked until the autopilot accepts it and the heartbeat shows it, else the next one the firmware allows --


def play(r: Obeying, ticks: int) -> tuple[list[tuple[float, tuple[str, Any]]], list[str]]:
    """``ticks`` ticks: what was asked and when (seconds from the first tick), and the reaction's states the feedback went through."""
    start, asked, states = r.h.clock.now() + 0.1, [], []
    for _ in range(ticks):
        if r.tick() != [R]:
            break
        asked += [(round(r.h.clock.now() - start, 1), c) for c in r.sent()]
        state = re.sub(r" \(\d+/\d+ s\): .*$", "", failsafe(r).feedback_message)
        if not states or states[-1] != state:
            states.append(state)
    return asked, states


def announced(r: Obeying) -> list[str]:
    """The STATUSTEXTs the ground station will send (the mission state's announcements), gathered from now on."""
    texts: list[str] = []
    r.h.mission_state.events.subscribe(Announcement, lambda text, warning: texts.append(text))
    return texts


def test_a_refused_reaction_is_asked_again_every_1_5_s_then_the_next_the_firmware_allows(rig, caplog) -> None:
    """ArduRover refuses HOLD (a scripted refusal: the firmware's HOLD needs nothing): asked 3 times, 1.5 s apart, then a disarm."""
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover")
    texts = announced(r)
    r.refuse.add("HOLD")
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    asked, states = play(r, 60)
    assert asked == [(0.0, ("mode", "HOLD")), (1.5, ("mode", "HOLD")), (3.0, ("mode", "HOLD")), (4.5, ("arm", 0.0))]
    assert states == [
        "asking HOLD",
        "asking HOLD: refused (FAILED)",
        "asking HOLD: refused (FAILED) x2",
        "asking HOLD: refused (FAILED) x3",
        "asking disarm instead of HOLD",
        "disarmed",
    ]
    assert [m.getMessage() for m in caplog.records] == [
        "failsafe ekf_loss: EKF has no position estimate (flags 0x81) -> hold (HOLD), resume when it recovers (within 30 s)",
        "failsafe ekf_loss: HOLD refused (FAILED) -> asked again every 1.5 s",
        "failsafe ekf_loss: HOLD refused (FAILED) x3 after 3 asks -> disarm instead "
        "(ArduRover HOLD needs no position (Rover/mode.h); a disarm stops the motors (Rover/AP_Arming_Rover.cpp))",
        "failsafe ekf_loss: the vehicle disarmed (accepted and seen; 1 ask, 0.1 s)",
    ]
    assert texts == [
        "failsafe ekf_loss -> hold (HOLD)",
        "ekf_loss: HOLD refused (FAILED)",
        "ekf_loss: HOLD refused (FAILED) x3 -> disarm",
        "ekf_loss: disarmed, confirmed",
    ]
    assert all(len(t) <= 50 for t in texts)  # a STATUSTEXT's room
    r.h.vehicle.set(vehicle__ekf=EKF_READY)  # recovered (3 s sane): re-armed, then the work resumes
    assert r.tick(40) == [R] * 40 and work(r).status == R and r.sent() == [("arm", 1.0)]


def test_a_reaction_never_answered_is_asked_again_and_the_next_one_after_three_asks(rig) -> None:
    """Heartbeats arrive (the link is up) but no ack ever comes: 3 unanswered asks are 3 failed asks."""
    r = rig("rover")
    r.acks = False
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    asked, states = play(r, 80)
    assert asked == [(0.0, ("mode", "HOLD")), (1.5, ("mode", "HOLD")), (3.0, ("mode", "HOLD"))] + [(t, ("arm", 0.0)) for t in (4.5, 6.0, 7.5)]
    assert states == [
        "asking HOLD",
        "asking HOLD: no answer",
        "asking HOLD: no answer x2",
        "asking disarm instead of HOLD",  # the third "no answer" is judged in the tick the next reaction is asked
        "asking disarm instead of HOLD: no answer",
        "asking disarm instead of HOLD: no answer x2",  # nothing after a disarm: asked again until the failsafe's time is up
    ]


def test_with_the_link_down_an_unanswered_reaction_is_asked_again_until_the_failsafes_time_and_never_replaced(rig) -> None:
    """No heartbeat, no ack: nothing says the vehicle cannot enter HOLD (it may hear us: a downlink loss), so HOLD it stays."""
    r = rig("rover")
    r.acks = False
    r.h.vehicle.set(link__up=False)
    first_tick = r.h.clock.now() + 0.1
    asked, states = play(r, 400)
    assert {c for _, c in asked} == {("mode", "HOLD")} and [t for t, _ in asked] == [1.5 * n for n in range(21)]  # the last in the abort's tick
    assert states[:3] == ["asking HOLD", "asking HOLD: no answer", "asking HOLD: no answer x2"] and states[-1] == "asking HOLD: no answer x20"
    assert failsafe(r).feedback_message == "not recovered after 30 s: Link alive? no heartbeat from the autopilot"
    assert failsafe(r).status == F and round(r.h.clock.now() - first_tick, 1) == 30.1 and failsafe_mode(r.h.root) == "HOLD"


def test_a_reaction_accepted_but_never_seen_is_asked_again_then_the_next_one(rig) -> None:
    """The autopilot acks ACCEPTED and its heartbeat stays in GUIDED: not done."""
    r = rig("rover")
    r.shows = False
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    asked, states = play(r, 70)
    assert asked[:4] == [(0.0, ("mode", "HOLD")), (1.5, ("mode", "HOLD")), (3.0, ("mode", "HOLD")), (4.5, ("arm", 0.0))]
    assert states[:6] == [
        "asking HOLD",
        "asking HOLD: accepted, the vehicle still in GUIDED",
        "asking HOLD: accepted, the vehicle still in GUIDED x2",
        "asking disarm instead of HOLD",
        "asking disarm instead of HOLD: accepted, the vehicle still armed",
    ]


def test_a_reaction_accepted_late_is_done_when_its_ack_and_the_heartbeat_come(rig, caplog) -> None:
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover")
    texts = announced(r)
    r.acks = False
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    asked, states = play(r, 20)  # 2 s: asked at 0 and 1.5 s, no answer
    r.h.ack(mavlink.MAV_CMD_DO_SET_MODE)  # the answer comes at last...
    asked2, states2 = play(r, 5)
    assert states2 == ["asking HOLD: no answer"]  # ...and the heartbeat still shows GUIDED: not done
    r.h.vehicle.set(vehicle__mode="HOLD")
    asked3, states3 = play(r, 20)
    assert asked == [(0.0, ("mode", "HOLD")), (1.5, ("mode", "HOLD"))] and asked2 == asked3 == []  # never asked again once accepted
    assert states == ["asking HOLD", "asking HOLD: no answer"] and states3 == ["in HOLD"]
    assert caplog.records[-1].getMessage() == "failsafe ekf_loss: the vehicle in HOLD (accepted and seen; 2 asks, 2.5 s)"
    assert texts[-1] == "ekf_loss: in HOLD, confirmed"


def test_the_first_reaction_the_firmware_allows_in_the_vehicles_state_is_asked_at_once(rig, caplog) -> None:
    """ArduRover refuses RTL without a position estimate (Rover/mode.cpp Mode::enter): with the EKF lost, HOLD at once, never RTL."""
    caplog.set_level(logging.WARNING, logger="executive")
    r = rig("rover", failsafe={"ekf_loss": {"reaction": "rtl"}})
    r.h.vehicle.set(vehicle__ekf=EKF_LOST)
    asked, states = play(r, 10)
    assert asked == [(0.0, ("mode", "HOLD"))] and states == ["asking HOLD instead of RTL", "in HOLD"]
    assert caplog.records[1].getMessage() == (
        "failsafe ekf_loss: RTL cannot be entered: the EKF has no position estimate (flags 0x81) (ArduRover RTL needs a position "
        "estimate and home (Rover/mode.cpp Mode::enter, Rover/mode_rtl.cpp)) -> HOLD instead"
    )


@pytest.mark.parametrize(
    ("kind", "breaks", "refused", "expected"),
    [
        # ArduSub: POSHOLD needs a position (ArduSub/mode.cpp Sub::set_mode): ALT_HOLD at once, as its own terrain failsafe does
        ("sub", {"vehicle__ekf": EKF_LOST}, set(), [(0.0, ("mode", "ALT_HOLD"))]),
        # a sub refused SURFACE x3: a disarm (ArduSub/failsafe.cpp failsafe_gcs_check does the same)
        ("sub", {"link__up": True, "vehicle__battery": Battery(11.0, 2.0, 15, 1.0)}, {"SURFACE"}, None),
        # ArduPlane QuadPlane refused QLOITER x3: QLAND (ArduPlane/events.cpp, its own failsafe's landing); never a disarm
        ("vtol", {"vehicle__ekf": EKF_LOST}, {"QLOITER"}, [(0.0, ("mode", "QLOITER")), (1.5, ("mode", "QLOITER")), (3.0, ("mode", "QLOITER")),
                                                          (4.5, ("mode", "QLAND"))]),
        # ... and as a plane, LOITER refused x3: CIRCLE (no position needed: ArduPlane/mode_circle.cpp)
        ("vtol-fw", {"vehicle__ekf": EKF_LOST}, {"LOITER"}, [(0.0, ("mode", "LOITER")), (1.5, ("mode", "LOITER")), (3.0, ("mode", "LOITER")),
                                                            (4.5, ("mode", "CIRCLE"))]),
    ],
)  # fmt: skip
def test_the_next_reaction_is_the_firmwares(rig, kind: str, breaks: dict[str, Any], refused: set[str], expected: Any) -> None:
    r = rig(kind.removesuffix("-fw"))
    if kind.endswith("-fw"):
        r.h.vehicle.set(vehicle__vtol_state="FW")
        r.tick()
    r.refuse |= refused
    r.h.vehicle.set(**breaks)
    statuses = r.tick(60)
    asked = r.sent()
    if expected is None:  # battery_low: surface, abort: the failsafe ends at once (the runtime then keeps asking SURFACE)
        assert statuses == [R] * 20 + [F] and asked == [("mode", "SURFACE")] and failsafe_mode(r.h.root) == "SURFACE"
        return
    assert [c for c in asked if c[0] == "mode"] == [c for _, c in expected]
    assert not [c for c in asked if c[0] == "arm"]


def test_on_px4_a_rovers_refused_hold_is_followed_by_a_disarm(rig) -> None:
    """PX4's AUTO.LOITER needs a global position (commander/ModeUtil/mode_requirements.cpp); a rover may always be disarmed (Commander.cpp)."""
    r = rig("rover")
    r.h.autopilot.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_GROUND_ROVER)
    r.h.vehicle.set(vehicle__mode="OFFBOARD")
    px4_modes = {number: name for name, number in PX4_MODES.items()}
    on_command = r.on_command

    def answer(msg: MAVLinkMessage) -> int | None:  # PX4 puts the main mode in param2, the sub mode in param3
        if msg.command != mavlink.MAV_CMD_DO_SET_MODE:
            return on_command(msg)
        mode = px4_modes[(int(msg.param2) << 16) | (int(msg.param3) << 24)]
        r.commands.append(("mode", mode))
        return mavlink.MAV_RESULT_TEMPORARILY_REJECTED  # "Switching to Hold is currently not available" (Commander.cpp)

    r.on_command = answer  # type: ignore[method-assign]
    r.h.vehicle.set(rc__connected=False)  # rc_loss: hold
    asked, states = play(r, 60)
    assert asked == [(0.0, ("mode", "AUTO.LOITER")), (1.5, ("mode", "AUTO.LOITER")), (3.0, ("mode", "AUTO.LOITER")), (4.5, ("arm", 0.0))]
    assert states == [
        "asking AUTO.LOITER",
        "asking AUTO.LOITER: refused (TEMPORARILY_REJECTED)",
        "asking AUTO.LOITER: refused (TEMPORARILY_REJECTED) x2",
        "asking AUTO.LOITER: refused (TEMPORARILY_REJECTED) x3",
        "asking disarm instead of AUTO.LOITER",
        "disarmed",
    ]


def test_each_step_reaches_the_operator_statustext_status_json_and_line(runtime_on_link, vehicle: Vehicle) -> None:
    """A whole runtime, the autopilot refusing HOLD: the ground station's STATUSTEXTs, ``ctl status``'s JSON and the status line say
    what the reaction waits for, then what replaced it."""
    from executive.operator.status import StatusSource, status_line

    mission = make_mission()
    root = mission_root(mission, failsafe_guarded(py_trees.behaviours.Running("Work"), standard_guards(mission), mission))
    on_link = runtime_on_link(mission, root=root, beat=True)
    on_link.autopilot.refuse.add("HOLD")
    on_link.runtime.mission_state.start()
    status = StatusSource("test", on_link.clock)
    seen: list[tuple[str, str]] = []  # the JSON's waiting feedback (its reaction) and the status line, as the reaction changes
    for tick in range(80):
        now_s = on_link.clock.now()  # the reports arrive fresh each tick, as the reader stamps them
        ekf = dataclasses.replace(EKF_READY if tick < 5 else EKF_LOST, time=now_s)
        vehicle.set(vehicle__ekf=ekf, rc__channels=RC_OK, vehicle__position=position(), rc__last_update=now_s)
        vehicle.set(vehicle__battery=Battery(12.4, 2.0, 80, now_s))
        on_link.tick()
        now = status.snapshot()
        if now["waiting"] is not None and now["waiting"]["node"] == "Wait for guards":
            reaction = re.sub(r" \(\d+/\d+ s\): .*$", "", now["waiting"]["feedback"])
            if not seen or seen[-1][0] != reaction:
                seen.append((reaction, status_line(now)))
    for reaction, line in seen:
        print(f"{reaction!r:60} | {line}")
    assert [reaction for reaction, _ in seen] == [
        "asking HOLD",
        "asking HOLD: refused (FAILED)",
        "asking HOLD: refused (FAILED) x2",
        "asking HOLD: refused (FAILED) x3",
        "asking disarm instead of HOLD",
        "disarmed",
    ]
    for reaction, line in seen:  # the line: the node, its time, then the feedback (cut at 60 characters)
        assert re.search(r"waiting: Wait for guards \(\d+ s\): " + re.escape(reaction), line), line
    assert [text for text in on_link.texts() if not text.startswith("mission ")] == [
        "failsafe ekf_loss -> hold (HOLD)",
        "ekf_loss: HOLD refused (FAILED)",
        "ekf_loss: HOLD refused (FAILED) x3 -> disarm",
        "ekf_loss: disarmed, confirmed",
    ]


def test_a_reaction_still_asked_is_dropped_while_a_person_has_the_vehicle_and_asked_again_when_they_let_go(rig) -> None:
    r = rig("rover")
    r.acks = False
    r.h.vehicle.set(link__up=False)
    asked, _ = play(r, 5)
    assert asked == [(0.0, ("mode", "HOLD"))]
    r.h.vehicle.set(rc__channels=RC_TAKEOVER)  # the pilot throws the take-over switch: the unanswered HOLD is not sent again
    asked, states = play(r, 50)
    assert asked == [] and states == ["hands off"] and r.commander.idle
    r.h.vehicle.set(rc__channels=RC_OK)  # let go (the switch back for RcNotTakingOver's 1 s): HOLD asked again at once
    asked, states = play(r, 12)
    assert asked == [(1.0, ("mode", "HOLD"))] and states == ["hands off", "asking HOLD"]
