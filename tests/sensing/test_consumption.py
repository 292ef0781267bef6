"""The consumption model: learns Wh per metre and per second from the battery's windows, with its uncertainty."""

from __future__ import annotations

import random

from executive.sensing.consumption import ConsumptionModel
from executive.sensing.heading import wait_for_filterpy


def drive(model: ConsumptionModel, wh_per_km: float, wh_per_min: float, windows: int, rng: random.Random, noise: float = 0.1) -> None:
    """Windows of 10 s at 2 m/s, the drawn energy noisy by ``noise`` of itself."""
    for _ in range(windows):
        drawn = (20.0 * wh_per_km / 1000.0 + 10.0 * wh_per_min / 60.0) * (1.0 + rng.uniform(-noise, noise))
        model.update(drawn, 20.0, 10.0, noise_wh=0.05 + 0.1 * drawn)


def test_it_starts_from_its_seed_with_half_its_value_as_uncertainty() -> None:
    assert wait_for_filterpy()
    model = ConsumptionModel(6.0, 0.5)
    need, sigma = model.need(1000.0, 500.0)
    assert round(need, 2) == round(6.0 + 0.5 * 500 / 60, 2)
    assert 0.3 * need < sigma < 0.6 * need


def test_a_noisy_current_is_learned_and_the_uncertainty_shrinks() -> None:
    assert wait_for_filterpy()
    model = ConsumptionModel(6.0, 0.5)
    _, sigma0 = model.need(1000.0, 500.0)
    drive(model, 9.0, 0.8, 30, random.Random(1))
    need, sigma = model.need(1000.0, 500.0)
    true = 9.0 + 0.8 * 500 / 60
    assert abs(need - true) < 0.1 * true and sigma < 0.6 * sigma0  # it keeps walking: a change can still show


def test_a_headwind_shows_within_a_few_windows() -> None:
    """Twice the consumption from one window on: within 6 windows (a minute, a leg or two) the estimate is within 20 %."""
    assert wait_for_filterpy()
    rng = random.Random(2)
    model = ConsumptionModel(6.0, 0.5)
    drive(model, 6.0, 0.5, 20, rng)
    drive(model, 12.0, 1.0, 6, rng)
    need, _ = model.need(20.0, 10.0)
    true = 20.0 * 12.0 / 1000.0 + 10.0 * 1.0 / 60.0
    assert abs(need - true) < 0.2 * true
