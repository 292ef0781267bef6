"""The battery read as energy: the capacity in Wh and what to set when it cannot be told."""

from __future__ import annotations

import pytest

from executive.mission.model import EnergyConfig
from executive.sensing import battery_energy
from executive.sensing.battery_energy import JudgedCapacity, NotJudged, capacity, cells_at_rest, counts_current, drawn_wh, judgeable, unknown_reading
from executive.world.state import Battery, BatteryStatus


def status(mah: float | None = 100.0, wh: float | None = None, pct: int | None = 90, volts: float = 12.0) -> BatteryStatus:
    return BatteryStatus(mah, wh, pct, None, volts, 5.0, 1, 0.0)


@pytest.mark.parametrize(
    ("config", "params", "autopilot", "expected"),
    [
        (EnergyConfig(capacity_wh=120.0), {}, "ardupilot", 120.0),
        (EnergyConfig(nominal_v=11.1), {"BATT_CAPACITY": 10000.0}, "ardupilot", 111.0),
        (EnergyConfig(), {"BAT1_CAPACITY": 5000.0, "BAT1_N_CELLS": 4.0}, "px4", 74.0),
        (EnergyConfig(), {"BATT_CAPACITY": 3300.0}, "ardupilot", "BATT_CAPACITY 3300 mAh, but not the pack's voltage: set energy.nominal_v"),
        (EnergyConfig(), {"BAT1_CAPACITY": -1.0}, "px4", "BAT1_CAPACITY is -1 (unknown): set it on the autopilot, or energy.capacity_wh"),
        (EnergyConfig(nominal_v=11.1), {}, "ardupilot", "BATT_CAPACITY not read from the autopilot: set energy.capacity_wh"),
        # ArduPilot says no cell count: the cells counted from the pack at rest, where only one count fits
        (EnergyConfig(), {"BATT_CAPACITY": 3300.0, "rest_v": 12.6}, "ardupilot", 36.63),
        (EnergyConfig(), {"BATT_CAPACITY": 10000.0, "rest_v": 16.3}, "ardupilot", 148.0),
        (EnergyConfig(), {"BATT_CAPACITY": 3300.0, "rest_v": 10.6}, "ardupilot", "BATT_CAPACITY 3300 mAh, but not the pack's voltage (10.6 V"),
    ],
)
def test_the_capacity_or_what_to_set(config: EnergyConfig, params: dict[str, float], autopilot: str, expected: float | str) -> None:
    params = dict(params)
    found = capacity(config, params, autopilot, params.pop("rest_v", None))
    if isinstance(expected, str):
        assert isinstance(found, str) and found.startswith(expected)
    else:
        assert not isinstance(found, str) and round(found.wh, 3) == expected


def test_energy_drawn_is_ardupilots_counter_else_px4s_mah_times_the_voltage() -> None:
    assert drawn_wh(status(wh=1.5), None) == 1.5
    assert drawn_wh(status(mah=500.0, wh=None, volts=16.0), None) == 8.0


def test_a_voltage_only_monitor_cannot_count_energy_and_says_what_to_fit() -> None:
    # ArduPilot estimates no remaining charge without a current (GCS_Common.cpp battery_remaining_pct: -1)
    why = unknown_reading(status(mah=None, wh=None, pct=None), Battery(12.0, None, None, 0.0), {"BATT_MONITOR": 3.0})
    assert why == (
        "the battery monitor counts no energy drawn (BATT_MONITOR 3: voltage only (no current: nothing counted)): "
        "fit a current sensor (BATT_MONITOR 4) or set energy: {check: off}"
    )


def test_no_remaining_charge_estimate_is_refused() -> None:
    why = unknown_reading(status(pct=None), Battery(12.0, 1.0, None, 0.0), {})
    assert why is not None and "battery_remaining -1" in why


def test_px4_sih_measures_no_current_its_energy_is_read_from_the_remaining_charge() -> None:
    """PX4 SIH's BATTERY_STATUS as recorded (current_battery -100, current_consumed 0, energy_consumed -1, remaining 99)."""
    sih = BatteryStatus(0.0, None, 99, 1187, 16.2, -1.0, 1, 0.0)
    assert unknown_reading(sih, None, {}) is None and not counts_current(sih)
    assert counts_current(status(mah=120.0, wh=1.4))


