"""Mission efficiency: the executive's GUIDED legs against the autopilot's own AUTO on the same waypoints.

In process, lock-step on a manual clock (deterministic): the example missions ``rover_square`` and
``boat_survey`` on their simulated vehicle, from the mission's home, with the parameters ArduPilot's
SITL starts that frame with (:data:`executive.sim.ardupilot.rover.SITL_PARAMS`: WP_SPEED 5, WP_RADIUS 3), so
the figures stand beside the real firmware's (:mod:`benchmarks.recorded`).

- GUIDED: the executive runs the mission (its ``waypoints`` tree, its own tick loop, on
  :class:`executive.testing.Lockstep`); timed from the autopilot entering
  GUIDED to the vehicle within the mission's acceptance radius of the last waypoint.
- AUTO: the same waypoints uploaded as a mission (NAV_WAYPOINTs, as a ground station would), the
  vehicle armed and put in AUTO; timed from entering AUTO to the same point.

- drive: auto: the executive runs the mission with ``drive: auto`` (the autopilot's AUTO drives, holding
  only the horizon, ``limits.auto_horizon_legs``, default 3); timed from the vehicle armed in AUTO, as AUTO.

The row is GUIDED (or drive: auto) time / AUTO time, and says what AUTO it compared against: the simulated
ArduRover's (here), or a recorded run of the real firmware (:mod:`benchmarks.recorded`). Its detail
gives, per corner (each intermediate waypoint), the largest distance of the vehicle from the route
there in each mode: the look-ahead is meant to cut no corner more than AUTO does.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks import recorded
from benchmarks.common import Row
from executive.io.mavlink.modes import ModeTable, mode_table
from executive.mission.loader import load_mission
from executive.mission.model import Mission, SimulatorOptions
from executive.sim import FirmwareSim, make_autopilot
from executive.sim.ardupilot.rover import SITL_PARAMS
from executive.sim.options import firmware_options, simulated_home
from executive.sim.px4.parameters import MISSION_CHECK_S
from executive.testing import Lockstep
from executive.world.clock import ManualClock
from executive.world.dialect import EXECUTIVE_COMPONENT, encoder, mavlink
from executive.world.geo import distance, distance_bearing
from executive.world.vehicles import PROFILES

MISSIONS = Path(__file__).resolve().parent.parent / "missions"
TARGET_RATIO = 1.10
#: drive: auto against the whole route in AUTO (issue 32).
AUTO_TARGET_RATIO = 1.02
RATE_HZ = 10.0
EKF_READY_S = 2.0
LIMIT_S = 600.0
#: What the simulated AUTO is: named in the row, so a figure is never taken for the real firmware's.
AGAINST_SIMULATOR = "our simulated ArduRover's AUTO (SITL's parameters)"
AGAINST_PX4_SIMULATOR = "our simulated PX4's AUTO.MISSION (standard VTOL, as a multicopter)"
#: Why a PX4 vtol's GUIDED (OFFBOARD) time is no pass/fail against AUTO.MISSION's (tests/data/px4/README.md): the path differs
#: (each GUIDED leg ends short), and the real OFFBOARD flew faster than AUTO.MISSION's MPC_XY_CRUISE (5 m/s).
PX4_GUIDED_CAVEAT = "a vtol's acceptance radius (70 m, its minimum) ends each GUIDED leg that far short of its waypoint"

Point = tuple[float, float]


@dataclass(frozen=True)
class Timing:
    """One run: vehicle time from entering the driving mode to the last waypoint, and the track meanwhile
    ((seconds since the mode was entered, lat, lon))."""

    mode: str
    seconds: float
    track: tuple[tuple[float, float, float], ...] = field(default=(), repr=False)


def with_sitl_parameters(mission: Mission) -> Mission:
    """The mission with its simulated vehicle set as ArduPilot's SITL starts that frame (the mission's own parameters on top)."""
    options = mission.simulator or SimulatorOptions()
    params = {**SITL_PARAMS.get(options.model or mission.vehicle, {}), **options.params}
    return mission.model_copy(update={"simulator": options.model_copy(update={"params": params})})


def route_of(mission: Mission) -> list[Point]:
    """The route as driven: the vehicle's start (the mission's home), then the waypoints."""
    home = simulated_home(mission)
    return [(home[0], home[1]), *((w.lat, w.lon) for w in mission.waypoints)]


def _to_local(origin: Point, point: Point) -> tuple[float, float]:
    distance, bearing = distance_bearing(origin[0], origin[1], point[0], point[1])
    return distance * math.cos(math.radians(bearing)), distance * math.sin(math.radians(bearing))


def _segment_distance(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def corner_cuts(track: Sequence[tuple[float, ...]], route: Sequence[Point]) -> list[float]:
    """Per intermediate waypoint: the largest distance from the route of the track points near it (nearer it than half
    of either leg through it), metres. Track points end in (lat, lon)."""
    if len(route) < 3:
        return []
    origin = route[0]
    local = [_to_local(origin, p) for p in route]
    points = [_to_local(origin, (p[-2], p[-1])) for p in track]
    cuts = []
    for k in range(1, len(local) - 1):
        before, corner, after = local[k - 1], local[k], local[k + 1]
        reach = min(math.dist(before, corner), math.dist(corner, after)) / 2.0
        near = [p for p in points if math.dist(p, corner) <= reach]
        cuts.append(max((min(_segment_distance(p, before, corner), _segment_distance(p, corner, after)) for p in near), default=math.nan))
    return cuts


def pass_radius_m(mission: Mission) -> float:
    """Within what an intermediate waypoint counts as passed: 5 m (a corner may be cut), or on PX4 the mission's acceptance radius
    (a vtol's is 70 m at least: GUIDED legs end that far short, and AUTO.MISSION's items are reached within NAV_ACC_RAD, 10 m)."""
    return mission.limits.acceptance_radius_m if mission.autopilot == "px4" else recorded.PASS_M


def mode_names(mission: Mission) -> ModeTable:
    """The mission's firmware's modes (``GUIDED`` is PX4's ``OFFBOARD``, ``AUTO`` its ``AUTO.MISSION``)."""
    firmware = mavlink.MAV_AUTOPILOT_PX4 if mission.autopilot == "px4" else mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
    return mode_table(firmware, PROFILES[mission.vehicle].mav_type)


class _Route:
    """Follows the vehicle along the waypoints: an intermediate one counts as passed within :func:`pass_radius_m`, the last one
    within the mission's acceptance radius."""

    def __init__(self, mission: Mission) -> None:
        self.points = [(w.lat, w.lon) for w in mission.waypoints]
        self.radius_m = mission.limits.acceptance_radius_m
        self.pass_m = pass_radius_m(mission)
        self.next = 0

    def done(self, ap: FirmwareSim) -> bool:
        """Whether the vehicle is at the last waypoint, having passed the others in turn."""
        last = len(self.points) - 1
        while self.next <= last and ap.vehicle.distance_to(*self.points[self.next]) <= (self.radius_m if self.next == last else self.pass_m):
            self.next += 1
        return self.next > last


class _Stopwatch:
    """Vehicle time from the autopilot first being armed in ``mode`` to the vehicle at the last waypoint; the track meanwhile."""

    def __init__(self, mission: Mission, mode: str) -> None:
        self.mission = mission
        self.mode = mode_names(mission).canonical(mode)
        self.route = _Route(mission)
        self.entered: float | None = None
        self.seconds: float | None = None
        self.track: list[tuple[float, float, float]] = []

    def observe(self, now: float, ap: FirmwareSim) -> bool:
        """Look at the vehicle now; True once it is at the last waypoint."""
        if self.entered is None and ap.mode == self.mode and ap.armed:
            self.entered = now
        if self.entered is not None and self.seconds is None:
            self.track.append((now - self.entered, ap.vehicle.lat, ap.vehicle.lon))
            if self.route.done(ap):
                self.seconds = now - self.entered
        return self.seconds is not None

    def timing(self) -> Timing:
        if self.seconds is None:
            raise RuntimeError(f"{self.mission.name}: {self.mode} did not reach the last waypoint within {LIMIT_S:g} s")
        return Timing(self.mode, self.seconds, tuple(self.track))


def time_guided(mission: Mission, rate_hz: float = RATE_HZ) -> Timing:
    """The executive drives the mission in GUIDED (its tree, its own tick loop) on the lock-step simulation."""
    return time_executive(mission.model_copy(update={"drive": "guided"}), rate_hz)


def time_supervised_auto(mission: Mission, rate_hz: float = RATE_HZ) -> Timing:
    """The executive runs the mission with ``drive: auto``: the autopilot's AUTO drives it, holding only the horizon."""
    return time_executive(mission.model_copy(update={"drive": "auto"}), rate_hz)


def time_executive(mission: Mission, rate_hz: float = RATE_HZ) -> Timing:
    """The executive runs the mission as its ``drive:`` says (its tree, its own tick loop) on the lock-step simulation;
    timed from the vehicle armed in the driving mode (GUIDED, or AUTO)."""
    with Lockstep(mission, ekf_ready_after_s=EKF_READY_S, rate_hz=rate_hz, autopilot=mission.autopilot or "ardupilot") as sim:
        watch = _Stopwatch(mission, "AUTO" if mission.drive == "auto" else "GUIDED")
        sim.run(LIMIT_S, until=lambda: watch.observe(sim.clock.now(), sim.autopilot))
    return watch.timing()


def time_auto(mission: Mission, period_s: float = 1.0 / RATE_HZ) -> Timing:
    """The autopilot drives the same waypoints as its own AUTO mission."""
    clock = ManualClock(0.0)
    options = firmware_options(mission)
    if mission.autopilot == "px4":
        options = {k: v for k, v in options.items() if k == "params"}  # the rest are ArduPilot's (as Lockstep's)
    firmware = mission.autopilot or "ardupilot"
    ap = make_autopilot(mission.vehicle, clock, simulated_home(mission), autopilot=firmware, ekf_ready_after_s=EKF_READY_S, **options)
    mav = encoder(1, EXECUTIVE_COMPONENT)

    def send(msg: mavlink.MAVLink_message) -> list[mavlink.MAVLink_message]:
        msg.pack(mav)
        return ap.handle(msg)

    def step() -> None:
        clock.advance(period_s)
        ap.update()

    while not ap.ekf_ready:
        step()
    points = [(w.lat, w.lon, w.alt_m) for w in mission.waypoints]
    if mission.autopilot != "px4":
        points.insert(0, points[0])  # ArduPilot's item 0: home (PX4 keeps home apart)
    system = ap.system_id
    send(mav.mission_count_encode(system, 1, len(points), 0))
    for seq, (lat, lon, alt) in enumerate(points):
        frame = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        item = (seq, frame, mavlink.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), alt, 0)
        send(mav.mission_item_int_encode(system, 1, *item))
    if ap.mission.count != len(points):
        raise RuntimeError(f"{mission.name}: the AUTO mission was not taken ({ap.mission.count} of {len(points)} items)")
    if mission.autopilot == "px4":
        for _ in range(round(MISSION_CHECK_S / period_s)):  # PX4 refuses AUTO.MISSION while it checks an upload
            step()
    command = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
    send(mav.command_long_encode(system, 1, command, 0, 1, 0, 0, 0, 0, 0, 0))
    main, sub = mode_names(mission).encode("AUTO")
    send(mav.command_long_encode(system, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, main, sub, 0, 0, 0, 0))
    watch = _Stopwatch(mission, "AUTO")
    deadline = clock.now() + LIMIT_S
    while not watch.observe(clock.now(), ap) and clock.now() < deadline:
        step()
    return watch.timing()


