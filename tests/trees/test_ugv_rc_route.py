"""The tracked UGV's RC route tree, tick by tick against a scripted ArduRover, and once end to end on the simulated Bunker.

The scripted rover obeys mode and arm commands at once (or refuses them when told to), answers the
mission protocol with the simulator's own mission store (ArduPilot's conventions: home at item 0,
MISSION_REQUEST, read-back as stored), and in AUTO steps toward the current mission item, reporting
MISSION_CURRENT and MISSION_ITEM_REACHED as ArduRover does.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

from executive.behaviours.auto_route import MISSION_STATE_COMPLETE
from executive.io.mavlink.mission_protocol import MissionCurrent, MissionItemReached
from executive.mission.errors import MissionError
from executive.mission.loader import load_mission, load_mission_text
from executive.mission.model import Mission, RcConfig
from executive.runtime.loop import RunOutcome, Runtime
from executive.sensing.rc import RcReader
from executive.sim.faults import FaultInjector, RcInput, RcLoss
from executive.testing import EKF_READY, Harness, Lockstep, MissionAutopilot
from executive.tree import select as mission_tree
from executive.world import geo
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.state import EkfFlags, EkfStatus, GlobalPosition, SwitchPosition

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN
PWM = {UP: 1000, MIDDLE: 1500, DOWN: 2000}
EKF_LOST = EkfStatus(EkfFlags.ATTITUDE | EkfFlags.CONST_POS_MODE, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0)
START = (-35.363261, 149.165230)
ROOT = Path(__file__).parents[2]
_M = mavlink


def mission_with(**changes: object) -> Mission:
    doc: dict[str, object] = {
        "version": 1, "name": "rc-route", "vehicle": "rover", "tree": "ugv_rc_route",
        "limits": {"recovery_timeout_s": 10.0, "ekf_wait_s": 20.0},
        "rc_route": {"aux_mode": "HOLD", "operator_timeout_s": 30.0},
        "simulator": {"params": {"MODE_CH": 0}},  # as ugv_rc_route.yaml: switch D is on ArduRover's default mode channel 8
        "waypoints": [],
    }  # fmt: skip
    doc.update(changes)
    return Mission.model_validate(doc)


def ahead(north_m: float, east_m: float = 0.0) -> tuple[float, float]:
    """A point north and east of START."""
    lat, lon = geo.destination(*START, 0.0, north_m)
    return geo.destination(lat, lon, 90.0, east_m)


def flat(points) -> list[float]:
    """Latitudes and longitudes in one list, for pytest.approx."""
    return [x for point in points for x in point]


REFUSALS = {"mode": (4, "Flight mode change failed"), "arm": (2, "PreArm: AHRS: not using configured AHRS type")}


class ScriptedRover(MissionAutopilot):
    """ArduRover behind the tree (10 Hz), answering at once: a whole upload and read-back within a tick; a refusal says why in a
    STATUSTEXT; its facts and the operator's RC channels read at the start of each tick, as the runtime's readers do."""

    def __init__(self, h: Harness, rc: RcConfig) -> None:
        self.mode_set_by: str | None = None  # the boot mode: nobody's; "us" once a DO_SET_MODE put it in its mode
        self.link_up = self.rc_alive = True
        self.ekf = EKF_READY
        self.position_age_s = 0.0  # how old the position reports are
        self.channels = [1500] * 16
        switches = rc.switch_channels
        self._channel = {"swa": switches.swa, "swb": switches.swb, "swc": switches.swc, "swd": switches.swd, "knob": switches.knob}
        self._rc_time = h.clock.now()
        super().__init__(h, START, step_m=2.0, mode="MANUAL")
        self.rc(swa=UP, swb=UP, swc=UP, swd=UP, knob=0)
        h.readers += [self.publish, RcReader(rc, h.clock).service]

    # -- the operator ----------------------------------------------------------------------------
    def rc(self, **positions: SwitchPosition | int | None) -> None:
        """``rc(swc=MIDDLE, knob=-50)``: the operator moves switches (None: the channel reads 0)."""
        for name, where in positions.items():
            pwm = 0 if where is None else 1500 + 5 * where if name == "knob" else PWM[where]  # type: ignore[index, operator]
            self.channels[self._channel[name] - 1] = pwm

    # -- ticking ---------------------------------------------------------------------------------
    def tick(self) -> Status:
        return self.run(1)[0]

    def run_until(self, done: Callable[[], bool], limit: int = 600) -> int:
        """Ticks until ``done()``; fails the test if it never is."""
        for n in range(1, limit + 1):
            assert self.tick() == Status.RUNNING
            if done():
                return n
        raise AssertionError(f"not done after {limit} ticks")

    # -- the scripted rover ----------------------------------------------------------------------
    def publish(self) -> None:
        if self.rc_alive:
            self._rc_time = self.clock.now()
            self.h.vehicle.set(rc__channels=tuple(self.channels))
        super().publish()

    def facts(self) -> dict[str, object]:
        now = self.clock.now()
        return {
            "link__up": self.link_up, "vehicle__mode": self.mode, "vehicle__mode_set_by": self.mode_set_by, "vehicle__armed": self.armed,
            "vehicle__ekf": self.ekf, "vehicle__position": GlobalPosition(self.lat, self.lon, 0.0, 0.0, 0.0, 0.0, None, now - self.position_age_s),
            "rc__last_update": self._rc_time,
        }  # fmt: skip

    def on_command(self, msg: MAVLinkMessage) -> int | None:
        result = super().on_command(msg)
        if result != _M.MAV_RESULT_ACCEPTED and self.commands[-1][0] in REFUSALS:
            self.statustext(*REFUSALS[self.commands[-1][0]])
        return result

    def enter_mode(self, mode: str) -> bool:
        entered = super().enter_mode(mode)
        if entered:
            self.mode_set_by = "us"
        return entered

    def on_message(self, msg: MAVLinkMessage) -> None:
        kind = msg.get_type()
        if kind == "MISSION_COUNT":
            self.commands.append(("upload", msg.count - 1))  # waypoints after home
        elif kind == "MISSION_REQUEST_LIST":
            self.commands.append(("read back",))
        super().on_message(msg)

    def respond(self) -> None:
        for _ in range(50):  # the rover answers at once: a whole upload and read-back within one tick
            sent = self.h.link.take()
            if not sent:
                break
            for msg in sent:
                self.answer(msg)
            self.deliver()
            self.transfer.flush()
            self.commander.flush()
        self.move()
        self.deliver()


def waypoints(r: ScriptedRover) -> list[tuple[float, float]]:
    """The route in the mission state."""
    return [(wp.lat, wp.lon) for wp in r.h.mission_state.legs.route.waypoints]


@pytest.fixture
def rover_for(clock) -> Callable[[Mission], ScriptedRover]:
    """``rover_for(mission)``: the mission's tree on a :class:`Harness`, a :class:`ScriptedRover` answering."""
    return lambda mission: ScriptedRover(Harness.build(mission, clock=clock, transfer=True), mission.rc)


