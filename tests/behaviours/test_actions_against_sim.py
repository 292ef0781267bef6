"""Vehicle-facing actions against the simulated firmware, at the message level and without sockets.

The executive's own commander, reader and stream set-up talk to a simulated ArduPilot (ArduPlane
QuadPlane, ArduSub, ArduRover boat) in process, on a manual clock: what the commander sends is
handled by ``autopilot.handle`` at once, and the replies and telemetry go back through a
MavlinkReader onto the blackboard. So TakeOff, VtolTransition, Land, ChangeDepth, ChangeAltitude,
ChangeSpeed, HoldFor and GoTo are proven against the firmware's behaviour (ArduPlane refuses
DO_VTOL_TRANSITION outside AUTO, takes only the altitude from a setpoint, disarms after landing...).
"""

from __future__ import annotations

from collections import deque

import py_trees
import pytest
from py_trees.common import Status

from executive.autopilot.selection import Autopilot
from executive.behaviours import (
    Arm,
    ChangeAltitude,
    ChangeDepth,
    ChangeSpeed,
    GoTo,
    HoldFor,
    Land,
    SetMode,
    TakeOff,
    VtolTransition,
)
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.reader import MavlinkReader
from executive.io.mavlink.streams import StreamRequester, rates_for
from executive.mission.lifecycle import MissionState
from executive.mission.model import VTOL_MIN_ACCEPTANCE_RADIUS_M, Mission
from executive.mission.port import MissionPort
from executive.sim import make_autopilot
from executive.sim.ardupilot.plane import LOITER_RADIUS_M
from executive.sim.physics.aircraft import QUADPLANE_LIMITS
from executive.world.clock import ManualClock
from executive.world.dialect import AUTOPILOT_COMPONENT, EXECUTIVE_COMPONENT, MAVLinkMessage, encoder, mavlink
from executive.world.geo import destination, distance
from executive.world.vehicles import PROFILES

HOME = (47.397742, 8.545594, 0.0)
EKF_READY_S = 5.0
R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE


class InProcessLink:
    """A Link to a simulated autopilot: a sent message is handled at once; replies and telemetry queue for the reader."""

    def __init__(self, autopilot) -> None:
        self.autopilot = autopilot
        self._ours = encoder(1, EXECUTIVE_COMPONENT)
        self._theirs = encoder(autopilot.system_id, AUTOPILOT_COMPONENT)
        self.incoming: deque[MAVLinkMessage] = deque()
        self.sent: list[MAVLinkMessage] = []

    def send(self, msg: MAVLinkMessage) -> None:
        msg.pack(self._ours)  # the header (our ids, a sequence number), as on the wire
        self.sent.append(msg)
        self._receive(self.autopilot.handle(msg))

    def recv(self) -> MAVLinkMessage | None:
        return self.incoming.popleft() if self.incoming else None

    def close(self) -> None:
        pass

    def update(self) -> None:
        self._receive(self.autopilot.update())

    def _receive(self, messages: list[MAVLinkMessage]) -> None:
        for msg in messages:
            msg.pack(self._theirs)
            self.incoming.append(msg)

    def commands(self) -> list[str]:
        """The MAV_CMD names sent so far (first sends and retries), oldest first."""
        names = []
        for msg in self.sent:
            if msg.get_type() in ("COMMAND_LONG", "COMMAND_INT") and msg.command != mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
                names.append(mavlink.enums["MAV_CMD"][msg.command].name.removeprefix("MAV_CMD_"))
        return names


