"""A camera's scans reach the simulated autopilot's proximity sensor while a mission runs, in the lock-step simulation."""

from __future__ import annotations

from dataclasses import dataclass, field

import py_trees

from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.testing import Lockstep

START = (-35.363261, 149.165230)
CAMERA_UNTIL_S = 12.0  # vehicle seconds after boot: then the camera goes quiet
#: 5° sectors from 90° left to 85° right; one obstacle 3.5 m ahead, a wall 9 m away on the left.
SCAN = {"distances_cm": [900] * 9 + [2000] * 9 + [350] + [2000] * 17, "increment_deg": 5, "angle_offset_deg": -90}


def mission() -> Mission:
    return Mission.model_validate({
        "version": 1, "name": "obstacles", "vehicle": "boat", "tree": "waypoints", "auto_arm": True,
        "home": {"lat": START[0], "lon": START[1]}, "simulator": {"ekf_ready_after_s": 2.0},
        "limits": {"acceptance_radius_m": 2.0, "leg_timeout_s": 60.0},
        "waypoints": [{"lat": START[0] + 0.0003, "lon": START[1]}],
    })  # fmt: skip


@dataclass
class Camera:
    """Stands in for the status line: each tick, sends a scan (from the autopilot's boot until CAMERA_UNTIL_S) and notes what its sensor holds."""

    sim: Lockstep | None = None  # the simulation, once made
    sent: int = 0
    seen: list[tuple[float, tuple[int, float] | None]] = field(default_factory=list)  # (autopilot time, closest obstacle)

    def update(self, force: bool = False) -> None:
        assert self.sim is not None
        autopilot = self.sim.autopilot
        now, booted = autopilot.elapsed_s, autopilot.booted
        self.seen.append((now, autopilot.proximity.closest(now)))
        if booted and now < CAMERA_UNTIL_S:  # an autopilot still initialising handles no message: the camera waits for it
            self.sim.send_obstacles(SCAN)
            self.sim.send_obstacles(b'{"distances_cm": "broken", "increment_deg": 5}')  # a camera bug: dropped, counted, never forwarded
            self.sent += 1

    def close(self) -> None:
        pass


def test_scans_reach_the_autopilot_while_the_camera_sends_and_time_out_after(lockstep) -> None:
    camera = Camera()
    sim = camera.sim = lockstep(mission(), obstacles=True, progress=camera)
    outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    storage = py_trees.blackboard.Blackboard.storage
    assert camera.sent > 50
    assert storage["/obstacles/rejected"] >= camera.sent - 2  # every broken datagram (bar the last ones in flight)
    assert storage["/obstacles/last_error"].startswith("distances_cm: expected a list")
    forwarded = storage["/obstacles/forwarded"]
    assert camera.sent - 5 <= forwarded <= camera.sent  # one per tick with a new scan; none after the camera stopped
    assert sim.autopilot.proximity.messages == forwarded  # every one arrived, and only those
    while_sending = [closest for t, closest in camera.seen if 5.0 < t < CAMERA_UNTIL_S]
    assert while_sending and all(closest == (0, 3.5) for closest in while_sending)
    assert sim.autopilot.proximity.faces[6] == 9.0  # the wall on the left
    after = [closest for t, closest in camera.seen if t > CAMERA_UNTIL_S + 1.0]
    assert after and all(closest is None for closest in after)  # no data half a second after the last scan: nothing repeated
