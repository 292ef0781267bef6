"""The energy rule on what the real firmware said (tests/data/energy/README.md): BATTERY_STATUS parsed, the consumption learned.

Each recording is played through the MAVLink reader into the energy watch, at its recorded times, for the mission it flew
(vtol_transit with ``energy:``); no tree runs, so the route stays the whole route from where the vehicle is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from tlog_replay import records

from executive.io.mavlink.commander import Commander
from executive.io.mavlink.reader import MavlinkReader
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.sensing.energy import EnergyEstimate, EnergyWatch, Held, held_s, planned, return_climb_m
from executive.sensing.heading import wait_for_filterpy
from executive.testing import FakeLink
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import AUTOPILOT_COMPONENT
from executive.world.state import BatteryStatus
from executive.world.vehicles import PROFILES

DATA = Path(__file__).parents[1] / "data" / "energy"
PX4 = Path(__file__).parents[1] / "data" / "px4"
ROOT = Path(__file__).parents[2]


def example(name: str) -> Mission:
    """An example mission as shipped: no ``energy:`` block, the rule's defaults."""
    import yaml

    return Mission.model_validate(yaml.safe_load((ROOT / "missions" / name).read_text(encoding="utf-8")))


def vtol_transit(**energy: Any) -> Mission:
    import yaml

    fields = yaml.safe_load((ROOT / "missions" / "vtol_transit.yaml").read_text(encoding="utf-8"))
    return Mission.model_validate(fields | {"energy": energy})


@dataclass
class Played:
    estimates: list[tuple[float, EnergyEstimate]] = field(default_factory=list)
    unknown: list[str] = field(default_factory=list)
    last: BatteryStatus | None = None
    params: dict[str, float] = field(default_factory=dict)
    armed_s: float = 0.0


def play(name: str, mission: Mission, autopilot: str, speedup: float, until_pct: int = 0, folder: Path = DATA) -> Played:
    """The recording at its recorded times times ``speedup`` (its run's --speedup: the vehicle's time), until battery_remaining
    falls to ``until_pct``."""
    assert wait_for_filterpy()
    blackboard.reset()
    clock, link = ManualClock(), FakeLink()
    reader = MavlinkReader(link, clock, Commander(link, clock, PROFILES[mission.vehicle]), link_timeout_s=5.0)
    state = MissionState()
    state.upload(mission)
    state.start()
    watch = EnergyWatch(clock, state, lambda: autopilot)
    bb = blackboard.reader("energy replay", ["/energy/estimate", "/energy/unknown", "/vehicle/battery_status", "/vehicle/params", "/vehicle/armed"])
    played, t0 = Played(), None
    for t, msg in records(folder / name):
        t0 = t if t0 is None else t0
        now = (t - t0) * speedup
        if now > clock.now():
            if bb.get("/vehicle/armed"):
                played.armed_s += now - clock.now()
            clock.advance(now - clock.now())
        if msg.get_srcComponent() != AUTOPILOT_COMPONENT:
            continue
        link.incoming.append(msg)
        reader.drain()
        watch.service()
        estimate = bb.get("/energy/estimate")
        if estimate is not None and (not played.estimates or played.estimates[-1][1] is not estimate):
            played.estimates.append((clock.now(), estimate))
        if bb.get("/energy/unknown"):
            played.unknown.append(bb.get("/energy/unknown"))
        status = bb.get("/vehicle/battery_status")
        if status is not None and status.remaining_pct is not None and status.remaining_pct <= until_pct:
            break
    played.last, played.params = bb.get("/vehicle/battery_status"), bb.get("/vehicle/params") or {}
    return played


@pytest.fixture(scope="module")
def quadplane_5000mah() -> Played:
    """The real QuadPlane's whole vtol_transit on 5000 mAh, played once per module (its tests: ``xdist_group("quadplane_5000mah")``)."""
    return play("vtol_transit-quadplane-5000mah.tlog", vtol_transit(nominal_v=11.1), "ardupilot", 3.0)