class Bench:
    """The executive's IO around a simulated autopilot, ticked by hand at ``dt``: update, drain, tick, request streams, flush."""

    def __init__(self, kind: str, waypoints: list[dict], **options: float) -> None:
        self.clock = ManualClock()
        self.autopilot = make_autopilot(kind, self.clock, HOME, ekf_ready_after_s=EKF_READY_S, **options)
        self.link = InProcessLink(self.autopilot)
        self.commander = Commander(self.link, self.clock, PROFILES[kind])
        self.reader = MavlinkReader(self.link, self.clock, self.commander)
        self.port = Autopilot(self.commander, None, PROFILES[kind])
        self.reader.on_autopilot = self.port.adopt
        self.streams = StreamRequester(self.commander, rates_for(kind))
        self.reader.on_reconnect = self.streams.restart
        # a vtol flies its legs as a plane: the mission rules refuse a radius under its loiter circle
        limits = {"acceptance_radius_m": VTOL_MIN_ACCEPTANCE_RADIUS_M} if kind == "vtol" else {}
        mission = Mission.model_validate({"version": 1, "name": "bench", "vehicle": kind, "limits": limits, "waypoints": waypoints})
        self.mission_state = MissionState()
        self.mission_state.upload(mission)
        self.mission_state.start()
        self.tree: py_trees.trees.BehaviourTree | None = None
        self.step(EKF_READY_S + 2.0)  # boot, EKF origin, streams set up

    def step(self, seconds: float, dt: float = 0.1) -> None:
        """Let time pass with the IO running and no tree."""
        for _ in range(round(seconds / dt)):
            self._io(dt)
            self.streams.service()
            self.commander.flush()

    def run(self, root: py_trees.behaviour.Behaviour, limit_s: float, dt: float = 0.1) -> tuple[Status, float]:
        """Tick ``root`` until it finishes or ``limit_s`` passes; returns its status and the time it took."""
        self.tree = py_trees.trees.BehaviourTree(root)
        self.tree.setup(clock=self.clock, autopilot=self.port, mission_state=MissionPort(self.mission_state))
        start = self.clock.now()
        while self.clock.now() - start < limit_s:
            self._io(dt)
            self.tree.tick()
            self.streams.service()
            self.commander.flush()
            if root.status != R:
                break
        return root.status, self.clock.now() - start

    def bb(self, key: str):
        return py_trees.blackboard.Blackboard.get(key)

    def _io(self, dt: float) -> None:
        self.clock.advance(dt)
        self.link.update()
        self.reader.drain()


VTOL_ROUTE = [{"lat": destination(HOME[0], HOME[1], 0.0, 600.0)[0], "lon": HOME[1], "alt_m": 30.0}]


def airborne(alt_m: float = 30.0) -> Bench:
    bench = Bench("vtol", VTOL_ROUTE)
    status, _ = bench.run(py_trees.composites.Sequence("Up", memory=True, children=[SetMode("GUIDED"), Arm(), TakeOff(alt_m)]), 60.0)
    assert status == S
    return bench