def px4_guided_caveat(guided: Timing, auto: Timing) -> str:
    """Why the two runs are not like for like, with their figures: the path flown and the peak speed (over 1 s) of each."""
    return (
        f"{PX4_GUIDED_CAVEAT}: GUIDED flew {_path_m(guided.track):.0f} m at up to {_peak_m_s(guided.track):.1f} m/s, AUTO "
        f"{_path_m(auto.track):.0f} m at up to {_peak_m_s(auto.track):.1f} m/s"
    )


def _path_m(track: Sequence[tuple[float, float, float]]) -> float:
    return sum(distance(a[1], a[2], b[1], b[2]) for a, b in itertools.pairwise(track))


def _peak_m_s(track: Sequence[tuple[float, float, float]], window_s: float = 1.0) -> float:
    peak, start = 0.0, 0
    for end in range(len(track)):
        while track[end][0] - track[start][0] > window_s:
            start += 1
        if track[end][0] - track[start][0] >= window_s / 2:
            peak = max(peak, _path_m(track[start : end + 1]) / (track[end][0] - track[start][0]))
    return peak


def _cuts(cuts: Sequence[float]) -> str:
    """Each corner's cut; ``-`` where the track never came within half a leg of the corner (a leg ended short of it)."""
    return "/".join("-" if math.isnan(c) else f"{c:.1f}" for c in cuts)