@pytest.fixture
def rover(rover_for) -> ScriptedRover:
    """An empty route, the rover in MANUAL and disarmed; ticked once: the empty route is on the rover."""
    r = rover_for(mission_with())
    assert r.tick() == Status.RUNNING
    assert r.take() == [("upload", 0), ("read back",)]  # the mission's route (none) replaces whatever the rover held
    return r


def record(r: ScriptedRover, *points: tuple[float, float]) -> None:
    """Drive to each point and flip switch A down and up there, the knob in the middle."""
    r.rc(knob=0)
    for point in points:
        r.lat, r.lon = point
        r.rc(swa=DOWN)
        r.tick()
        r.rc(swa=UP)
        r.tick()


# -- the whole story, tick by tick ---------------------------------------------------------------


def test_the_operator_arms_records_a_route_and_auto_drives_it_to_the_end(rover: ScriptedRover) -> None:
    rover.rc(swd=DOWN)
    assert rover.tick() == Status.RUNNING
    assert rover.take() == [("arm", 1.0)] and rover.armed
    assert rover.h.feedback("Switch D: arm") == "switch D DOWN: asked to be armed"
    rover.tick()
    assert rover.h.feedback("Switch D: arm") == "switch D DOWN: armed"  # the heartbeat shows it
    points = [ahead(10.0), ahead(20.0), ahead(20.0, 10.0)]
    for n, point in enumerate(points, start=1):
        rover.lat, rover.lon = point
        rover.rc(swa=DOWN)
        assert rover.tick() == Status.RUNNING
        assert rover.take() == [("upload", n), ("read back",)]
        assert rover.h.feedback("Switch A: edit the route") == f"switch A DOWN, knob +0: waypoint {n} added at {point[0]:.7f}, {point[1]:.7f}"
        assert waypoints(rover) == points[:n]
        assert flat(rover.held()) == pytest.approx(flat(points[:n]), abs=1e-7)
        rover.rc(swa=UP)
        assert rover.tick() == Status.RUNNING
        assert rover.take() == []
    assert rover.h.feedback("Keep the route on the autopilot") == "the autopilot holds the route: 3 waypoints, read back"
    assert rover.h.feedback("Drive the route in AUTO").startswith("waiting for the operator (")
    assert rover.h.feedback("Drive the route in AUTO").endswith("switch C to the middle (AUTO) drives the route; the mode is MANUAL")
    rover.rc(swc=MIDDLE)
    assert rover.tick() == Status.RUNNING
    assert rover.take() == [("mode", "AUTO")]
    legs = []
    while (status := rover.tick()) == Status.RUNNING:
        legs.append(rover.h.mission_state.legs.leg_index)
    assert status == Status.SUCCESS
    assert sorted(set(legs)) == [0, 1, 2, 3]  # the leg index followed the rover through every waypoint
    assert rover.take() == [("mode", "HOLD")]  # held at the end; nothing else was asked on the way
    assert (rover.lat, rover.lon) == pytest.approx(points[-1], abs=1e-7)  # at the last waypoint, as the rover stored it


# -- switch C: the mode --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("aux", "mode", "route", "before", "after", "commands", "feedback"),
    [
        ("HOLD", "MANUAL", 0, UP, DOWN, [("mode", "HOLD")], "switch C DOWN: HOLD"),
        (None, "MANUAL", 0, UP, DOWN, [], "switch C DOWN: no aux mode set (rc_route.aux_mode): ignored"),
        ("HOLD", "HOLD", 0, DOWN, UP, [("mode", "MANUAL")], "switch C UP: MANUAL"),
        ("HOLD", "MANUAL", 0, MIDDLE, UP, [], "switch C UP: MANUAL (already)"),
        ("HOLD", "MANUAL", 1, UP, MIDDLE, [("mode", "AUTO")], "switch C MIDDLE: AUTO"),
        ("HOLD", "MANUAL", 0, UP, MIDDLE, [], "switch C MIDDLE: AUTO not asked: no route recorded"),
    ],
)
def test_switch_c_sets_the_mode_when_it_moves(rover_for, aux, mode, route, before, after, commands, feedback) -> None:
    r = rover_for(mission_with(rc_route={"aux_mode": aux}, waypoints=[{"lat": ahead(5.0)[0], "lon": START[1]}] * route))
    r.mode = mode
    r.rc(swc=before)
    assert r.run(3) == [Status.RUNNING] * 3
    assert r.take() == [("upload", route), ("read back",)]  # the first position is acted on: nothing to do in these
    r.rc(swc=after)
    assert r.run(2) == [Status.RUNNING] * 2
    assert r.take() == commands
    assert r.h.feedback("Switch C: mode") == feedback


