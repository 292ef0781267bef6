"""Recorded runs of the real firmware: ArduRover SITL (4.7-dev) driving the example missions, GUIDED and AUTO; PX4 SIH
(a70a558393, standard_vtol) flying a waypoints route, OFFBOARD and AUTO.MISSION.

``tests/data/ardurover/{mission}-{frame}-{mode}.tlog``: what the vehicle said (HEARTBEAT,
GLOBAL_POSITION_INT, ...) while the executive drove the mission in GUIDED (``executive run --mavlink``),
or while the firmware drove the same waypoints as its own AUTO mission; SITL started as
``sim_vehicle.py -v Rover -f {frame}`` does (its default parameters: WP_SPEED 5, WP_RADIUS 3), at the
mission's home, speed-up 2. How they were made: tests/data/ardurover/README.md.

``tests/data/px4/vtol-waypoints-*.tlog`` (issue 32): the executive's ``drive: guided`` (OFFBOARD) and ``drive: auto`` runs of
``tests/data/px4/vtol-waypoints.yaml``, and PX4's own AUTO.MISSION over the whole route (a probe uploaded it); how they were
made: tests/data/px4/README.md.

Times are the vehicle's own (GLOBAL_POSITION_INT ``time_boot_ms``), so the speed-up does not matter.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "ardurover"
#: The SITL frame each example mission was recorded on.
FRAMES = {"rover_square": "rover", "boat_survey": "motorboat"}
#: The recorded runs: the executive's GUIDED legs, its drive: auto (horizon 3), and the firmware's own AUTO over the whole route.
DRIVES = {"guided": "GUIDED", "auto": "SUPERVISED", "whole": "AUTO"}
PASS_M = 5.0  # an intermediate waypoint counts as passed within this (as benchmarks.efficiency._Route)

PX4_DATA = DATA.parent / "px4"
#: The route the PX4 runs flew, and its mission file.
PX4_MISSION = PX4_DATA / "vtol-waypoints.yaml"
#: The PX4 recordings: drive -> (file, the mode timed from); "whole" is PX4's own AUTO.MISSION over the whole route.
PX4_RUNS = {
    "guided": ("vtol-waypoints-guided.tlog", "OFFBOARD"),
    "auto": ("vtol-waypoints-auto.tlog", "AUTO.MISSION"),
    "whole": ("vtol-waypoints-px4-own-auto.tlog", "AUTO.MISSION"),
}
PX4_SYSTEM = 7  # run_px4_sih.sh -i 6: MAV_SYS_ID 1 + the instance

TrackPoint = tuple[float, float, float]  # vehicle seconds since the mode was entered, lat, lon


@dataclass(frozen=True)
class Recording:
    """One recorded run: when the vehicle was armed in the mode (boot seconds), and where it was after (mode-relative seconds)."""

    path: Path
    mode: str
    entered_s: float
    track: tuple[TrackPoint, ...]
    #: Where the vehicle was, and its heading (degrees), when it entered the mode: where a simulation of the run starts.
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)


def path_of(mission: str, mode: str) -> Path:
    return DATA / f"{mission}-{FRAMES[mission]}-{mode.lower()}.tlog"


def px4_path(drive: str) -> Path:
    return PX4_DATA / PX4_RUNS[drive][0]


def read(path: str | os.PathLike[str], mode: str, system: int = 1) -> Recording:
    """The track of a recorded run from the moment the autopilot (``system``, component 1) was armed in ``mode`` (an ArduRover
    mode, or a PX4 one: ``AUTO.MISSION``, ``OFFBOARD``)."""
    os.environ.setdefault("MAVLINK20", "1")
    from pymavlink import mavutil

    from executive.io.mavlink.modes import PX4_MODES
    from executive.world.vehicles import PROFILES

    conn = mavutil.mavlink_connection(os.fspath(path), dialect="ardupilotmega", robust_parsing=True)
    positions: list[tuple[float, float, float, float]] = []  # tlog time, boot s, lat, lon
    headings: list[float] = []
    entered_at: float | None = None  # tlog time
    while True:
        msg = conn.recv_match(type=["HEARTBEAT", "GLOBAL_POSITION_INT"])
        if msg is None:
            break
        if msg.get_srcSystem() != system or msg.get_srcComponent() != 1:
            continue
        stamp = float(getattr(msg, "_timestamp", 0.0))
        if msg.get_type() == "GLOBAL_POSITION_INT":
            positions.append((stamp, msg.time_boot_ms / 1000.0, msg.lat * 1e-7, msg.lon * 1e-7))
            headings.append(msg.hdg / 100.0)
        elif entered_at is None and msg.type != 6:  # 6: a GCS
            armed = bool(msg.base_mode & 128)
            if msg.autopilot == mavutil.mavlink.MAV_AUTOPILOT_PX4:
                number = PX4_MODES[mode]
            else:
                number = PROFILES["boat" if msg.type == 11 else "rover"].modes[mode]
            if armed and msg.custom_mode == number:
                entered_at = stamp
    conn.close()
    if entered_at is None or not positions:
        raise ValueError(f"{path}: no armed {mode} with positions in the recording")
    # the mode's entry in boot time: the first position after the heartbeat that showed it, less the tlog time between
    after = next((p for p in positions if p[0] >= entered_at), positions[-1])
    entered_s = after[1] - (after[0] - entered_at)
    first = next(i for i, p in enumerate(positions) if p[1] >= entered_s)
    track = tuple((boot - entered_s, lat, lon) for _, boot, lat, lon in positions[first:])
    start = (positions[first][2], positions[first][3], headings[first])
    return Recording(Path(path), mode, entered_s, track, start)


def _distance(a: tuple[float, float], b: tuple[float, float]) -> float:
    from executive.world.geo import distance

    return distance(a[0], a[1], b[0], b[1])


def arrival_s(track: Sequence[TrackPoint], waypoints: Sequence[tuple[float, float]], radius_m: float, pass_m: float = PASS_M) -> float | None:
    """When the vehicle was within ``radius_m`` of the last waypoint, having passed the others within ``pass_m`` in turn."""
    k = 0
    for t, lat, lon in track:
        while k < len(waypoints) and _distance((lat, lon), waypoints[k]) <= (radius_m if k == len(waypoints) - 1 else pass_m):
            k += 1
        if k == len(waypoints):
            return t
    return None


def leg_times(track: Sequence[TrackPoint], waypoints: Sequence[tuple[float, float]], radius_m: float) -> list[float]:
    """How long each leg took: an intermediate waypoint is passed where the vehicle came nearest it (before it was half-way
    along the next leg), the last one when the vehicle was within ``radius_m`` of it."""
    times, start, begin = [], 0.0, 0
    for k, waypoint in enumerate(waypoints):
        if k == len(waypoints) - 1:
            end = next((i for i in range(begin, len(track)) if _distance(track[i][1:], waypoint) <= radius_m), None)
            if end is None:
                break
        else:
            half = _distance(waypoint, waypoints[k + 1]) / 2.0
            stop = next((i for i in range(begin, len(track)) if _distance(track[i][1:], waypoints[k + 1]) <= half), len(track))
            end = min(range(begin, max(begin + 1, stop)), key=lambda i: _distance(track[i][1:], waypoint))
        times.append(track[end][0] - start)
        start, begin = track[end][0], end + 1
    return times


def available(mission: str) -> bool:
    """Whether GUIDED and AUTO runs of ``mission`` were recorded."""
    return mission in FRAMES and all(path_of(mission, mode).exists() for mode in ("GUIDED", "AUTO"))


def px4_available() -> bool:
    """Whether the PX4 vtol runs were recorded (each drive, and PX4's own AUTO.MISSION)."""
    return PX4_MISSION.exists() and all(px4_path(drive).exists() for drive in PX4_RUNS)