def _rounded(cuts: Sequence[float]) -> list[float | None]:
    return [None if math.isnan(c) else round(c, 2) for c in cuts]


def ratio_row(
    name: str, driven: Timing, auto: Timing, route: Sequence[Point], against: str, vehicle: str, drive: str = "guided", caveat: str = ""
) -> Row:
    """The row for one mission: the executive's time to its last waypoint (GUIDED legs, or ``drive: auto``) / AUTO's, what AUTO
    it was, the corners cut in each. With a ``caveat`` (why the two are not like for like) the figure is information, no pass/fail."""
    label, target = ("GUIDED", TARGET_RATIO) if drive == "guided" else ("drive: auto", AUTO_TARGET_RATIO)
    ratio = driven.seconds / auto.seconds
    driven_cuts, auto_cuts = corner_cuts(driven.track, route), corner_cuts(auto.track, route)
    wider = sum(g > a + 0.05 for g, a in zip(driven_cuts, auto_cuts, strict=True))
    return Row(
        "efficiency",
        f"{label} / AUTO time, {name} ({vehicle}), against {against}",
        round(ratio, 3),
        "x",
        "" if caveat else f"<= {target:.2f}x",
        None if caveat else ratio <= target,
        (f"information, not like for like: {caveat}; " if caveat else "")
        + f"{label} {driven.seconds:.1f} s, AUTO {auto.seconds:.1f} s; farthest from the route per corner (m): {label} {_cuts(driven_cuts)}, "
        f"AUTO {_cuts(auto_cuts)}; {wider} corner(s) cut over 5 cm more than AUTO",
        {
            "drive": drive, "driven_s": round(driven.seconds, 2), "auto_s": round(auto.seconds, 2), "against": against,
            "driven_cuts_m": _rounded(driven_cuts), "auto_cuts_m": _rounded(auto_cuts),
        },
    )  # fmt: skip