def test_switch_c_does_not_fight_a_ground_station(rover: ScriptedRover) -> None:
    rover.rc(swc=DOWN)
    rover.tick()
    assert rover.take() == [("mode", "HOLD")]
    rover.mode = "GUIDED"  # a ground station takes the vehicle (the runtime pauses the mission: see tests/operator/test_intervention.py)
    assert rover.run(20) == [Status.RUNNING] * 20
    assert rover.take() == []


def test_a_switch_already_in_auto_at_the_start_drives_the_route_without_a_flick(rover_for) -> None:
    """The defect: the tree waited for switch C to change; with it already in AUTO the mission timed out."""
    r = rover_for(mission_with(waypoints=[{"lat": ahead(5.0)[0], "lon": START[1]}, {"lat": ahead(10.0)[0], "lon": START[1]}]))
    r.armed = True
    r.rc(swc=MIDDLE)
    statuses = r.run(100)
    assert statuses[-1] == Status.SUCCESS
    assert r.take() == [("upload", 2), ("read back",), ("mode", "AUTO"), ("mode", "HOLD")]


def test_after_a_failsafe_hold_the_vehicle_is_put_back_in_the_switchs_mode(rover: ScriptedRover) -> None:
    """The defect: 'resume leg 1/4' was logged but the mode stayed HOLD, switch C still in AUTO."""
    rover.armed, rover.step_m = True, 0.05
    record(rover, ahead(10.0), ahead(20.0))
    rover.rc(swc=MIDDLE)
    rover.run(3)
    assert rover.mode == "AUTO"
    rover.take()
    rover.rc_alive = False  # the receiver's report freezes
    rover.run(12)
    assert rover.take() == [("mode", "HOLD")] and rover.mode == "HOLD"
    rover.rc_alive = True
    rover.run_until(lambda: rover.mode == "AUTO", limit=40)  # once the guard counts as recovered (its hysteresis)
    assert rover.take() == [("mode", "AUTO")]


def test_auto_waits_for_the_route_upload_then_is_asked(rover: ScriptedRover) -> None:
    rover.answers_missions = False  # the rover does not answer the mission protocol for now
    record(rover, ahead(10.0))
    rover.rc(swc=MIDDLE)
    rover.tick()
    assert rover.take() == [("upload", 1)]  # the count, unanswered; no AUTO
    assert rover.h.feedback("Switch C: mode").startswith("switch C MIDDLE: AUTO waits for the route upload: the autopilot's mission differs")
    assert rover.h.feedback("Keep the route on the autopilot") == "uploading the route: sending 0/2 items"
    rover.answers_missions = True
    n = rover.run_until(lambda: rover.mode == "AUTO", limit=30)
    assert rover.take() == [("upload", 1), ("read back",), ("mode", "AUTO")]  # the count resent after 1.5 s, then all went through
    assert 14 <= n <= 17
    assert rover.h.feedback("Switch C: mode") == "switch C MIDDLE: AUTO: asked"
    rover.tick()
    assert rover.h.feedback("Switch C: mode") == "switch C MIDDLE: AUTO"  # the heartbeat shows it


def test_a_mode_refused_by_the_autopilot_is_reported_and_the_mission_goes_on(rover: ScriptedRover) -> None:
    record(rover, ahead(10.0))
    rover.take()
    rover.refuse.add("AUTO")
    rover.rc(swc=MIDDLE)
    assert rover.run(10) == [Status.RUNNING] * 10
    assert rover.take() == [("mode", "AUTO")]
    assert rover.h.feedback("Switch C: mode") == "switch C MIDDLE: AUTO refused: FAILED (Flight mode change failed); asking again in 2 s"
    assert rover.run(220) == [Status.RUNNING] * 220
    assert rover.take() == [("mode", "AUTO")] * 9  # every 2 s, for 20 s from the flick (a firmware failsafe may be latched), then no more
    assert rover.h.feedback("Switch C: mode") == "switch C MIDDLE: AUTO refused: FAILED (Flight mode change failed)"
    rover.refuse.clear()
    rover.rc(swc=UP)
    rover.tick()
    rover.rc(swc=MIDDLE)  # the operator tries again
    rover.tick()
    assert rover.take() == [("mode", "AUTO")] and rover.mode == "AUTO"