@pytest.mark.xdist_group("quadplane_5000mah")
def test_arduplane_reports_the_energy_drawn_in_hj_and_the_flight_teaches_its_consumption(quadplane_5000mah: Played) -> None:
    """5000 mAh: the whole of vtol_transit drew 1030 mAh, 12.97 Wh (energy_consumed 467 hJ) in 128 s armed (42.6 s at speed-up 3)."""
    played = quadplane_5000mah
    last = played.last
    assert last is not None and (last.consumed_mah, round(last.consumed_wh, 2), last.remaining_pct) == (1030.0, 12.97, 79)
    assert played.params["BATT_CAPACITY"] == 5000.0 and played.params["BATT_MONITOR"] == 4.0
    first, final = played.estimates[0][1], played.estimates[-1][1]
    assert round(first.capacity_wh, 1) == 55.5 and (first.wh_per_km, first.wh_per_min) == (5.0, 16.0)  # the vtol's seeds
    # before arming: the whole flight needs 6 Wh + 11 Wh home (+/- 7), 17 Wh: it drew 12.97 (+31 %, within 1 sigma)
    assert abs(first.route_wh + first.home_wh - 12.97) < first.sigma_wh
    # the flight taught it, its hover (moving or not: MC, TRANSITION_TO_MC, slower than 10 m/s) by the minute and its
    # plane flight by the km (issue 33b): the tlog's own split, armed, is 9.56 Wh in 77 s hovering (7.5 Wh/min) and 3.42 Wh
    # over 1084 m wing-borne (3.2 Wh/km, the transitions in it); it learned 8.7 Wh/min and 1.4 Wh/km. Counted as one
    # (every metre at one rate) it had learned 20 Wh/min and 8.1 Wh/km: a plane at 25 m/s then "drew" more than the hover.
    assert 6.0 < final.wh_per_min < 11.0 and 1.0 < final.wh_per_km < 5.0


def test_arduplane_with_a_300_mah_pack_does_not_fit_before_arming() -> None:
    played = play("vtol_transit-quadplane-300mah-refused.tlog", vtol_transit(nominal_v=11.1), "ardupilot", 3.0)
    estimate = played.estimates[-1][1]
    assert not estimate.fits and round(estimate.has_wh, 1) == 2.6  # 300 mAh x 11.1 V x (99 % - 20 %)


def test_arduplane_turned_back_when_the_flight_had_taught_it_more_than_the_optimistic_seed() -> None:
    """1400 mAh, seeds 2 Wh/km + 3 Wh/min: it fitted at the start (needs 1 + 3 Wh, has 12) and no longer once the hover and the
    transition had taught it 9.7 Wh/min held (the run turned back there, just after its transition to FW: 4.6 Wh drawn)."""
    mission = vtol_transit(nominal_v=11.1, wh_per_km=2, wh_per_min=3)
    played = play("vtol_transit-quadplane-1400mah-turned-back.tlog", mission, "ardupilot", 3.0)
    assert played.estimates[0][1].fits
    short = next(e for _, e in played.estimates if not e.fits)
    assert 2.0 < short.drawn_wh < 5.0 and short.wh_per_min > 6.0


def test_px4_sih_has_no_current_sensor_its_energy_is_learned_from_the_remaining_charge() -> None:
    """BAT1_CAPACITY 5000 mAh x BAT1_N_CELLS 4 (an INT32, sent as its bytes) x 3.7 V = 74 Wh. The recording fell from 96 % to 50 %
    (SIM_BAT_MIN_PCT, where the simulator stops draining) in 68.3 s at PX4_SIM_SPEED_FACTOR 4: 34 Wh in 273 s, 7.5 Wh/min."""
    played = play("vtol_transit-px4-sih-drain600.tlog", vtol_transit(), "px4", 4.0, until_pct=50)
    assert played.params["BAT1_N_CELLS"] == 4.0
    last = played.last
    assert last is not None and last.consumed_wh is None and last.consumed_mah == 0.0 and last.current_a == -1.0
    final = played.estimates[-1][1]
    assert final.capacity_wh == pytest.approx(74.0)
    assert abs(final.wh_per_min - 7.5) < 0.25 * 7.5


