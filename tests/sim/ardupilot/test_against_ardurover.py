"""The simulated ArduRover against the real firmware: each leg of each recorded run takes the same time within 5 %.

tests/data/ardurover/ holds real ArduRover SITL (4.7-dev) driving the example missions in GUIDED (the
executive's legs) and in AUTO (the firmware's own mission). The same mission runs here on the lock-step
simulation, with SITL's parameters, from where the recorded vehicle was (and its heading) when it entered
the mode: the motorboat frame's waves move the boat before it is armed.
"""

from __future__ import annotations

import pytest

from benchmarks import recorded
from benchmarks.efficiency import MISSIONS, corner_cuts, route_of, time_auto, time_guided, with_sitl_parameters
from executive.mission.loader import load_mission
from executive.mission.model import Mission

LEG_TOLERANCE = 0.05
RUNS = [(mission, mode) for mission in recorded.FRAMES for mode in ("GUIDED", "AUTO")]


def from_recorded_start(mission: Mission, start: tuple[float, float, float]) -> Mission:
    assert mission.home is not None
    home = mission.home.model_copy(update={"lat": start[0], "lon": start[1], "heading_deg": start[2]})
    return with_sitl_parameters(mission).model_copy(update={"home": home})


def test_every_run_was_recorded() -> None:
    assert all(recorded.path_of(mission, mode).is_file() for mission, mode in RUNS)
    assert all(recorded.path_of(mission, mode).stat().st_size < 200_000 for mission, mode in RUNS)


@pytest.mark.parametrize(("name", "mode"), RUNS)
def test_each_leg_takes_the_firmware_s_time_within_5_percent(name: str, mode: str) -> None:
    mission = load_mission(MISSIONS / f"{name}.yaml")
    real = recorded.read(recorded.path_of(name, mode), mode)
    ours = (time_guided if mode == "GUIDED" else time_auto)(from_recorded_start(mission, real.start))
    waypoints, radius = [(w.lat, w.lon) for w in mission.waypoints], mission.limits.acceptance_radius_m
    real_legs, our_legs = recorded.leg_times(real.track, waypoints, radius), recorded.leg_times(ours.track, waypoints, radius)
    assert len(real_legs) == len(our_legs) == len(waypoints)
    off = [abs(o - r) / r for r, o in zip(real_legs, our_legs, strict=True)]
    assert max(off) <= LEG_TOLERANCE, list(zip(real_legs, our_legs, strict=True))


def test_on_the_real_firmware_guided_leaves_the_route_no_farther_than_auto() -> None:
    for name in recorded.FRAMES:
        mission = load_mission(MISSIONS / f"{name}.yaml")
        guided, auto = (recorded.read(recorded.path_of(name, mode), mode) for mode in ("GUIDED", "AUTO"))
        guided_cuts, auto_cuts = (corner_cuts(run.track, route_of(mission)) for run in (guided, auto))
        assert max(guided_cuts) <= max(auto_cuts), (name, guided_cuts, auto_cuts)