# -- switch D: arming ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("mode", "armed", "before", "after", "commands", "feedback"),
    [
        ("MANUAL", False, UP, DOWN, [("arm", 1.0)], "switch D DOWN: armed"),
        ("HOLD", False, UP, DOWN, [], "switch D DOWN: arming refused: the mode is HOLD; ArduRover arms only in MANUAL (switch C up)"),
        ("AUTO", False, UP, DOWN, [], "switch D DOWN: arming refused: the mode is AUTO; ArduRover arms only in MANUAL (switch C up)"),
        ("MANUAL", True, DOWN, UP, [("arm", 0.0)], "switch D UP: disarmed"),
        ("AUTO", True, DOWN, UP, [("arm", 0.0)], "switch D UP: disarmed"),  # disarming is allowed in any mode
        ("MANUAL", True, UP, DOWN, [], "switch D DOWN: already armed"),
        ("MANUAL", False, DOWN, UP, [], "switch D UP: already disarmed"),
        ("MANUAL", False, UP, MIDDLE, [], "switch D MIDDLE: a two-position switch has no middle: ignored"),
    ],
)
def test_switch_d_arms_only_in_manual_and_disarms(rover_for, mode, armed, before, after, commands, feedback) -> None:
    r = rover_for(mission_with())
    r.mode, r.armed = mode, armed
    r.rc(swd=before, swc={"MANUAL": UP, "HOLD": DOWN, "AUTO": MIDDLE}[mode])  # switch C where the mode is (AUTO: no route, not asked)
    r.tick()
    assert r.take() == [("upload", 0), ("read back",)]  # the first position is only noted
    r.rc(swd=after)
    assert r.run(2) == [Status.RUNNING] * 2
    assert r.take() == commands
    assert r.h.feedback("Switch D: arm") == feedback


def test_switch_d_down_with_switch_c_just_put_up_arms_once_the_heartbeat_shows_manual(rover_for) -> None:
    """Both flicked at once (or seen in one late tick): the arm waits for MANUAL instead of being refused."""
    r = rover_for(mission_with())
    r.mode, r.armed = "HOLD", False
    r.rc(swd=UP, swc=DOWN)
    r.tick()
    r.take()
    r.rc(swc=UP, swd=DOWN)
    r.tick()
    assert r.take() == [("mode", "MANUAL")]
    assert r.h.feedback("Switch D: arm") == "switch D DOWN: arming once the mode is MANUAL (switch C up; the mode is HOLD)"
    assert r.run(2) == [Status.RUNNING] * 2
    assert r.take() == [("arm", 1.0)]
    assert r.armed and r.h.feedback("Switch D: arm") == "switch D DOWN: armed"


@pytest.mark.parametrize(
    ("then", "feedback"),
    [
        ({}, "switch D DOWN: arming refused: the mode is HOLD, not MANUAL after 5 s (switch C up)"),
        ({"swc": MIDDLE}, "switch D DOWN: arming refused: switch C left MANUAL before the mode showed it (the mode is HOLD)"),
    ],
)
def test_switch_d_down_waiting_for_manual_is_refused_when_it_never_shows_or_switch_c_moves_on(rover_for, then, feedback) -> None:
    r = rover_for(mission_with())
    r.mode, r.armed = "HOLD", False
    r.refuse.add("MANUAL")
    r.rc(swd=UP, swc=DOWN)
    r.tick()
    r.rc(swc=UP, swd=DOWN)
    r.tick()
    if then:
        r.rc(**then)
    r.run(60)
    assert ("arm", 1.0) not in r.take() and not r.armed
    assert r.h.feedback("Switch D: arm") == feedback


def test_an_arm_refused_by_the_autopilot_says_why_and_is_not_retried(rover: ScriptedRover) -> None:
    rover.refuse.add("arm")
    rover.rc(swd=DOWN)
    assert rover.run(60) == [Status.RUNNING] * 60
    assert rover.take() == [("arm", 1.0)]
    assert rover.h.feedback("Switch D: arm") == "switch D DOWN: not armed: refused: FAILED (PreArm: AHRS: not using configured AHRS type)"


# -- switch A and the knob: route edits ----------------------------------------------------------

ROUTE = [ahead(10.0), ahead(20.0), ahead(30.0)]


@pytest.mark.parametrize(
    ("knob", "edit", "route_after", "leg_after"),
    [
        (-100, "route cleared (3 waypoints removed)", [], 0),
        (-26, "route cleared (3 waypoints removed)", [], 0),
        (-25, "waypoint 4 added at {here}", [*ROUTE, "here"], 1),
        (0, "waypoint 4 added at {here}", [*ROUTE, "here"], 1),
        (25, "waypoint 4 added at {here}", [*ROUTE, "here"], 1),
        (26, "waypoint 2/3 removed", [ROUTE[0], ROUTE[2]], 1),  # the current one: the rover heads for waypoint 2
        (100, "waypoint 2/3 removed", [ROUTE[0], ROUTE[2]], 1),
    ],
)
def test_switch_a_edits_the_route_by_the_knob_and_the_edit_is_uploaded(rover_for, knob, edit, route_after, leg_after) -> None:
    r = rover_for(mission_with(waypoints=[{"lat": lat, "lon": lon} for lat, lon in ROUTE]))
    r.tick()
    r.h.mission_state.advance_leg()  # waypoint 1 is behind: heading for waypoint 2
    r.lat, r.lon = here = ahead(15.0, 5.0)
    r.rc(knob=knob)
    r.tick()
    assert r.take() == [("upload", 3), ("read back",)]
    r.rc(swa=DOWN)
    assert r.tick() == Status.RUNNING
    expected = [here if p == "here" else p for p in route_after]
    assert r.take() == [("upload", len(expected)), ("read back",)]
    assert waypoints(r) == expected
    assert flat(r.held()) == pytest.approx(flat(expected), abs=1e-7)
    assert r.h.mission_state.legs.leg_index == leg_after
    assert r.h.feedback("Switch A: edit the route") == f"switch A DOWN, knob {knob:+d}: " + edit.format(here=f"{here[0]:.7f}, {here[1]:.7f}")