def test_real_ardurover_sitl_draws_current_by_its_throttle() -> None:
    """SITL_State_common.cpp update_voltage_current: 50 A at full throttle when the vehicle model gives none (Rover, not Sub)."""
    seen: list[BatteryStatus] = []
    blackboard.reset()
    clock, link = ManualClock(), FakeLink()
    reader = MavlinkReader(link, clock, Commander(link, clock, PROFILES["rover"]), link_timeout_s=5.0)
    bb = blackboard.reader("rover replay", ["/vehicle/battery_status"])
    for _, msg in records(DATA / "rover_square-rover-current.tlog"):
        link.incoming.append(msg)
        reader.drain()
        status = bb.get("/vehicle/battery_status")
        if status is not None and (not seen or seen[-1] is not status):
            seen.append(status)
    assert max(s.current_a or 0.0 for s in seen) > 10.0 and seen[-1].consumed_mah > 50.0 and seen[-1].consumed_wh > 0.5


# PX4 fills BATTERY_STATUS so (src/modules/mavlink/streams/BATTERY_STATUS.hpp at a70a558393): id = battery 1 - 1,
# current_consumed = discharged_mah, energy_consumed = -1 always, current_battery = current_a * 100,
# battery_remaining = round(remaining * 100), time_remaining = max(time_remaining_s, 1) or 0 when not finite. SIH has no current
# sensor (BatterySimulator.cpp: ibatt -1), so -100 cA and 0 mAh; SIM_BAT_DRAIN drains the charge by the armed time alone
# (100 % to SIM_BAT_MIN_PCT in SIM_BAT_DRAIN s; full again when disarmed): the remaining % falls, the counters do not move.


def test_real_px4_refuses_vtol_transit_on_a_300_mah_pack_before_arming_with_the_default_rule() -> None:
    """BAT1_CAPACITY 300 x BAT1_N_CELLS 4 x 3.7 V = 4.44 Wh; the shipped mission, no energy: block."""
    played = play("vtol_transit-energy-300mah-refused.tlog", example("vtol_transit.yaml"), "px4", 2.0, folder=PX4)
    assert (played.params["BAT1_CAPACITY"], played.params["BAT1_N_CELLS"]) == (300.0, 4.0)
    last = played.last
    assert last is not None and (last.consumed_mah, last.consumed_wh, last.current_a) == (0.0, None, -1.0)
    assert last.remaining_pct == 99 and last.voltage_v == pytest.approx(16.2)  # 4 x BAT1_V_CHARGED 4.05 V
    estimate = played.estimates[-1][1]
    assert estimate.capacity_wh == pytest.approx(4.44) and not estimate.fits and played.armed_s == 0.0
    # home: 750 m and 45 s of hover landing, and RTL's climb from the last waypoint's 40 m to RTL_RETURN_ALT: the recording
    # predates reading it, so PX4's default 60 m, 20 m costed as 200 m of cruise (was 14 Wh without the climb)
    assert "RTL_RETURN_ALT" not in played.params
    assert estimate.figures() == "needs 12 Wh + 15 Wh home (+/- 11), has 4 Wh above the 20 % reserve"


def test_real_px4_read_rtl_return_alt_80_at_pre_flight_and_the_way_home_costs_its_climb() -> None:
    """Real PX4 SIH with RTL_RETURN_ALT 80 and the same 300 mAh pack: 40 m of climb from the last waypoint, 2 Wh more home."""
    played = play("vtol_transit-energy-300mah-rtl80-refused.tlog", example("vtol_transit.yaml"), "px4", 2.0, folder=PX4)
    assert played.params["RTL_RETURN_ALT"] == 80.0 and played.armed_s == 0.0
    assert played.estimates[-1][1].figures() == "needs 12 Wh + 16 Wh home (+/- 11), has 4 Wh above the 20 % reserve"


def test_px4s_return_climbs_to_rtl_return_alt_first_which_the_way_home_costs() -> None:
    vtol = example("vtol_transit.yaml")  # its last waypoint at 40 m
    assert return_climb_m(vtol, "px4", {}) == 20.0  # PX4's default RTL_RETURN_ALT, 60 m
    assert return_climb_m(vtol, "px4", {"RTL_RETURN_ALT": 100.0}) == 60.0
    assert return_climb_m(vtol, "px4", {"RTL_RETURN_ALT": 30.0}) == 0.0  # higher already: RTL flies home at its height
    assert return_climb_m(vtol, "ardupilot", {}) == 0.0