def simulated_rows(name: str) -> list[Row]:
    """One example mission on our simulator, SITL's parameters: GUIDED, ``drive: auto`` (the mission's horizon), and AUTO."""
    mission = with_sitl_parameters(load_mission(MISSIONS / f"{name}.yaml"))
    auto = time_auto(mission)
    return [
        ratio_row(name, time_guided(mission), auto, route_of(mission), AGAINST_SIMULATOR, mission.vehicle),
        ratio_row(name, time_supervised_auto(mission), auto, route_of(mission), AGAINST_SIMULATOR, mission.vehicle, "auto"),
    ]


def px4_simulated_rows(legs: int | None = None) -> list[Row]:
    """The PX4 vtol's route of the recordings (its first ``legs`` waypoints, or all) on our simulated PX4 standard VTOL: ``drive: auto``
    against the simulated AUTO.MISSION over the whole route (pass/fail), GUIDED (OFFBOARD) as information."""
    mission = load_mission(recorded.PX4_MISSION)
    if legs is not None:
        mission = mission.model_copy(update={"waypoints": mission.waypoints[:legs]})
    auto, guided, route = time_auto(mission), time_guided(mission), route_of(mission)
    caveat = px4_guided_caveat(guided, auto)
    return [
        ratio_row(mission.name, time_supervised_auto(mission), auto, route, AGAINST_PX4_SIMULATOR, "vtol, PX4", "auto"),
        ratio_row(mission.name, guided, auto, route, AGAINST_PX4_SIMULATOR, "vtol, PX4", "guided", caveat),
    ]


