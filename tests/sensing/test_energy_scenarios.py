"""The energy rule on the simulated rover, lock-step: refused at the start, turned back at the leg where the estimate no longer
fits (and home reached), and a whole route that fits driven to the end.

The rover drives 4 legs of 60 m due north of LINE_HOME; its pack is made small (BATT_CAPACITY in ``simulator.params`` sizes
the simulated pack and is what the autopilot reports) so that a few hundred metres matter: 1000 mAh x 11.1 V = 11.1 Wh,
8.9 Wh above the 20 % reserve.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pytest

from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.operator.status import status_line
from executive.runtime.loop import RunOutcome
from executive.sensing.energy import EnergyWatch
from executive.sim.faults import Headwind
from executive.testing import Lockstep
from executive.world import blackboard, geo
from tests_support import LINE_HOME

LEG_DEG = 0.0002248 * 60.0 / 25.0  # 60 m of latitude
FACTOR = 2.5  # the headwind: 2.5 times the current for the same way


def energy_line(capacity_mah: float, legs: int = 4, **energy: Any) -> Mission:
    return Mission.model_validate({
        "version": 1, "name": "energy line", "vehicle": "rover", "auto_arm": True,
        "home": {"lat": LINE_HOME[0], "lon": LINE_HOME[1], "heading_deg": 0.0},
        "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 120, "recovery_timeout_s": 30},
        "simulator": {"ekf_ready_after_s": 2, "params": {"BATT_CAPACITY": capacity_mah}},
        "energy": {"nominal_v": 11.1, **energy},
        "waypoints": [{"lat": LINE_HOME[0] + LEG_DEG * k, "lon": LINE_HOME[1]} for k in range(1, legs + 1)],
    })  # fmt: skip


def test_a_route_too_long_for_the_battery_is_refused_before_arming_with_its_figures(lockstep) -> None:
    sim = lockstep(energy_line(500.0), home=(*LINE_HOME, 0.0))
    outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED
    assert "does not fit the battery: needs 2.4 Wh + 2.4 Wh home (+/- 2.4), has 4.4 Wh above the 20 % reserve" in outcome.reason
    assert not sim.autopilot.armed and sim.autopilot.battery.consumed_mah < 1.0  # nothing armed, nothing drawn but the idle


def without_energy(mission: Mission, **update: Any) -> Mission:
    return Mission.model_validate({**mission.model_dump(exclude_none=True, exclude={"energy"}), **update})


def test_a_mission_that_says_nothing_of_energy_is_judged_too_its_pack_in_wh_from_the_cells_counted_at_rest(lockstep) -> None:
    sim = lockstep(without_energy(energy_line(500.0)), home=(*LINE_HOME, 0.0))
    outcome = sim.run_to_end(limit_s=60)  # 500 mAh x 3 cells x 3.7 V = 5.55 Wh: the 4 x 60 m does not fit
    assert outcome.status is MissionStatus.ABORTED and not sim.autopilot.armed
    assert "does not fit the battery: needs 2.4 Wh + 2.4 Wh home (+/- 2.4), has 4.4 Wh above the 20 % reserve" in outcome.reason


def test_a_voltage_only_monitor_runs_a_mission_that_says_nothing_unjudged_and_warned_but_refuses_one_that_asks(lockstep, caplog) -> None:
    params = {"BATT_CAPACITY": 1000.0, "BATT_MONITOR": 3.0}
    limits = {"acceptance_radius_m": 1.5, "leg_timeout_s": 120, "battery_min_pct": None, "battery_min_v": 10.5}
    quiet = without_energy(energy_line(1000.0, legs=1), simulator={"ekf_ready_after_s": 2, "params": params}, limits=limits)
    assert lockstep(quiet, home=(*LINE_HOME, 0.0)).run_to_end(limit_s=120).status is MissionStatus.COMPLETED
    assert "energy not judged on this vehicle: the battery monitor counts no energy drawn (BATT_MONITOR 3: voltage only" in caplog.text
    asks = quiet.model_copy(update={"energy": energy_line(1000.0).energy})
    outcome = lockstep(asks, home=(*LINE_HOME, 0.0)).run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED and "fit a current sensor (BATT_MONITOR 4)" in outcome.reason


@dataclass
class FittingRoute:
    """The 4 x 60 m line on the 1000 mAh pack, driven to its end: ``executive ctl status`` on leg 3, the first start estimate,
    the outcome and the energy the route drew."""

    status: dict[str, Any]
    first_estimate: Any
    outcome: RunOutcome
    drawn_wh: float


@pytest.fixture(scope="module")
def fitting_route() -> Callable[[], FittingRoute]:
    """The run once per module, when a test first asks (its tests share it: ``xdist_group("fitting_route")``). Asking for the
    status on the way changes nothing of the run: the same line run straight through steps identically (position and energy)."""
    made: list[FittingRoute] = []

    def run() -> FittingRoute:
        if not made:
            with Lockstep(energy_line(1000.0), home=(*LINE_HOME, 0.0)) as sim:
                bb = blackboard.reader("energy test", ["/energy/estimate"])
                first: list[Any] = []
                sim.observers.append(lambda s: first.append(bb.get("/energy/estimate")) if not first and bb.get("/energy/estimate") else None)
                sim.run(until=lambda: sim.runtime.mission_state.legs.leg_index == 2)
                status = sim.runtime.operator.request("tree").to_dict()["status"]  # as `executive ctl status` has it
                outcome = sim.run_to_end(limit_s=400)
                made.append(FittingRoute(status, first[0], outcome, sim.autopilot.battery.consumed_wh))
        return made[0]

    return run


@pytest.mark.xdist_group("fitting_route")
def test_a_route_that_fits_is_driven_to_the_end_its_energy_shown_on_the_way(fitting_route) -> None:
    route = fitting_route()
    energy = route.status["energy"]
    assert abs(energy["margin_wh"] - (energy["has_wh"] - energy["need_wh"] - energy["sigma_wh"])) <= 0.02  # each rounded to 0.01
    assert energy["margin_wh"] > 0
    assert f"energy {energy['has_wh']:.1f}/{energy['need_wh']:.1f}±{energy['sigma_wh']:.1f} Wh" in status_line(route.status)
    assert route.outcome.status is MissionStatus.COMPLETED


def test_a_headwind_turns_the_rover_back_at_the_leg_where_the_estimate_no_longer_fits_and_it_reaches_home(lockstep) -> None:
    sim = lockstep(energy_line(1000.0), home=(*LINE_HOME, 0.0), events=[Headwind(kind="headwind", at_s=60.0, factor=FACTOR)])
    legs: list[int] = []
    bb = blackboard.reader("energy test", ["/mission/leg_index"])
    sim.observers.append(lambda s: legs.append(bb.get("/mission/leg_index")))
    outcome = sim.run_to_end(limit_s=400)
    assert outcome.status is MissionStatus.ABORTED
    assert outcome.reason.startswith("Enough energy to finish and return?: energy short: needs ")
    assert legs[-1] == 2  # on the third leg: the first two fitted (the wind rose on the second)
    assert sim.autopilot.mode == "RTL" and "RTL (confirmed)" in (outcome.safe or "")
    v = sim.autopilot.vehicle
    for _ in range(200):  # the firmware's RTL drives home
        sim.step(1.0)
        if geo.distance(v.lat, v.lon, *LINE_HOME) < 3.0:  # ArduRover's RTL stops within WP_RADIUS (2 m)
            break
    assert geo.distance(v.lat, v.lon, *LINE_HOME) < 3.0
    print(f"home with {sim.autopilot.battery.charge:.1%} of the pack")
    assert sim.autopilot.battery.charge > 0.0


@pytest.mark.xdist_group("fitting_route")
@pytest.mark.parametrize("factor", [1.0])
def test_the_estimate_at_the_start_is_within_a_quarter_of_what_the_route_and_the_way_home_drew(fitting_route, factor: float) -> None:
    """The report's figure: the error of the start estimate against the energy drawn (the route, then RTL home)."""
    route = fitting_route()
    assert route.outcome.status is MissionStatus.COMPLETED
    route_drawn = route.drawn_wh
    assert abs(route.first_estimate.route_wh - route_drawn) < 0.25 * route_drawn