def test_real_px4_draining_in_150_s_fits_at_the_start_and_is_short_by_the_second_leg_as_the_flight_teaches_it() -> None:
    """SIM_BAT_DRAIN 150 on BAT1_CAPACITY 5000 (74 Wh): 29.6 Wh/min whatever the aircraft does; the seeds say 16 Wh/min
    hovering, 5 Wh/km as a plane. The run turned back at 72 s (the executive's recording ends at its abort)."""
    played = play("vtol_transit-energy-drain150-turned-back.tlog", example("vtol_transit.yaml"), "px4", 2.0, folder=PX4)
    first, last = played.estimates[0][1], played.estimates[-1][1]
    assert first.capacity_wh == pytest.approx(74.0) and first.fits
    assert not last.fits and last.wh_per_min > 1.25 * 16.0  # learned from the remaining % alone: the hover costs more than seeded
    assert played.last is not None and played.last.current_a == -1.0 and played.last.consumed_mah == 0.0
    drawn_per_min = last.drawn_wh / (played.armed_s / 60.0)
    assert drawn_per_min == pytest.approx(74.0 / 150.0 * 60.0, rel=0.1)  # the fall of the remaining % is SIM_BAT_DRAIN's rate


def test_real_ardurover_rover_square_with_the_default_rule_estimate_against_the_energy_drawn() -> None:
    """rover.parm's BATT_MONITOR 4, BATT_CAPACITY 3300 mAh; the pack's voltage unsaid: 12.6 V at rest is 3 cells (11.1 V)."""
    played = play("rover_square-ardurover-default-rule.tlog", example("rover_square.yaml"), "ardupilot", 2.0)
    first, last = played.estimates[0][1], played.estimates[-1][1]
    assert first.capacity_wh == pytest.approx(36.63) and first.fits
    used = last.drawn_wh
    assert used == pytest.approx(0.97, abs=0.01)  # BATTERY_STATUS energy_consumed
    assert abs(first.route_wh + first.home_wh - used) <= 0.15 * used  # 0.90 Wh estimated at the start


def test_the_seconds_held_ahead_cost_a_vtols_hover_phases_and_every_sample_hold() -> None:
    """vtol_transit: climb 30 m at 2.5 m/s (12 s), the hover point 36.1 m away at 5 m/s (7.2 s), the transition to FW (15 s);
    home: the transition back (10 s), 34 m down at 1.5 m/s and the last 6 m at 0.5 m/s (34.7 s)."""
    vtol = example("vtol_transit.yaml")
    held = held_s(vtol, 0, take_off=True, to_fw_ahead=True)
    assert (round(held.route_s, 1), round(held.home_s, 1)) == (34.2, 44.7)
    assert held_s(vtol, 1, take_off=False, to_fw_ahead=False).route_s == 0.0
    assert held_s(vtol, 2, take_off=False, to_fw_ahead=False, hovering_at_m=12.0).home_s == pytest.approx(6 / 1.5 + 12.0)
    boat = example("asv_sampling.yaml")  # two sample points of sampling.duration_s 10 s
    assert [held_s(boat, leg, take_off=leg == 0, to_fw_ahead=False) for leg in (0, 2, 4)] == [Held(20.0, 0.0), Held(10.0, 0.0), Held(0.0, 0.0)]


@pytest.mark.xdist_group("quadplane_5000mah")
def test_the_real_quadplane_flight_costed_at_its_own_learned_rates_matches_what_it_drew(quadplane_5000mah: Played) -> None:
    """The 5000 mAh flight drew 12.97 Wh; its hover seconds (take-off, hover point, transitions, landing) and its plane metres,
    costed at the rates it taught the model, come to within 10 % of it (climb and descent alone, as before: about 9 Wh)."""
    played = quadplane_5000mah
    learned = played.estimates[-1][1]
    costed = planned(vtol_transit(capacity_wh=55.5, wh_per_km=learned.wh_per_km, wh_per_min=learned.wh_per_min))
    assert isinstance(costed, EnergyEstimate)
    assert costed.route_wh + costed.home_wh == pytest.approx(learned.drawn_wh, rel=0.1)
