"""Consumption learned on the way: energy per metre moved, per second held and per metre dived or climbed (a sub), a filterpy
Kalman filter with its uncertainty.

State ``x = [Wh per m, Wh per s held, Wh per vertical m]``; each measurement is the energy the battery reports drawn over a
window (``z = dWh``) against the metres moved, the seconds held and the metres of depth changed in it (``H = [dm, ds, dz]``):
held is armed and barely moving (hover, loiter, station keeping, a stop), whose cost the distance does not count. A sub's
dives and climbs are costed by the metre, not the second: at the autopilot's vertical speed the vertical thrusters work
against the water's drag, so a metre of depth costs the same whatever the mode's speed limit (ArduSub's GUIDED and AUTO
WPNAV_SPEED_UP 250 / WPNAV_SPEED_DN 150 cm/s, AC_WPNav.cpp; SURFACE at most PILOT_SPEED_UP 100 cm/s, mode_surface.cpp and
ArduSub/Parameters.h; the simulated sub 0.5 m/s), while its seconds would be costed at the held rate, a sixth of a dive's
on the simulated sub. Windows with depth changes and little way made teach this rate apart from the other two. The
state walks (process noise, a few percent of the seed per window) so that a change of conditions (a
headwind, a current, a heavier load) shows within a few legs; a window is gated at 3 sigma before
the update (LIBRARY-NOTES: filterpy computes its Mahalanobis distance after the update) and a run of
rejections re-opens the uncertainty, so a real change is taken, not locked out.

Seeds per kind (``energy.wh_per_km`` / ``wh_per_min`` replace them), from the simulated packs' loads
(:mod:`executive.sim.battery`) and typical small vehicles: a rover or boat 10 Wh/km moving (its electronics
included) + 0.5 Wh/min held, a VTOL 5 Wh/km in wing-borne cruise + 16 Wh/min hovering on its lift motors. A sub
(a vectored ROV/AUV frame such as ArduSub's, the BlueROV2 class): 100 Wh/km + 1 Wh/min + 0.2 Wh per metre of depth: the
simulated 4S pack at ~15.5 V draws 4 A armed at rest (1 Wh/min), 18 A cruising at 0.8 m/s (99 Wh/km) and 24 A diving or
climbing at 0.5 m/s (0.21 Wh/m). The seed is trusted to within half its value (1 sigma).
"""

from __future__ import annotations

import math

import numpy as np

from executive.sensing.heading import kalman_filter_class

#: kind -> (Wh per km, Wh per minute), the seeds.
SEEDS: dict[str, tuple[float, float]] = {"rover": (10.0, 0.5), "boat": (10.0, 0.5), "sub": (100.0, 1.0), "vtol": (5.0, 16.0)}
#: kind -> Wh per metre of depth changed, the seed (a sub's only: the others' climbs are in their seconds held).
VERTICAL_SEEDS: dict[str, float] = {"sub": 0.2}
#: Slower than this (ground speed, m/s) the vehicle is held: its seconds cost, not its metres.
HELD_BELOW_M_S = 0.3

_SEED_SIGMA = 0.5  # of the seed, 1 sigma
_WALK = 0.15  # of the seed per window, 1 sigma: a change shows within a few windows
_GATE = 9.0  # chi-square, 3 sigma
_REJECTIONS_TO_REOPEN = 2


class ConsumptionModel:
    """Wh per metre, per second held and per vertical metre, with their covariance; :meth:`update` with each window's figures."""

    def __init__(self, wh_per_km: float, wh_per_min: float, wh_per_vertical_m: float = 0.0) -> None:
        self.seed = np.array([wh_per_km / 1000.0, wh_per_min / 60.0, wh_per_vertical_m])
        kf = self._kf = kalman_filter_class()(dim_x=3, dim_z=1)
        kf.x = self.seed.reshape(3, 1).copy()
        kf.P = np.diag((self.seed * _SEED_SIGMA + 1e-9) ** 2)
        kf.F = np.eye(3)
        kf.Q = np.diag((self.seed * _WALK + 1e-12) ** 2)
        self.windows = 0
        self.rejected = 0
        self._rejected_run = 0
        self._needs: dict[tuple[float, float, float], tuple[float, float]] = {}  # asked since the last window (a tick asks again)

    @property
    def wh_per_m(self) -> float:
        return float(self._kf.x[0, 0])

    @property
    def wh_per_s(self) -> float:
        return float(self._kf.x[1, 0])

    @property
    def wh_per_vertical_m(self) -> float:
        return float(self._kf.x[2, 0])

    def need(self, metres: float, seconds: float, vertical_m: float = 0.0) -> tuple[float, float]:
        """The energy ``metres`` moved, ``seconds`` held and ``vertical_m`` dived or climbed take, Wh, and its 1-sigma uncertainty."""
        key = (metres, seconds, vertical_m)
        known = self._needs.get(key)
        if known is not None:
            return known
        h = np.array([[metres, seconds, vertical_m]])
        mean = (h @ self._kf.x).item()
        need = max(0.0, mean), math.sqrt(max(0.0, (h @ self._kf.P @ h.T).item()))
        if len(self._needs) >= 16:
            self._needs.clear()
        self._needs[key] = need
        return need

    def update(self, drawn_wh: float, metres: float, seconds: float, noise_wh: float, vertical_m: float = 0.0) -> bool:
        """One window: ``drawn_wh`` over ``metres`` moved, ``seconds`` held and ``vertical_m`` dived or climbed, measured to
        ``noise_wh`` (1 sigma); whether it was taken."""
        kf = self._kf
        self._needs.clear()
        kf.predict()
        h = np.array([[metres, seconds, vertical_m]])
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