@pytest.mark.parametrize(
    ("trouble", "knob", "feedback"),
    [
        ("ekf", 0, "switch A DOWN, knob +0: add a waypoint here refused: the EKF has no position estimate"),
        ("old position", 0, "switch A DOWN, knob +0: add a waypoint here refused: the last position is 1.6 s old"),
        ("empty", 60, "switch A DOWN, knob +60: remove the current waypoint refused: the route is empty: no waypoint to remove"),
        ("no knob", None, "switch A DOWN: no knob VRA position: nothing done"),
    ],
)
def test_a_route_edit_that_cannot_be_done_changes_nothing_and_says_why(rover: ScriptedRover, trouble, knob, feedback) -> None:
    record(rover, ahead(5.0))
    if trouble == "empty":
        rover.rc(knob=-100, swa=DOWN)
        rover.tick()
        rover.rc(swa=UP)
        rover.tick()
    rover.take()
    before = waypoints(rover)
    rover.rc(knob=knob)
    if trouble == "ekf":
        rover.ekf = EKF_LOST
    if trouble == "old position":
        rover.position_age_s = 1.6  # GLOBAL_POSITION_INT stopped coming 1.6 s ago
    rover.tick()
    rover.rc(swa=DOWN)
    rover.tick()
    assert rover.take() == []
    assert waypoints(rover) == before
    assert rover.h.feedback("Switch A: edit the route") == feedback


def test_one_edit_per_flip_of_switch_a(rover: ScriptedRover) -> None:
    rover.rc(swa=DOWN)
    assert rover.run(30) == [Status.RUNNING] * 30  # held down: one waypoint
    rover.rc(swa=UP)
    assert rover.run(5) == [Status.RUNNING] * 5  # up: nothing
    assert waypoints(rover) == [START]
    rover.rc(swa=DOWN)
    rover.tick()
    assert waypoints(rover) == [START, START]
    assert rover.take() == [("upload", 1), ("read back",), ("upload", 2), ("read back",)]


def test_switch_a_does_nothing_while_switch_b_is_down(rover: ScriptedRover) -> None:
    rover.rc(swb=DOWN)
    rover.tick()
    rover.rc(swa=DOWN)
    rover.tick()
    assert rover.h.feedback("Switch A: edit the route") == "switch A DOWN: ignored while switch B is down"
    rover.rc(swb=UP)
    assert rover.run(5) == [Status.RUNNING] * 5  # switch B up again: still the same flip, still nothing
    assert waypoints(rover) == [] and rover.take() == []
    rover.rc(swa=UP)
    rover.tick()
    rover.rc(swa=DOWN)
    rover.tick()
    assert waypoints(rover) == [START]


def test_a_failed_upload_is_tried_again_later_and_auto_waits_for_it(rover: ScriptedRover) -> None:
    rover.answers_missions = False
    record(rover, ahead(10.0))
    n = rover.run_until(lambda: "upload failed" in rover.h.feedback("Keep the route on the autopilot"), limit=100)
    assert 90 <= n <= 97  # the count and 5 resends 1.5 s apart (checked at 10 Hz), then the transfer gives up
    assert rover.take() == [("upload", 1)] * 6
    assert rover.h.feedback("Keep the route on the autopilot") == "upload failed (no MISSION_REQUEST for item 0 after 5 retries); trying again in 5 s"
    rover.answers_missions = True
    rover.rc(swc=MIDDLE)
    assert rover.run(49) == [Status.RUNNING] * 49
    assert rover.take() == []  # no upload and no AUTO for 5 s
    rover.run_until(lambda: rover.mode == "AUTO", limit=3)
    assert rover.take() == [("upload", 1), ("read back",), ("mode", "AUTO")]


# -- driving the route ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("left_undone", "why"),
    [
        ("no route", "no route recorded (switch A down with the knob in the middle adds a waypoint here)"),
        ("no upload", "the route is not on the autopilot yet: the autopilot's mission differs (the vehicle holds 0 items, 1 were sent)"),
        ("MANUAL", "switch C to the middle (AUTO) drives the route; the mode is MANUAL"),
        ("disarmed", "the vehicle is disarmed (it arms in MANUAL only: switch C up, switch D down)"),
    ],
)
def test_the_operator_not_driving_the_route_in_time_fails_the_mission(rover: ScriptedRover, left_undone: str, why: str) -> None:
    rover.answers_missions = left_undone != "no upload"
    if left_undone != "no route":
        record(rover, ahead(10.0))  # 0.2 s of the 30 s are gone
    else:
        rover.run(2)
    if left_undone == "disarmed":
        rover.mode = "AUTO"
    statuses = rover.run(400)
    assert statuses == [Status.RUNNING] * 298 + [Status.FAILURE]
    assert rover.h.feedback("Drive the route in AUTO") == f"the operator did not drive the route within 30 s: {why}"


