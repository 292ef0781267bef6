"""The battery read as energy: the capacity in Wh and what to set when it cannot be told."""

from __future__ import annotations

import pytest

from executive.mission.model import EnergyConfig
from executive.sensing.battery_energy import capacity, counts_current, drawn_wh, unknown_reading
from executive.state import Battery, BatteryStatus


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
    ],
)
def test_the_capacity_or_what_to_set(config: EnergyConfig, params: dict[str, float], autopilot: str, expected: float | str) -> None:
    found = capacity(config, params, autopilot)
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
        "fit a current sensor (BATT_MONITOR 4) or remove energy:"
    )


def test_no_remaining_charge_estimate_is_refused() -> None:
    why = unknown_reading(status(pct=None), Battery(12.0, 1.0, None, 0.0), {})
    assert why is not None and "battery_remaining -1" in why


def test_px4_sih_measures_no_current_its_energy_is_read_from_the_remaining_charge() -> None:
    """PX4 SIH's BATTERY_STATUS as recorded (current_battery -100, current_consumed 0, energy_consumed -1, remaining 99)."""
    sih = BatteryStatus(0.0, None, 99, 1187, 16.2, -1.0, 1, 0.0)
    assert unknown_reading(sih, None, {}) is None and not counts_current(sih)
    assert counts_current(status(mah=120.0, wh=1.4))