class TestVtol:
    def test_takeoff_in_guided_armed_climbs_and_hovers(self):
        bench = Bench("vtol", VTOL_ROUTE)
        takeoff = TakeOff(30.0)
        status, took = bench.run(py_trees.composites.Sequence("Up", memory=True, children=[SetMode("GUIDED"), Arm(), takeoff]), 60.0)
        assert status == S
        assert bench.link.commands() == ["DO_SET_MODE", "COMPONENT_ARM_DISARM", "NAV_TAKEOFF"]
        assert (bench.bb("/vehicle/landed_state"), bench.bb("/vehicle/vtol_state")) == ("IN_AIR", "MC")
        assert bench.autopilot.vehicle.alt_m >= 0.95 * 30.0
        assert took >= 30.0 / QUADPLANE_LIMITS.climb_m_s  # no faster than Q_WP_SPEED_UP allows

    def test_takeoff_unarmed_is_refused_by_arduplane(self):
        bench = Bench("vtol", VTOL_ROUTE)
        takeoff = TakeOff(30.0)
        status, took = bench.run(py_trees.composites.Sequence("Up", memory=True, children=[SetMode("GUIDED"), takeoff]), 10.0)
        assert status == F and took < 1.0
        assert takeoff.feedback_message == "refused: FAILED (Must be armed for takeoff)"
        assert bench.autopilot.vehicle.alt_m == 0.0

    def test_transition_to_fw_by_reposition_and_back_to_mc_by_qloiter(self):
        bench = airborne()
        seen: list[str] = []
        to_fw = VtolTransition("FW")
        status, took = _run_watching(bench, to_fw, 40.0, seen)
        assert status == S, to_fw.feedback_message
        assert seen[0] == "MC" and "TRANSITION_TO_FW" in seen and seen[-1] == "FW"
        assert took > 5.0  # the airspeed wait and Q_TRANSITION_MS: an ack alone proves nothing
        assert "DO_VTOL_TRANSITION" not in bench.link.commands()  # ArduPlane would refuse it outside AUTO
        assert bench.link.commands()[-1] == "DO_REPOSITION" and bench.autopilot.mode == "GUIDED"
        to_mc = VtolTransition("MC")
        status, took = bench.run(to_mc, 10.0)
        assert status == S and bench.autopilot.mode == "QLOITER" and bench.bb("/vehicle/vtol_state") == "MC"
        assert to_mc.feedback_message == "MC (by QLOITER)"

    def test_goto_by_reposition_reaches_the_loiter_circle_in_fixed_wing_flight(self):
        bench = airborne()
        assert bench.run(VtolTransition("FW"), 40.0)[0] == S
        goto = GoTo(LOITER_RADIUS_M + 20.0, 120.0, method="reposition")
        status, _ = bench.run(goto, 120.0)
        assert status == S, goto.feedback_message
        target = bench.mission_state.legs.target
        assert distance(bench.autopilot.vehicle.lat, bench.autopilot.vehicle.lon, target.lat, target.lon) <= LOITER_RADIUS_M + 20.0
        assert bench.link.commands().count("DO_REPOSITION") == 2  # the transition's and the leg's: never re-sent once accepted
        assert bench.bb("/vehicle/vtol_state") == "FW" and bench.autopilot.vehicle.alt_m == pytest.approx(30.0, abs=1.0)

    def test_land_in_qland_until_on_the_ground_and_disarmed(self):
        bench = airborne(10.0)
        land = Land()
        status, took = bench.run(land, 60.0)
        assert status == S, land.feedback_message
        assert not bench.autopilot.armed and bench.autopilot.vehicle.on_ground and bench.autopilot.mode == "QLAND"
        assert took >= 4.0 + 6.0 / QUADPLANE_LIMITS.land_final_m_s  # the slow final descent and the 4 s land detector

    def test_a_transition_timeout_reports_the_last_state(self):
        bench = airborne()
        to_fw = VtolTransition("FW", timeout_s=2.0)
        status, _ = bench.run(to_fw, 10.0)
        assert status == F
        assert to_fw.feedback_message == "still TRANSITION_TO_FW after 2 s (by reposition 300 m ahead)"


def _run_watching(bench: Bench, root, limit_s: float, seen: list[str]) -> tuple[Status, float]:
    """As Bench.run, noting each new /vehicle/vtol_state."""
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(clock=bench.clock, autopilot=bench.port, mission_state=MissionPort(bench.mission_state))
    start = bench.clock.now()
    while bench.clock.now() - start < limit_s:
        bench._io(0.1)
        state = bench.bb("/vehicle/vtol_state")
        if not seen or seen[-1] != state:
            seen.append(state)
        tree.tick()
        bench.streams.service()
        bench.commander.flush()
        if root.status != R:
            break
    return root.status, bench.clock.now() - start


SUB_ROUTE = [
    {"lat": destination(HOME[0], HOME[1], 0.0, 20.0)[0], "lon": HOME[1], "depth_m": 10.0, "control_mode": "depth", "speed_m_s": 0.5},
    {"lat": HOME[0], "lon": HOME[1], "altitude_m": 5.0, "control_mode": "altitude"},
]