def test_leaving_auto_keeps_the_leg_restarts_the_wait_and_auto_resumes_there(rover: ScriptedRover) -> None:
    rover.armed = True
    record(rover, ahead(10.0), ahead(20.0), ahead(30.0))
    rover.rc(swc=MIDDLE)
    rover.run_until(lambda: rover.h.mission_state.legs.leg_index == 1)
    rover.rc(swc=UP)  # the operator takes the vehicle back for a while
    rover.tick()
    assert rover.mode == "MANUAL" and rover.h.mission_state.legs.leg_index == 1
    assert rover.run(290) == [Status.RUNNING] * 290  # 29 s: the wait restarted when the drive stopped
    rover.rc(swc=MIDDLE)
    rover.run_until(lambda: rover.h.mission_state.legs.leg_index == 2)
    assert rover.store.current_seq == 3
    assert rover.run(100)[-1] == Status.SUCCESS


def test_a_reached_report_from_before_the_run_does_not_count(rover: ScriptedRover, vehicle) -> None:
    rover.armed = True
    record(rover, ahead(10.0), ahead(20.0))
    vehicle.set(vehicle__mission_reached=MissionItemReached(2, 0.0, 2))  # left over from an earlier run
    rover.tick()
    rover.rc(swc=MIDDLE)
    rover.step_m = 0.5
    rover.run(3)
    assert rover.h.mission_state.legs.leg_index == 0
    assert rover.h.feedback("Drive the route in AUTO").startswith("waypoint 1/2: ")


def auto_asked(rover: ScriptedRover) -> None:
    """Two waypoints recorded ahead, the rover back at the start, armed, standing still in AUTO (step 0)."""
    rover.armed, rover.step_m = True, 0.0
    record(rover, ahead(10.0), ahead(20.0))
    rover.lat, rover.lon = START
    rover.rc(swc=MIDDLE)
    rover.tick()
    assert rover.mode == "AUTO"  # the rover is in AUTO; the executive sees it in the next tick


def test_an_item_reached_before_the_heartbeat_shows_auto_is_not_lost(rover: ScriptedRover, vehicle) -> None:
    """The defect: a MISSION_ITEM_REACHED drained in the tick the switch to AUTO shows was ignored (the drive 'started' after it)."""
    auto_asked(rover)
    vehicle.set(vehicle__mission_reached=MissionItemReached(1, rover.clock.now() + 0.05, 1))  # arrives between two ticks
    rover.tick()
    assert rover.h.mission_state.legs.leg_index == 1


def test_mission_current_complete_ends_the_drive(rover: ScriptedRover, vehicle) -> None:
    """The defect: MISSION_CURRENT mission_state 5 (the autopilot ran its mission to the end) was ignored."""
    auto_asked(rover)
    rover.tick()
    vehicle.set(vehicle__mission_current=MissionCurrent(2, 2, MISSION_STATE_COMPLETE, True, rover.clock.now() + 0.05))
    rover.tick()
    assert rover.h.mission_state.legs.leg_index == 2
    assert rover.run(3)[-1] == Status.SUCCESS  # held at the end
    assert rover.h.feedback("Drive the route in AUTO") == "route done: 2/2 waypoints reached"


def test_a_drive_in_auto_that_makes_no_progress_fails_within_the_leg_timeout(rover_for) -> None:
    """The defect: one run sat RUNNING at 0.0 m for 1,440 s; AUTO had no progress bound."""
    r = rover_for(mission_with(limits={"recovery_timeout_s": 10.0, "ekf_wait_s": 20.0, "leg_timeout_s": 5.0}))
    r.tick()
    auto_asked(r)
    statuses = r.run(100)
    assert statuses == [Status.RUNNING] * 51 + [Status.FAILURE]
    assert r.h.feedback("Drive the route in AUTO") == "no progress in AUTO: waypoint 1/2 not reached within 5 s: 10.0 m at 000°"


def test_a_route_of_one_place_recorded_by_a_vehicle_that_never_moved_does_not_complete(rover: ScriptedRover) -> None:
    """The defect: the operator's vehicle was held, all 4 route points were recorded at home, and the run ended COMPLETED."""
    rover.armed = True
    record(rover, START, START, START, START)
    rover.rc(swc=MIDDLE)
    statuses = rover.run(20)
    assert statuses[-1] == Status.FAILURE
    assert rover.h.feedback("Drive the route in AUTO") == (
        "the route's 4 waypoints are all one place (the vehicle never moved while they were recorded): nothing was driven"
    )


def test_removing_the_current_waypoint_while_driving_sends_the_rover_to_the_next(rover: ScriptedRover) -> None:
    rover.armed, rover.step_m = True, 0.5
    record(rover, ahead(10.0), ahead(20.0), ahead(30.0))
    rover.rc(swc=MIDDLE)
    rover.run_until(lambda: rover.h.mission_state.legs.leg_index == 1)
    rover.take()
    rover.rc(knob=80, swa=DOWN)
    rover.tick()
    assert rover.take() == [("upload", 2), ("read back",)]
    assert waypoints(rover) == [ahead(10.0), ahead(30.0)] and rover.h.mission_state.legs.leg_index == 1
    assert rover.run(100)[-1] == Status.SUCCESS  # the mission ends there
    assert (rover.lat, rover.lon) == pytest.approx(ahead(30.0), abs=1e-6)


# -- guards, pre-flight, pause -------------------------------------------------------------------


