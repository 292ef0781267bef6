"""Mission efficiency: the executive's GUIDED legs against the autopilot's own AUTO on the same waypoints.

In process, lock-step on a manual clock (deterministic): the example missions ``rover_square`` and
``boat_survey`` on their simulated vehicle, from the mission's home.

- GUIDED: the executive runs the mission (its ``waypoints`` tree, its own tick loop, on
  :class:`executive.testing.Lockstep`); timed from the autopilot entering
  GUIDED to the vehicle within the mission's acceptance radius of the last waypoint.
- AUTO: the same waypoints uploaded as a mission (NAV_WAYPOINTs, as a ground station would), the
  vehicle armed and put in AUTO; timed from entering AUTO to the same point.

Both run at the vehicle's default speed (no waypoint sets one). The row is GUIDED time / AUTO time.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from benchmarks.common import Row
from executive.clock import ManualClock
from executive.io.mavlink.dialect import EXECUTIVE_COMPONENT, encoder, mavlink
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from executive.sim import ArduPilotSim, make_autopilot
from executive.sim.options import simulated_home
from executive.testing import Lockstep

MISSIONS = Path(__file__).resolve().parent.parent / "missions"
TARGET_RATIO = 1.10
RATE_HZ = 10.0
EKF_READY_S = 2.0
LIMIT_S = 600.0


@dataclass(frozen=True)
class Timing:
    """One run: vehicle time from entering the driving mode to the last waypoint."""

    mode: str
    seconds: float


class _Route:
    """Follows the vehicle along the waypoints: an intermediate one counts as passed within ``PASS_M`` (a corner may be cut),
    the last one within the mission's acceptance radius."""

    PASS_M = 5.0

    def __init__(self, mission: Mission) -> None:
        self.points = [(w.lat, w.lon) for w in mission.waypoints]
        self.radius_m = mission.limits.acceptance_radius_m
        self.next = 0

    def done(self, ap: ArduPilotSim) -> bool:
        """Whether the vehicle is at the last waypoint, having passed the others in turn."""
        last = len(self.points) - 1
        while self.next <= last and ap.vehicle.distance_to(*self.points[self.next]) <= (self.radius_m if self.next == last else self.PASS_M):
            self.next += 1
        return self.next > last


class _Stopwatch:
    """Vehicle time from the autopilot first being armed in ``mode`` to the vehicle at the last waypoint."""

    def __init__(self, mission: Mission, mode: str) -> None:
        self.mission = mission
        self.mode = mode
        self.route = _Route(mission)
        self.entered: float | None = None
        self.seconds: float | None = None

    def observe(self, now: float, ap: ArduPilotSim) -> bool:
        """Look at the vehicle now; True once it is at the last waypoint."""
        if self.entered is None and ap.mode == self.mode and ap.armed:
            self.entered = now
        if self.entered is not None and self.seconds is None and self.route.done(ap):
            self.seconds = now - self.entered
        return self.seconds is not None

    def timing(self) -> Timing:
        if self.seconds is None:
            raise RuntimeError(f"{self.mission.name}: {self.mode} did not reach the last waypoint within {LIMIT_S:g} s")
        return Timing(self.mode, self.seconds)


def time_guided(mission: Mission, rate_hz: float = RATE_HZ) -> Timing:
    """The executive drives the mission in GUIDED (its tree, its own tick loop) on the lock-step simulation."""
    with Lockstep(mission, ekf_ready_after_s=EKF_READY_S, rate_hz=rate_hz) as sim:
        watch = _Stopwatch(mission, "GUIDED")
        sim.run(LIMIT_S, until=lambda: watch.observe(sim.clock.now(), sim.autopilot))
    return watch.timing()


def time_auto(mission: Mission, period_s: float = 1.0 / RATE_HZ) -> Timing:
    """The autopilot drives the same waypoints as its own AUTO mission."""
    clock = ManualClock(0.0)
    ap = make_autopilot(mission.vehicle, clock, simulated_home(mission), ekf_ready_after_s=EKF_READY_S)
    mav = encoder(1, EXECUTIVE_COMPONENT)

    def send(msg: mavlink.MAVLink_message) -> list[mavlink.MAVLink_message]:
        msg.pack(mav)
        return ap.handle(msg)

    def step() -> None:
        clock.advance(period_s)
        ap.update()

    while not ap.ekf_ready:
        step()
    points = [(mission.waypoints[0].lat, mission.waypoints[0].lon), *((w.lat, w.lon) for w in mission.waypoints)]  # item 0: home
    send(mav.mission_count_encode(1, 1, len(points), 0))
    for seq, (lat, lon) in enumerate(points):
        frame = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        send(mav.mission_item_int_encode(1, 1, seq, frame, mavlink.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), 0, 0))
    if ap.mission.count != len(points):
        raise RuntimeError(f"{mission.name}: the AUTO mission was not taken ({ap.mission.count} of {len(points)} items)")
    command = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
    send(mav.command_long_encode(1, 1, command, 0, 1, 0, 0, 0, 0, 0, 0))
    send(mav.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, ap.profile.modes["AUTO"], 0, 0, 0, 0, 0))
    watch = _Stopwatch(mission, "AUTO")
    deadline = clock.now() + LIMIT_S
    while not watch.observe(clock.now(), ap) and clock.now() < deadline:
        step()
    return watch.timing()


def ratio_row(name: str) -> Row:
    """The row for one example mission: GUIDED / AUTO vehicle time to its last waypoint."""
    mission = load_mission(MISSIONS / f"{name}.yaml")
    guided, auto = time_guided(mission), time_auto(mission)
    ratio = guided.seconds / auto.seconds
    return Row(
        "efficiency",
        f"GUIDED / AUTO time, {name} ({mission.vehicle})",
        round(ratio, 3),
        "x",
        f"<= {TARGET_RATIO:.2f}x",
        ratio <= TARGET_RATIO,
        f"GUIDED {guided.seconds:.1f} s, AUTO {auto.seconds:.1f} s (vehicle time, lock-step at {RATE_HZ:g} Hz)",
        {"guided_s": round(guided.seconds, 2), "auto_s": round(auto.seconds, 2)},
    )


def run(missions: tuple[str, ...] = ("rover_square", "boat_survey")) -> list[Row]:
    """One row per example mission."""
    return [ratio_row(name) for name in missions]