def test_a_weak_battery_is_refused_on_px4_which_reads_its_charge_and_not_on_ardupilot_which_counts_from_full(lockstep) -> None:
    """Half a 1000 mAh pack: PX4 reports 50 % (its estimator starts from the voltage), ArduPilot 100 % (its counter starts full)."""
    from executive.sim.faults import WeakBattery

    weak = [WeakBattery(kind="weak_battery", at_s=0.0, share=0.5)]
    px4 = {"params": {"BAT1_CAPACITY": 1000.0}}  # BAT1_N_CELLS 3: 11.1 Wh
    sim = lockstep(energy_line(1000.0), home=(*LINE_HOME, 0.0), events=weak, autopilot="px4", firmware=px4)
    outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED and not sim.autopilot.armed
    assert "does not fit the battery" in outcome.reason and "has 3.3 Wh above the 20 % reserve" in outcome.reason
    ardupilot = lockstep(energy_line(1000.0), home=(*LINE_HOME, 0.0), events=weak)
    ardupilot.run(until=lambda: ardupilot.autopilot.armed)  # it cannot know: the mission starts


def test_a_person_who_takes_over_wins_over_the_energy_failsafe(lockstep) -> None:
    """The same headwind, and a pilot who takes the rover (take-over switch high, MANUAL) at 80 s, before the estimate fails:
    the mission pauses hands off and nothing is asked of the vehicle, however short the energy gets."""
    from executive.sim.faults import RcTakeover

    faults = [Headwind(kind="headwind", at_s=60.0, factor=FACTOR), RcTakeover(kind="rc_takeover", at_s=80.0, channel=6, pwm=1900, mode="MANUAL")]
    sim = lockstep(energy_line(1000.0), home=(*LINE_HOME, 0.0), events=faults)
    asked: list[int] = []
    send = sim.link.send

    def spy(msg: Any) -> None:
        if msg.get_type() == "COMMAND_LONG" and sim.clock.now() > 80.0:
            asked.append(msg.command)
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    sim.run(limit_s=200.0, until=lambda: sim.clock.now() > 190.0)
    assert sim.status is MissionStatus.PAUSED and sim.autopilot.mode == "MANUAL"
    estimate = blackboard.reader("energy test", ["/energy/estimate"]).get("/energy/estimate")
    assert estimate.margin_wh < 0.0  # short (needs 1.6 Wh + 4.1 Wh home (+/- 1.3), has 4.5 Wh): still nothing asked
    assert asked == []