@pytest.mark.parametrize("trouble", ["rc stale", "link lost"])
def test_a_failed_guard_holds_the_vehicle_and_ends_the_mission_if_it_does_not_recover(rover: ScriptedRover, trouble: str) -> None:
    rover.armed, rover.step_m = True, 0.001
    record(rover, ahead(10.0))
    rover.lat, rover.lon = START  # 10 m to go
    rover.rc(swc=MIDDLE)
    rover.run(3)
    assert rover.mode == "AUTO"
    rover.take()
    if trouble == "rc stale":
        rover.rc_alive = False  # the receiver's report freezes (CAN: the base repeats the last frame)
        assert rover.run(10) == [Status.RUNNING] * 10  # fresh for rc.fresh_timeout_s (1 s)
        assert rover.take() == []
    else:
        rover.link_up = False
    rover.rc(swc=UP)  # unseen while RC is stale
    rover.tick()
    assert rover.take() == [("mode", "HOLD")]
    assert rover.h.feedback("Wait for guards").startswith("asking HOLD (0/10 s): ")  # until accepted and seen...
    rover.tick()
    assert rover.h.feedback("Wait for guards").startswith("in HOLD (0/10 s): ")  # ...then it is done: never asked again
    statuses = rover.run(200)
    assert statuses == [Status.RUNNING] * 99 + [Status.FAILURE]
    assert rover.take() == []


@pytest.mark.parametrize("trouble", ["rc stale", "link lost"])
def test_no_failsafe_takes_the_vehicle_from_the_operator_driving_in_manual(rover: ScriptedRover, trouble: str) -> None:
    """The defect: a 0.2 s RC gap at 20x put the vehicle in HOLD while the operator drove it in MANUAL (switch C up)."""
    record(rover, ahead(10.0))
    rover.take()
    assert rover.mode == "MANUAL"
    rover.mode_set_by = "others"  # MANUAL from the operator (the RC, or switch C up: asked for by us, a person's mode all the same)
    if trouble == "rc stale":
        rover.rc_alive = False
    else:
        rover.link_up = False
    assert rover.run(30) == [Status.RUNNING] * 30
    assert rover.take() == [] and rover.mode == "MANUAL"  # the autopilot's own RC failsafe answers an RC loss
    rover.rc_alive = rover.link_up = True
    assert rover.run(5) == [Status.RUNNING] * 5 and rover.take() == []


def test_switch_moves_wait_out_stale_rc_and_count_when_it_is_back(rover: ScriptedRover) -> None:
    record(rover, ahead(10.0))
    rover.take()
    rover.mode_set_by = "us"  # switch C up: MANUAL asked for at the operator's request
    rover.rc_alive = False
    rover.run(12)
    assert rover.take() == []  # in MANUAL: a person drives, nothing commanded
    assert rover.h.feedback("Wait for guards") == "hands off (0/10 s): RC fresh? no RC report within 1 s"
    rover.rc(swc=MIDDLE)
    assert rover.run(20) == [Status.RUNNING] * 20
    assert rover.take() == []
    rover.rc_alive = True
    assert rover.run(20) == [Status.RUNNING] * 20 and rover.take() == []  # the reports fresh for RcFresh's 2 s first
    rover.tick()
    assert rover.take() == [("mode", "AUTO")]  # the operator's latest wish, once it can be read


def test_the_switches_wait_for_the_ekf_and_the_mission_fails_without_one(rover_for) -> None:
    r = rover_for(mission_with())
    r.ekf = EKF_LOST
    r.rc(swd=DOWN)
    statuses = r.run(300)
    assert statuses == [Status.RUNNING] * 201 + [Status.FAILURE]  # limits.ekf_wait_s: 20 s
    assert r.take() == []  # no upload, no arming


def test_pause_holds_and_resume_puts_back_the_switchs_mode_and_redoes_nothing_else(rover: ScriptedRover) -> None:
    record(rover, ahead(10.0))
    rover.rc(swc=DOWN)
    rover.tick()
    rover.rc(swc=UP)
    rover.tick()
    rover.take()
    rover.h.mission_state.pause("operator: pause")
    assert rover.run(10) == [Status.RUNNING] * 10
    assert rover.take() == [("mode", "HOLD")]
    rover.h.mission_state.resume()
    assert rover.run(10) == [Status.RUNNING] * 10
    assert rover.take() == [("mode", "MANUAL")]  # switch C is still up: MANUAL again; the route is still on the rover: no upload
    assert waypoints(rover) == [ahead(10.0)]


# -- the mission file ----------------------------------------------------------------------------


def test_an_aux_mode_the_rover_lacks_is_refused_before_anything_runs() -> None:
    text = "version: 1\nname: m\nvehicle: rover\ntree: ugv_rc_route\nrc_route: {aux_mode: LOITR}\nwaypoints: []\n"
    with pytest.raises(MissionError) as refused:
        load_mission_text(text, "m.yaml")
    assert [str(e) for e in refused.value.errors] == [
        "m.yaml:5:22: rc_route.aux_mode: 'LOITR': not a rover mode (known: MANUAL, ACRO, STEERING, HOLD, LOITER, FOLLOW, SIMPLE, DOCK, CIRCLE, "
        "AUTO, RTL, SMART_RTL, GUIDED)"
    ]


def test_the_example_mission_shows_its_tree() -> None:
    text = py_trees.display.unicode_tree(mission_tree.build(load_mission(ROOT / "missions/ugv_rc_route.yaml")))
    for name in ("Switch A: edit the route", "Keep the route on the autopilot", "Switch C: mode", "Switch D: arm", "Drive the route in AUTO"):
        assert name in text


# -- end to end: the simulated Bunker and the scripted operator -----------------------------------


