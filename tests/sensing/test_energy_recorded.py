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

from executive import blackboard
from executive.clock import ManualClock
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.reader import MavlinkReader
from executive.mavlink_dialect import AUTOPILOT_COMPONENT
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission
from executive.sensing.energy import EnergyEstimate, EnergyWatch
from executive.sensing.heading import wait_for_filterpy
from executive.state import BatteryStatus
from executive.testing import FakeLink
from executive.vehicles import PROFILES

DATA = Path(__file__).parents[1] / "data" / "energy"
ROOT = Path(__file__).parents[2]


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


def play(name: str, mission: Mission, autopilot: str, speedup: float, until_pct: int = 0) -> Played:
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
    for t, msg in records(DATA / name):
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


def test_arduplane_reports_the_energy_drawn_in_hj_and_the_flight_teaches_its_consumption() -> None:
    """5000 mAh: the whole of vtol_transit drew 1030 mAh, 12.97 Wh (energy_consumed 467 hJ) in 128 s armed (42.6 s at speed-up 3)."""
    played = play("vtol_transit-quadplane-5000mah.tlog", vtol_transit(nominal_v=11.1), "ardupilot", 3.0)
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
