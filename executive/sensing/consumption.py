"""Consumption learned on the way: energy per metre moved and per second held, a filterpy Kalman filter with its uncertainty.

State ``x = [Wh per m, Wh per s held]``; each measurement is the energy the battery reports drawn over a
window (``z = dWh``) against the metres moved and the seconds held in it (``H = [dm, ds]``): held is armed and
barely moving (hover, loiter, station keeping, a stop), whose cost the distance does not count. The
state walks (process noise, a few percent of the seed per window) so that a change of conditions (a
headwind, a current, a heavier load) shows within a few legs; a window is gated at 3 sigma before
the update (LIBRARY-NOTES: filterpy computes its Mahalanobis distance after the update) and a run of
rejections re-opens the uncertainty, so a real change is taken, not locked out.

Seeds per kind (``energy.wh_per_km`` / ``wh_per_min`` replace them), from the simulated packs' loads
(:mod:`executive.sim.battery`) and typical small vehicles: a rover or boat 10 Wh/km moving (its electronics
included) + 0.5 Wh/min held, a sub 20 Wh/km + 1 Wh/min, a VTOL 5 Wh/km in wing-borne cruise + 16 Wh/min
hovering on its lift motors. The seed is trusted to within half its value (1 sigma).
"""

from __future__ import annotations

import math

import numpy as np

from executive.sensing.heading import kalman_filter_class

#: kind -> (Wh per km, Wh per minute), the seeds.
SEEDS: dict[str, tuple[float, float]] = {"rover": (10.0, 0.5), "boat": (10.0, 0.5), "sub": (20.0, 1.0), "vtol": (5.0, 16.0)}
#: Slower than this (ground speed, m/s) the vehicle is held: its seconds cost, not its metres.
HELD_BELOW_M_S = 0.3

_SEED_SIGMA = 0.5  # of the seed, 1 sigma
_WALK = 0.15  # of the seed per window, 1 sigma: a change shows within a few windows
_GATE = 9.0  # chi-square, 3 sigma
_REJECTIONS_TO_REOPEN = 2


class ConsumptionModel:
    """Wh per metre and per second, with their covariance; :meth:`update` with each window's figures."""

    def __init__(self, wh_per_km: float, wh_per_min: float) -> None:
        self.seed = np.array([wh_per_km / 1000.0, wh_per_min / 60.0])
        kf = self._kf = kalman_filter_class()(dim_x=2, dim_z=1)
        kf.x = self.seed.reshape(2, 1).copy()
        kf.P = np.diag((self.seed * _SEED_SIGMA + 1e-9) ** 2)
        kf.F = np.eye(2)
        kf.Q = np.diag((self.seed * _WALK + 1e-12) ** 2)
        self.windows = 0
        self.rejected = 0
        self._rejected_run = 0

    @property
    def wh_per_m(self) -> float:
        return float(self._kf.x[0, 0])

    @property
    def wh_per_s(self) -> float:
        return float(self._kf.x[1, 0])

    def need(self, metres: float, seconds: float) -> tuple[float, float]:
        """The energy ``metres`` moved and ``seconds`` held take, Wh, and its 1-sigma uncertainty."""
        h = np.array([[metres, seconds]])
        mean = (h @ self._kf.x).item()
        return max(0.0, mean), math.sqrt(max(0.0, (h @ self._kf.P @ h.T).item()))

    def update(self, drawn_wh: float, metres: float, seconds: float, noise_wh: float) -> bool:
        """One window: ``drawn_wh`` over ``metres`` moved and ``seconds`` held, measured to ``noise_wh`` (1 sigma); whether it was taken."""
        kf = self._kf
        kf.predict()
        h = np.array([[metres, seconds]])
        r = np.array([[noise_wh**2]])
        innovation = drawn_wh - (h @ kf.x).item()
        s = (h @ kf.P @ h.T + r).item()
        self.windows += 1
        if innovation * innovation / s > _GATE:
            self.rejected += 1
            self._rejected_run += 1
            if self._rejected_run < _REJECTIONS_TO_REOPEN:
                return False
            kf.P = kf.P + np.diag((self.seed * _SEED_SIGMA) ** 2)  # conditions changed: trust the seed's spread again
        self._rejected_run = 0
        kf.update(np.array([[drawn_wh]]), R=r, H=h)
        kf.x = np.maximum(kf.x, 0.0)
        return True