class Observer(FaultInjector):
    """Plays the operator's event file and watches the simulated vehicle: where it was at each flip of switch A,
    its mode and distance at each waypoint reached, and whether it was ever armed outside MANUAL."""

    def __init__(self, plan, clock, swa_channel: int) -> None:
        super().__init__(plan, clock)
        self.swa_channel = swa_channel
        self.flips: list[tuple[float, float]] = []
        self.reached: list[tuple[int, str, float]] = []
        self.armed_in: set[str] = set()
        self._swa = 0
        self._armed = False

    def attach(self, autopilot) -> None:
        super().attach(autopilot)
        store, advance = autopilot.mission, autopilot.mission.advance

        def reached():
            item = store.current
            self.reached.append((store.current_seq, autopilot.mode, autopilot.vehicle.distance_to(item.lat, item.lon)))
            return advance()

        store.advance = reached

    def update(self, autopilot) -> None:
        super().update(autopilot)
        swa = autopilot.rc_channels[self.swa_channel - 1]
        if swa > 1700 >= self._swa:
            self.flips.append((autopilot.vehicle.lat, autopilot.vehicle.lon))
        self._swa = swa
        if autopilot.armed and not self._armed:
            self.armed_in.add(autopilot.mode)
        self._armed = autopilot.armed


@pytest.fixture
def scenario(lockstep) -> tuple[Observer, Runtime, RunOutcome, Lockstep]:
    mission = load_mission(ROOT / "missions/ugv_rc_route.yaml")
    assert mission.simulator is not None and mission.simulator.events is not None and mission.home is not None
    observers: list[Observer] = []

    def observer(faults, clock) -> Observer:
        assert faults and all(isinstance(f, RcInput) for f in faults)  # the mission's operator script
        observers.append(Observer(faults, clock, mission.rc.switch_channels.swa))
        return observers[0]

    sim = lockstep(mission, model="bunker", mission_dir=ROOT / "missions", injector=observer)
    outcome = sim.run_to_end(limit_s=600)
    return observers[0], sim.runtime, outcome, sim


def test_scenario_the_operator_records_a_route_on_the_simulated_bunker_and_auto_drives_it(scenario) -> None:
    observer, runtime, outcome, sim = scenario
    assert str(outcome.status) == "COMPLETED", outcome.reason
    recorded = [(wp.lat, wp.lon) for wp in runtime.mission_state.legs.route.waypoints]
    assert len(recorded) == len(observer.flips) == 4
    # where the vehicle was at each flip of switch A (the operator stops to record: what the executive hears a few
    # reports later, RC_CHANNELS and GLOBAL_POSITION_INT at 5 Hz, is still that place)
    for (lat, lon), flip in zip(recorded, observer.flips, strict=True):
        assert geo.distance(lat, lon, *flip) < 0.1
    assert min(geo.distance(*a, *b) for a, b in itertools.pairwise(recorded)) > 5.0  # four distinct places
    assert flat((i.x, i.y) for i in runtime.link.mission_transfer.items) == pytest.approx(flat(recorded), abs=1e-7)  # read back
    store = sim.autopilot.mission
    assert flat((store.command(s).lat, store.command(s).lon) for s in range(1, store.count)) == pytest.approx(flat(recorded), abs=1e-7)
    assert [(seq, mode) for seq, mode, _ in observer.reached] == [(1, "AUTO"), (2, "AUTO"), (3, "AUTO"), (4, "AUTO")]
    # AR_WPNav: a corner is reached with the turn's mid point within WP_RADIUS (a fast waypoint), or stopped at within it (one the
    # Bunker pivots at), and so is the last (a stop); the old simulator's 0.3 m stop was its own physics
    radius = sim.autopilot.motion.radius_m
    assert all(d <= radius for _, _, d in observer.reached), observer.reached
    assert observer.armed_in == {"MANUAL"}  # switch D down in HOLD armed nothing
    assert runtime.mission_state.legs.leg_index == 4
    assert sim.autopilot.mode == "HOLD"
    assert sim.autopilot.elapsed_s < 180.0


def test_scenario_rc_gaps_while_the_operator_drives_in_manual_take_nothing_from_them(lockstep) -> None:
    """The defect (ugv_rc_route.yaml at 20x): a short RC gap fired the RC-loss failsafe, which put the vehicle in HOLD while the
    operator drove it in MANUAL; all 4 route points were recorded at home and the run ended COMPLETED. Two 0.6 s gaps while
    the operator drives: the vehicle stays in MANUAL, the route is four places, and it is driven."""
    mission = load_mission(ROOT / "missions/ugv_rc_route.yaml")
    gaps = [RcLoss(kind="rc_loss", at_s=20.5, for_s=0.6), RcLoss(kind="rc_loss", at_s=30.5, for_s=0.6)]
    sim = lockstep(mission, model="bunker", mission_dir=ROOT / "missions", events=gaps)
    modes: list[tuple[float, str]] = []
    sim.observers.append(lambda s: modes.append((s.autopilot.elapsed_s, s.autopilot.mode)))
    outcome = sim.run_to_end(limit_s=600)
    assert str(outcome.status) == "COMPLETED", outcome.reason
    assert {mode for t, mode in modes if 14.5 <= t < 48.5} == {"MANUAL"}  # armed in MANUAL at 14 s, AUTO at 49 s: never held
    recorded = [(wp.lat, wp.lon) for wp in sim.runtime.mission_state.legs.route.waypoints]
    assert len(recorded) == 4 and min(geo.distance(*a, *b) for a, b in itertools.pairwise(recorded)) > 5.0