def submerged_bench(mode: str) -> Bench:
    bench = Bench("sub", SUB_ROUTE)
    assert bench.run(py_trees.composites.Sequence("Ready", memory=True, children=[SetMode(mode), Arm()]), 10.0)[0] == S
    return bench


class TestSub:
    @pytest.mark.parametrize("mode", ["ALT_HOLD", "GUIDED"])
    def test_change_depth(self, mode):
        bench = submerged_bench(mode)
        change = ChangeDepth()
        status, took = bench.run(change, 120.0)
        assert status == S, change.feedback_message
        assert bench.autopilot.vehicle.depth_m == pytest.approx(10.0, abs=0.5)
        assert took >= 10.0 / 0.5  # the sub descends at 0.5 m/s at most
        assert bench.autopilot.vehicle.distance_to(*HOME[:2]) < 1.0  # held where it was, not off to the waypoint
        bench.step(20.0)
        assert bench.autopilot.vehicle.depth_m == pytest.approx(10.0, abs=0.1)  # the target stays with the autopilot

    def test_change_altitude_in_guided_follows_the_seabed(self):
        bench = submerged_bench("GUIDED")
        bench.mission_state.advance_leg()
        change = ChangeAltitude()
        status, _ = bench.run(change, 150.0)
        assert status == S, change.feedback_message
        assert bench.autopilot.vehicle.altitude_m == pytest.approx(5.0, abs=0.5)
        assert bench.autopilot.vehicle.depth_m == pytest.approx(bench.autopilot.vehicle.seabed_depth_m - 5.0, abs=0.5)

    @pytest.mark.parametrize("mode", ["GUIDED", "ALT_HOLD"])
    def test_change_altitude_over_a_seabed_beyond_the_rangefinder(self, mode):
        """ArduSub's SITL: the seabed 50 m down, the sonar to 30 m. The sub dives without a reading until the sonar reads the seabed,
        then holds 5 m above it, with depth targets only (ArduSub drops terrain-frame ones)."""
        bench = Bench("sub", SUB_ROUTE, seabed_depth_m=50.0)
        assert bench.run(py_trees.composites.Sequence("Ready", memory=True, children=[SetMode(mode), Arm()]), 10.0)[0] == S
        bench.mission_state.advance_leg()
        change = ChangeAltitude()
        status, _ = bench.run(change, 200.0)
        assert status == S, change.feedback_message
        assert bench.autopilot.vehicle.altitude_m == pytest.approx(5.0, abs=0.6)  # within the action's 0.5 m, as last reported
        bench.step(20.0)
        assert bench.autopilot.vehicle.altitude_m == pytest.approx(5.0, abs=0.1)  # the last depth target was the right one
        frames = {m.coordinate_frame for m in bench.link.sent if m.get_type() == "SET_POSITION_TARGET_GLOBAL_INT"}
        assert frames == {mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}

    def test_change_speed_then_goto_at_depth(self):
        bench = submerged_bench("GUIDED")
        assert bench.run(py_trees.composites.Sequence("Dive", memory=True, children=[ChangeSpeed(), ChangeDepth()]), 120.0)[0] == S
        goto = GoTo(1.0, 180.0)
        status, took = bench.run(goto, 180.0)
        assert status == S, goto.feedback_message
        assert took >= 19.0 / 0.5  # 20 m at the leg's 0.5 m/s (the sub cruises at 0.8 m/s unless told)
        assert bench.autopilot.vehicle.depth_m == pytest.approx(10.0, abs=0.5)  # the leg's setpoints keep the depth


class TestBoat:
    def test_hold_for_in_loiter(self):
        bench = Bench("boat", [{"lat": HOME[0], "lon": HOME[1]}])
        hold = HoldFor(5.0, "LOITER")
        status, took = bench.run(hold, 20.0)
        assert status == S, hold.feedback_message
        assert bench.autopilot.mode == "LOITER"
        assert 5.0 <= took <= 5.5  # from the heartbeat showing LOITER, which ArduPilot sends at once
