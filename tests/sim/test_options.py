"""Where the simulated vehicle of a mission starts, said when it starts."""

from __future__ import annotations

from executive.mission.loader import load_mission
from executive.sim.options import simulated_home, where_it_starts


def test_without_home_it_says_the_vehicle_starts_at_the_first_waypoint(minimal_mission, square_mission) -> None:
    """Issue 43: without `home:` a far first waypoint passed on the simulator, the vehicle being put there; nothing said so."""
    mission = load_mission(minimal_mission)
    assert simulated_home(mission)[:2] == (47.397742, 8.545594)
    assert where_it_starts(mission).startswith("; the mission has no home: so it starts at waypoint 1 (47.3977420, 8.5455940)")
    assert where_it_starts(square_mission.model_copy(update={"home": None})).startswith("; the mission has no home:")
    with_home = square_mission.model_copy(update={"home": {"lat": 47.39, "lon": 8.54}})
    assert where_it_starts(with_home) == ""