def test_the_estimate_worked_out_once_per_report_is_the_one_worked_out_afresh_at_every_tick(monkeypatch: pytest.MonkeyPatch) -> None:
    """The energy watch works its figures out again only when an input is another object (a position or battery report,
    the leg, the model's update): at every tick of a drive they are the figures worked out afresh, and most ticks reuse them."""
    ticks: list[tuple[object, object, bool]] = []
    real = EnergyWatch._publish

    def publish(self: EnergyWatch, mission: Mission, config: Any, capacity_wh: float, drawn: float, autopilot: str, params: Any) -> None:
        before = self._needs
        real(self, mission, config, capacity_wh, drawn, autopilot, params)
        estimate = blackboard.value("/energy/estimate")
        afresh = self._estimate(mission, config, capacity_wh, drawn, autopilot, params, blackboard.value("/vehicle/altitude_above_bottom_m"))
        published = (estimate.has_wh, estimate.route_wh, estimate.home_wh, estimate.sigma_wh, estimate.wh_per_km, estimate.wh_per_min)
        ticks.append((published, afresh, self._needs is before))

    monkeypatch.setattr(EnergyWatch, "_publish", publish)
    with Lockstep(energy_line(1000.0, legs=1), home=(*LINE_HOME, 0.0)) as sim:
        sim.run(limit_s=60, until=lambda: sim.clock.now() >= 25.0)  # armed, driving, the model's first window learnt
    assert [published for published, _, _ in ticks] == [afresh for _, afresh, _ in ticks]
    assert sum(reused for _, _, reused in ticks) > len(ticks) / 3  # between two position reports (5 Hz; ticks at 10 Hz)