def run(missions: tuple[str, ...] = ("rover_square", "boat_survey"), px4_legs: int | None = None) -> list[Row]:
    """Per example mission on our simulator, both drives; the same per mission recorded on the real firmware, if any; then the
    PX4 vtol's route on our simulated PX4 (its first ``px4_legs`` waypoints, or all; 0: none) and as recorded on the real PX4."""
    rows = [row for name in missions for row in simulated_rows(name)] + recorded_rows(missions)
    return rows + (px4_simulated_rows(px4_legs) + px4_recorded_rows() if px4_legs != 0 else [])


def _recorded_timing(recording: recorded.Recording, waypoints: Sequence[Point], radius_m: float, pass_m: float = recorded.PASS_M) -> Timing:
    seconds = recorded.arrival_s(recording.track, waypoints, radius_m, pass_m)
    if seconds is None:
        raise ValueError(f"{recording.path}: the vehicle never reached the last waypoint")
    return Timing(recording.mode, seconds, tuple(sample for sample in recording.track if sample[0] <= seconds))


def recorded_rows(missions: Sequence[str]) -> list[Row]:
    """For each mission recorded in both modes: the real firmware's GUIDED / AUTO time, and the corners each cut."""
    out = []
    for name in missions:
        if not recorded.available(name):
            continue
        mission = load_mission(MISSIONS / f"{name}.yaml")
        waypoints = [(w.lat, w.lon) for w in mission.waypoints]
        recordings = {
            drive: recorded.read(recorded.path_of(name, mode), "AUTO" if drive == "auto" else mode)
            for drive, mode in recorded.DRIVES.items()
            if recorded.path_of(name, mode).exists()
        }
        timings = {drive: _recorded_timing(recording, waypoints, mission.limits.acceptance_radius_m) for drive, recording in recordings.items()}
        vehicle = f"{mission.vehicle}, SITL frame {recorded.FRAMES[name]}"
        for drive in ("guided", "auto"):
            if drive in timings:
                runs = f"{recorded.path_of(name, 'AUTO').name}; {recorded.path_of(name, recorded.DRIVES[drive]).name}"
                against = f"a recorded real ArduRover SITL AUTO run ({runs})"
                out.append(ratio_row(name, timings[drive], timings["whole"], route_of(mission), against, vehicle, drive))
    return out


def px4_recorded_rows() -> list[Row]:
    """The PX4 vtol's route on the real PX4 (SIH standard_vtol, recorded): ``drive: auto`` against PX4's own AUTO.MISSION over the
    whole route (pass/fail), and GUIDED (OFFBOARD) against it as information. A waypoint counts as passed within the acceptance
    radius (70 m: GUIDED legs end there), timed from the mode's first armed heartbeat."""
    if not recorded.px4_available():
        return []
    mission = load_mission(recorded.PX4_MISSION)
    waypoints = [(w.lat, w.lon) for w in mission.waypoints]
    radius = mission.limits.acceptance_radius_m
    timings = {
        drive: _recorded_timing(recorded.read(recorded.px4_path(drive), mode, recorded.PX4_SYSTEM), waypoints, radius, pass_m=radius)
        for drive, (_, mode) in recorded.PX4_RUNS.items()
    }
    vehicle = "vtol, PX4 SIH standard_vtol"
    out = []
    for drive in ("auto", "guided"):
        against = f"a recorded real PX4 SIH AUTO.MISSION run ({recorded.PX4_RUNS['whole'][0]}; {recorded.PX4_RUNS[drive][0]})"
        caveat = px4_guided_caveat(timings[drive], timings["whole"]) if drive == "guided" else ""
        out.append(ratio_row(mission.name, timings[drive], timings["whole"], route_of(mission), against, vehicle, drive, caveat))
    return out
