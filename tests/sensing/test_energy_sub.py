"""A sub's energy on the simulated ArduSub, lock-step: its dives, climbs and surfacing are costed (by the metre of depth),
so the example survey's estimate at the start comes close to what the pack draws, and a pack too small for them is refused.

Before they were costed, ``auv_survey`` was estimated at 2.1 Wh at the start for 19.8 Wh drawn: a 1000 mAh pack fitted.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from executive.mission.lifecycle import MissionStatus
from executive.mission.loader import load_mission
from executive.mission.model import Mission
from tests_support import AUV_SURVEY_RUN, SubRun

SURVEY = load_mission(Path(__file__).parents[2] / "missions" / "auv_survey.yaml")


def survey(**simulator: Any) -> tuple[Mission, tuple[float, float, float]]:
    home = SURVEY.home
    assert home is not None
    mission = SURVEY.model_copy(update={"simulator": SURVEY.simulator.model_copy(update=simulator)}) if simulator else SURVEY
    return mission, (home.lat, home.lon, home.heading_deg)


@AUV_SURVEY_RUN
def test_the_survey_estimated_at_the_start_within_its_uncertainty_of_what_the_dives_and_legs_drew(auv_survey_run: SubRun) -> None:
    """The example survey booted at its home (the run tests/trees/test_auv_survey.py reads too)."""
    assert auv_survey_run.outcome.status is MissionStatus.COMPLETED
    assert auv_survey_run.armed_wh is not None
    drawn = auv_survey_run.end_wh - auv_survey_run.armed_wh  # the route's legs and dives, then SURFACE (its way home)
    start = auv_survey_run.first_estimate
    print(f"start {start.route_wh:.1f} + {start.home_wh:.1f} +/- {start.sigma_wh:.1f} Wh, drawn {drawn:.1f} Wh")
    assert drawn > 15.0  # the dives at full vertical thrust: most of the draw
    assert abs(start.route_wh + start.home_wh - drawn) <= start.sigma_wh


def test_a_pack_too_small_for_the_dives_is_refused_before_arming_with_its_figures(lockstep) -> None:
    """1000 mAh, 4 cells counted at rest: 14.8 Wh, 11.8 above the 20 % reserve; the survey needs about 17."""
    mission, home = survey(params={"BATT_CAPACITY": 1000.0})
    sim = lockstep(mission, home=home)
    outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED and not sim.autopilot.armed
    assert "does not fit the battery: needs 17 Wh + 2 Wh home (+/- 7), has 12 Wh above the 20 % reserve" in outcome.reason