def test_the_cells_are_counted_at_rest_only_where_one_count_fits() -> None:
    assert [cells_at_rest(v) for v in (4.1, 12.6, 11.4, 16.8, 25.2)] == [1, 3, 3, 4, 6]
    assert cells_at_rest(10.8) is None  # 3 cells at 3.6 V (nearly empty) or nothing: not told
    assert cells_at_rest(29.5) is None  # 7 cells at 4.21 V or 8 at 3.69 V


ARDUPILOT = {"BATT_MONITOR": 4.0, "BATT_CAPACITY": 3300.0}
VOLTAGE_ONLY = BatteryStatus(None, None, None, None, 12.4, None, 0, 0.0)


def test_a_mission_that_says_nothing_is_judged_where_the_battery_tells_and_runs_unjudged_on_a_voltage_only_monitor() -> None:
    found = judgeable(EnergyConfig(), False, status(), None, ARDUPILOT, "ardupilot", 12.6)
    assert not isinstance(found, (str, NotJudged)) and round(found.wh, 2) == 36.63
    unjudged = judgeable(EnergyConfig(), False, VOLTAGE_ONLY, None, {"BATT_MONITOR": 3.0}, "ardupilot", 12.4)
    assert isinstance(unjudged, NotJudged) and "BATT_MONITOR 3: voltage only" in unjudged.why
    # PX4 SIH's defaults: no current sensor, BAT1_CAPACITY -1: its charge from the voltage only
    sih = BatteryStatus(0.0, None, 99, None, 16.2, -1.0, 1, 0.0)
    unjudged = judgeable(EnergyConfig(), False, sih, None, {"BAT1_CAPACITY": -1.0, "BAT1_N_CELLS": 4.0}, "px4", 16.2)
    assert isinstance(unjudged, NotJudged) and "measures no current, and BAT1_CAPACITY is -1" in unjudged.why


def test_a_current_measured_with_no_capacity_is_refused_naming_what_to_set_and_the_opt_out() -> None:
    found = judgeable(EnergyConfig(), False, status(), None, {"BATT_MONITOR": 4.0, "BATT_CAPACITY": 0.0}, "ardupilot", 12.6)
    assert found == "BATT_CAPACITY is 0 (unknown): set it on the autopilot, or energy.capacity_wh; or energy: {check: off}"


def test_a_mission_that_asks_for_the_rule_is_refused_where_the_battery_cannot_tell() -> None:
    found = judgeable(EnergyConfig(nominal_v=11.1), True, VOLTAGE_ONLY, None, {"BATT_MONITOR": 3.0, "BATT_CAPACITY": 3300.0}, "ardupilot", 12.4)
    assert isinstance(found, str) and found.startswith("the battery monitor counts no energy drawn (BATT_MONITOR 3")


def test_the_verdict_is_judged_again_only_when_an_input_changes(monkeypatch: pytest.MonkeyPatch) -> None:
    """The energy watch asks every tick; the battery reports at ~1 Hz: a tick between two reports reuses the verdict."""
    judged: list[BatteryStatus] = []
    real = battery_energy.judgeable
    monkeypatch.setattr(battery_energy, "judgeable", lambda config, said, report, *rest: judged.append(report) or real(config, said, report, *rest))
    verdict = JudgedCapacity()
    first, later = status(), status(mah=120.0)
    for report, params in ((first, ARDUPILOT), (first, ARDUPILOT), (first, dict(ARDUPILOT)), (later, ARDUPILOT)):
        found = verdict.get(EnergyConfig(), False, report, None, params, "ardupilot", 12.6)
        assert found == judgeable(EnergyConfig(), False, report, None, params, "ardupilot", 12.6)
    assert judged == [first, later]  # an equal parameters dict is the same input
    # a parameter that changes the capacity is judged again
    assert verdict.get(EnergyConfig(), False, later, None, {**ARDUPILOT, "BATT_CAPACITY": 0.0}, "ardupilot", 12.6) == (
        "BATT_CAPACITY is 0 (unknown): set it on the autopilot, or energy.capacity_wh; or energy: {check: off}"
    )
