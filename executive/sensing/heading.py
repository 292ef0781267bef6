"""The heading sanity filter: does the compass tell the truth?

The thesis rover's compass read ~20° off and swung by up to 45° when the motors started, so the
track snaked. This filter catches both, from what the MAVLink reader already writes:

- a Kalman filter of heading and yaw rate, *in the compass's frame*, fed by the compass
  (ATTITUDE yaw), the gyro (ATTITUDE yawspeed) and, while moving, the GPS course over ground
  (atan2(ve, vn)) shifted by the estimated compass bias. Each compass and course reading is gated
  on its wrapped innovation (y²/S against a chi-square gate) *before* the update; a glitch is
  rejected and the heading does not jump. After N consecutive rejections that agree with each
  other (the filter, not the compass, is wrong: a glitched first reading, a step) it re-initialises
  from the compass;
- a slow filter of the wrapped compass - course difference, sampled only while driving straight
  (low gyro rate for a while, above a minimum speed) with a compass the gate accepted: the compass
  bias. It averages quickly at first, then follows with a time constant of about a minute; a
  bias sample far from the estimate is rejected, and when the mean of the last N samples is outside
  the gate the estimate re-initialises to it (the bias changed for good, e.g. when the motors started);
- the verdict: /heading/ok is False while the compass is being rejected persistently (a share of
  its readings over a window: the 45° swings) or the bias exceeds a threshold too far off to trust
  its correction (30°, with hysteresis); True once the bias was judged (enough straight driving) and
  neither holds. A steady bias below the threshold (the seed's 20°) is measured and compensated:
  taken off /heading/deg and reported (logged, /heading/bias_deg), the compass ok; None before (a stationary vehicle cannot
  judge its compass against its course) or when the attitude is stale.

/heading/deg is the filter's heading with the bias taken off once judged (before, the compass's own
heading, filtered): the best guess of the true heading. /heading/bias_deg is the estimate once judged
(None before). Course over ground differs from heading by any crab angle (a boat in a current, a
skidding track), which this reads as bias. The runtime calls :meth:`HeadingFilter.service` once per
tick, right after the MAVLink reader drains.
"""

from __future__ import annotations

import gc
import importlib
import importlib.util
import logging
import math
import sys
import threading
import types
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import Attitude, GlobalPosition

log = logging.getLogger(__name__)

_HEADING, _RATE = 0, 1  # the state's components (and the row of H that measures each)


class HeadingKalman:
    """Heading and turn rate in filterpy's ``KalmanFilter`` (constant-rate model, discrete white-noise acceleration).

    The state stays in filterpy's arrays, changed in place (building arrays each step cost more than
    the filter's own arithmetic); the caller reads plain floats and wraps the heading itself (filterpy
    has no angle hook). Its import still takes numpy and scipy.linalg (~0.5 s of CPU): :func:`load_filterpy`
    runs in the background so the first tick does not wait.
    """

    def __init__(self) -> None:
        kf = self._kf = kalman_filter_class()(dim_x=2, dim_z=1)
        kf.inv = _inverse_1x1  # filterpy's hook for the innovation's inverse: S is 1x1 here
        self._r = kf.R  # the measurement's variance, set before each update: filterpy reads kf.R when update is given no R

    @property
    def heading(self) -> float:
        return float(self._kf.x[0, 0])

    @heading.setter
    def heading(self, deg: float) -> None:
        self._kf.x[0, 0] = deg

    @property
    def rate(self) -> float:
        return float(self._kf.x[1, 0])

    @property
    def heading_var(self) -> float:
        return float(self._kf.P[0, 0])

    def reset(self, heading: float, rate: float, heading_var: float, rate_var: float) -> None:
        """Start again from these readings, uncorrelated."""
        kf = self._kf
        kf.x[0, 0], kf.x[1, 0] = heading, rate
        kf.P[:] = ((heading_var, 0.0), (0.0, rate_var))

    def predict(self, dt: float, var: float) -> None:
        kf = self._kf
        kf.F[0, 1] = dt
        # filterpy's Q_discrete_white_noise(dim=2, dt, var), written out: its scipy block_diag costs more than the rest of the step
        q = kf.Q
        q[0, 0], q[0, 1], q[1, 1] = dt**4 / 4.0 * var, dt**3 / 2.0 * var, dt**2 * var
        q[1, 0] = q[0, 1]
        kf.predict()

    def widen_heading(self, var: float) -> None:
        """Add ``var`` to the heading's variance (process noise the constant-rate model cannot know of)."""
        self._kf.P[0, 0] += var

    def update(self, z: float, r: float, i: int) -> None:
        """Take a measurement ``z`` of state component ``i`` whose variance is ``r``."""
        self._r[0, 0] = r
        # z as a float: filterpy keeps a deepcopy of it (kalman_filter.py update), ten times dearer for an array;
        # with H given it is not reshaped, and z - Hx is the same 1x1 array of the same number. R in place rather than
        # given: a given R is tested with numpy's isscalar (an ABC check) at each update; the arithmetic is the same
        self._kf.update(z, H=_H[i])


def _inverse_1x1(s: np.ndarray) -> np.ndarray:
    return 1.0 / s


_H = (np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]]))
_filterpy_ready = threading.Event()


def import_long_lived(name: str | Callable[[], object]) -> None:
    """Import a module whose objects live as long as the process, without the collector's passes, then freeze them out of later ones.

    ``name`` is the module's, or a function that loads it.

    filterpy's import made ~40k objects: while it ran in the background the collector's full passes over them held
    the interpreter 40-50 ms each, under a running loop's ticks.
    """
    collecting = gc.isenabled()
    gc.disable()
    try:
        if callable(name):
            name()
        else:
            importlib.import_module(name)
    finally:
        gc.freeze()
        if collecting:
            gc.enable()


KALMAN_FILTER_MODULE = "filterpy.kalman.kalman_filter"


class _LogpdfOnFirstUse(types.ModuleType):
    """Stands in for ``filterpy.stats`` while filterpy's Kalman filter module loads: its ``logpdf`` imports the real one when first called."""

    @staticmethod
    def logpdf(*args: object, **kwargs: object) -> object:
        return importlib.import_module("filterpy.stats").logpdf(*args, **kwargs)


def _module_from_file(name: str, path: Path) -> types.ModuleType:
    """The module ``name`` run from ``path``, not entered in ``sys.modules``."""
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"no module named {name!r}", name=name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _load_kalman_filter_module() -> None:
    """Load filterpy's ``kalman_filter`` module (and ``filterpy.common``, which it uses) without the rest of filterpy.

    ``import filterpy`` (2.0) imports every part of the package (EKF, UKF, IMM, H-infinity, Monte
    Carlo...) and, through ``filterpy.stats``, scipy.stats: 1.5 s of CPU on a desktop core, several
    seconds on a companion computer, at every start, for one class that needs numpy. The module
    takes only ``logpdf`` from ``filterpy.stats`` (for ``KalmanFilter.log_likelihood``, which the
    heading filter never reads) and ``pretty_str`` and ``reshape_z`` from ``filterpy.common``, whose
    ``__init__`` also imports its discretization helpers and so scipy.linalg (with numpy's f2py:
    ~0.2 s of CPU). So it loads from its file under a bare ``filterpy`` package (the real folder,
    without its ``__init__``), a ``filterpy.stats`` whose ``logpdf`` imports the real one on first
    use, and ``filterpy.common``'s ``helpers`` file (numpy only) as ``filterpy.common``. The stand-ins
    leave ``sys.modules`` afterwards: a later ``import filterpy`` (a user's plugin) runs the real
    package, which reuses this very ``kalman_filter`` module.
    """
    package_spec = importlib.util.find_spec("filterpy")  # a top-level name: found, not imported
    if package_spec is None or not package_spec.submodule_search_locations:
        raise ImportError("no module named 'filterpy'", name="filterpy")
    folder = Path(next(iter(package_spec.submodule_search_locations)))
    bare = types.ModuleType("filterpy")
    bare.__path__ = [str(folder)]
    stand_ins = {"filterpy": bare, "filterpy.stats": _LogpdfOnFirstUse("filterpy.stats")}
    if "filterpy.common" not in sys.modules:
        stand_ins["filterpy.common"] = _module_from_file("filterpy.common.helpers", folder / "common" / "helpers.py")
    stand_ins = {name: module for name, module in stand_ins.items() if name not in sys.modules}
    sys.modules.update(stand_ins)
    try:
        kalman_filter = _module_from_file(KALMAN_FILTER_MODULE, folder / "kalman" / "kalman_filter.py")
    finally:
        for name, stand_in in stand_ins.items():
            if sys.modules.get(name) is stand_in:
                del sys.modules[name]
    sys.modules[KALMAN_FILTER_MODULE] = kalman_filter


def kalman_filter_class() -> type:
    """filterpy's ``KalmanFilter`` (loaded as :func:`_load_kalman_filter_module` says, once)."""
    if KALMAN_FILTER_MODULE not in sys.modules:
        _load_kalman_filter_module()
    return sys.modules[KALMAN_FILTER_MODULE].KalmanFilter


def load_filterpy() -> None:
    """Import filterpy's Kalman filter once, in a thread of its own; :class:`HeadingFilter` judges nothing until it is in."""

    def load() -> None:
        import_long_lived(_load_kalman_filter_module)
        _filterpy_ready.set()

    if not _filterpy_ready.is_set() and not any(t.name == "load filterpy" for t in threading.enumerate()):
        threading.Thread(target=load, name="load filterpy", daemon=True).start()


def filterpy_ready() -> bool:
    """filterpy's Kalman filter is loaded (:func:`load_filterpy`): a filter can be made without waiting."""
    return _filterpy_ready.is_set()


def wait_for_filterpy(timeout_s: float = 30.0) -> bool:
    """Block until filterpy is loaded (tools and tests that want a judging filter from the first reading)."""
    load_filterpy()
    return _filterpy_ready.wait(timeout_s)


def _measured_at(reading: Attitude | GlobalPosition) -> float:
    """When the autopilot measured ``reading`` (its boot clock) if it said, else when it arrived."""
    return reading.boot_s if reading.boot_s is not None else reading.time


def wrap180(deg: float) -> float:
    """An angle in [-180, 180)."""
    return (deg + 180.0) % 360.0 - 180.0


def circular_mean(degrees: list[float]) -> float:
    """The mean direction of angles, in [-180, 180) (359° and 1° average to 0°, not 180°)."""
    s = sum(math.sin(math.radians(d)) for d in degrees)
    c = sum(math.cos(math.radians(d)) for d in degrees)
    return wrap180(math.degrees(math.atan2(s, c)))


@dataclass(frozen=True)
class HeadingFilterConfig:
    """The filter's numbers; the defaults suit a rover or a boat at 1-4 m/s with 5-10 Hz ATTITUDE."""

    compass_sigma_deg: float = 3.0  # compass noise
    gyro_sigma_deg_s: float = 1.0  # gyro (ATTITUDE yawspeed) noise
    yaw_accel_sigma_deg_s2: float = 30.0  # process noise: how hard the vehicle can change its turn rate
    gps_velocity_sigma_m_s: float = 0.15  # GPS velocity noise; course noise is atan(sigma / speed)
    timing_sigma_s: float = 0.05  # readings are stamped at reception: at a turn rate r this adds r * sigma
    gate: float = 9.0  # chi-square gate on y²/S (9 = 3 sigma, one degree of freedom)
    reinit_after: int = 10  # consecutive compass rejections that re-initialise the filter ...
    reinit_spread_deg: float = 10.0  # ... if their innovations agree within this (a lock-out or a step, not swings)
    min_course_speed_m_s: float = 0.5  # below this the course over ground means nothing
    straight_rate_deg_s: float = 3.0  # driving straight: |gyro rate| below this ...
    straight_settle_s: float = 1.0  # ... for this long (the course lags the heading out of a turn)
    bias_prior_sigma_deg: float = 30.0  # bias uncertainty before the first sample
    bias_drift_deg_per_sqrt_s: float = 0.05  # how fast the bias may wander: a settled estimate follows in ~1 min
    bias_reinit_window: int = 10  # the bias re-initialises when the mean of this many recent samples ...
    bias_change_gate: float = 16.0  # ... is this far out (chi-square; 4 sigma: tested at every sample, so stricter than the gate)
    bias_judged_after_s: float = 5.0  # straight driving needed before the bias is judged ...
    bias_judged_sigma_deg: float = 2.0  # ... and the estimate's uncertainty below this
    # A judged bias up to this is measured and compensated (the published heading has it taken off; the compass is ok):
    # the seed's ~20° misalignment. Flagging it instead held a vehicle still, where the bias cannot be measured again.
    bias_threshold_deg: float = 30.0  # |bias| above this: the compass is not ok (too far off to trust its correction)
    bias_clear_deg: float = 28.0  # ... until it is back below this
    bias_reported_deg: float = 3.0  # a compensated bias above this is reported (logged once, and again after each change)
    rejection_window_s: float = 5.0  # the compass's recent readings ...
    rejection_flag_share: float = 0.2  # ... of which this share rejected: not ok
    rejection_clear_share: float = 0.05  # ... until the share is back below this
    rejection_min_count: int = 3  # ... and at least this many (one or two glitches are not persistent)
    stale_after_s: float = 2.0  # an attitude older than this: no heading, no verdict; the filter restarts


class HeadingFilter:
    """Writes the /heading keys (deg, ok, bias_deg, reason, last_update); call :meth:`service` once per tick after the MAVLink reader drains."""

    def __init__(self, clock: Clock, config: HeadingFilterConfig | None = None) -> None:
        self.config = config or HeadingFilterConfig()
        self._clock = clock
        self._in = blackboard.reader("heading filter in", ["/vehicle/attitude", "/vehicle/position"])
        self._out = blackboard.writer("heading filter", blackboard.keys_under("/heading/"))
        self._kf: HeadingKalman = None  # type: ignore[assignment]  # made on the first tick after filterpy is loaded
        load_filterpy()
        self._t: float | None = None  # time of the filter's state; None = not initialised
        self._attitude: Attitude | None = None
        self._position: GlobalPosition | None = None
        self._compass: tuple[float, float, float] | None = None  # (time, yaw, rate) of the last accepted compass reading
        self._gyro: tuple[float, float] | None = None  # (time, rate) of the last gyro reading
        self._straight_since: float | None = None
        self._rejected_run: list[float] = []  # innovations of consecutive rejected compass readings
        self._verdicts: deque[tuple[float, bool]] = deque()  # (time, rejected) of recent compass readings
        self._rejections = 0  # how many of them were rejected (kept with the deque: no sum over it every tick)
        self._rejecting = False
        self._last_rejection = -math.inf
        # the bias filter (scalar Kalman filter of compass - course)
        self._bias = 0.0
        self._bias_var = self.config.bias_prior_sigma_deg**2
        self._bias_t: float | None = None
        self._bias_straight_s = 0.0
        self._bias_window: deque[tuple[float, float]] = deque(maxlen=self.config.bias_reinit_window)  # recent (sample, variance)
        self._bias_flagged = False
        self._bias_reported: float | None = None  # the compensated bias last logged
        #: Counters, for diagnostics and tests.
        self.compass_accepted = self.compass_rejected = self.course_accepted = self.course_rejected = 0
        self.bias_samples = self.bias_rejected = self.reinits = self.bias_reinits = 0
        #: The wrapped innovation of the latest compass reading, degrees.
        self.last_compass_innovation_deg: float | None = None

    # -- what it concluded ---------------------------------------------------------------------
    @property
    def heading_deg(self) -> float | None:
        """The filtered heading, less the bias once judged, [0, 360); None before the first compass reading."""
        if self._t is None:
            return None
        return (self._kf.heading - (self._bias if self.bias_judged else 0.0)) % 360.0

    @property
    def bias_judged(self) -> bool:
        """Enough straight driving to trust the bias estimate."""
        cfg = self.config
        return self._bias_straight_s >= cfg.bias_judged_after_s and self._bias_var <= cfg.bias_judged_sigma_deg**2

    @property
    def rejected_share(self) -> float:
        """The share of the compass readings in the window that the gate rejected."""
        return self._rejections / len(self._verdicts) if self._verdicts else 0.0

    @property
    def reason(self) -> str:
        """Why the compass is not ok; empty when it is (or is not judged)."""
        if self._rejecting:
            return f"compass rejected in {self.rejected_share:.0%} of its readings over {self.config.rejection_window_s:g} s"
        if self._bias_flagged:
            return f"compass reads {self._bias:+.1f}° off the course over ground"
        return ""

    # -- each tick -----------------------------------------------------------------------------
    def service(self) -> None:
        """Take the new attitude and position readings (in time order), then publish the verdict."""
        if self._kf is None:
            if not _filterpy_ready.is_set():  # still loading: nothing judged yet (/heading/ok stays None)
                self._publish(self._clock.now())
                return
            self._kf = HeadingKalman()
        attitude: Attitude | None = self._in.get("/vehicle/attitude")
        position: GlobalPosition | None = self._in.get("/vehicle/position")
        # The same object at most ticks (a reading comes every few ticks): known without comparing its fields. A new one
        # received at another time differs in that field, so only one received at the same time has its fields compared.
        last_attitude, last_position = self._attitude, self._position
        if (
            attitude is None
            or attitude is last_attitude
            or (last_attitude is not None and attitude.time == last_attitude.time and attitude == last_attitude)
        ):
            attitude = None  # nothing new
        if (
            position is None
            or position is last_position
            or (last_position is not None and position.time == last_position.time and position == last_position)
        ):
            position = None
        if attitude is not None:
            self._attitude = attitude
        if position is not None:
            self._position = position
        # The filter runs on when the autopilot measured (its boot clock): reception times jitter with the link,
        # and a turn's rate times that jitter reads as a compass error.
        if attitude is not None and position is not None and _measured_at(position) < _measured_at(attitude):
            self._on_position(position, _measured_at(position))
            position = None
        if attitude is not None:
            self._on_attitude(attitude, _measured_at(attitude))
        if position is not None:
            self._on_position(position, _measured_at(position))
        self._publish(self._clock.now())

    # -- the heading filter --------------------------------------------------------------------
    def _start(self, yaw_deg: float, rate_deg_s: float, t: float) -> None:
        cfg = self.config
        self._kf.reset(yaw_deg % 360.0, rate_deg_s, cfg.compass_sigma_deg**2, cfg.gyro_sigma_deg_s**2)
        self._t = t
        self._gyro = (t, rate_deg_s)
        self._rejected_run.clear()

    def _predict_to(self, t: float) -> None:
        assert self._t is not None
        dt = t - self._t
        if dt > 0.0:
            self._kf.predict(dt, self.config.yaw_accel_sigma_deg_s2**2)
            self._kf.heading %= 360.0
            self._t = t

    def _gated_update(self, z_deg: float, r_var: float) -> tuple[bool, float]:
        """Update the heading with ``z_deg`` unless its wrapped innovation fails the gate; returns (accepted, innovation)."""
        x = self._kf.heading
        y = wrap180(z_deg - x)
        s = self._kf.heading_var + r_var
        if y * y / s > self.config.gate:
            return False, y
        self._kf.update(x + y, r_var, _HEADING)  # z chosen so the filter's innovation is y
        self._kf.heading %= 360.0
        return True, y

    def _on_attitude(self, a: Attitude, t: float) -> None:
        cfg = self.config
        straight = abs(a.yaw_rate_deg_s) <= cfg.straight_rate_deg_s
        self._straight_since = (self._straight_since if self._straight_since is not None else t) if straight else None
        if self._t is None or t - self._t > cfg.stale_after_s or t < self._t - cfg.stale_after_s:  # a gap, or a reboot
            self._start(a.yaw_deg, a.yaw_rate_deg_s, t)
            self._compass = (t, a.yaw_deg, a.yaw_rate_deg_s)
            return
        self._predict_to(t)
        if self._gyro is not None:
            # The turn rate changed by dr somewhere in the dt since the last reading (a pivot starts in a few
            # ms): the heading turned by anything between the two rates times dt. Uniform over dt, that is a
            # variance of (dr dt)^2 / 12 the constant-rate model does not carry; without it a pivot seen at
            # 4 Hz leaves the filter ~10° off the compass and too sure of itself to follow it.
            gyro_dt, dr = t - self._gyro[0], a.yaw_rate_deg_s - self._gyro[1]
            self._kf.widen_heading((dr * gyro_dt) ** 2 / 12.0)
        self._gyro = (t, a.yaw_rate_deg_s)
        self._kf.update(a.yaw_rate_deg_s, cfg.gyro_sigma_deg_s**2, _RATE)
        r_var = cfg.compass_sigma_deg**2 + (a.yaw_rate_deg_s * cfg.timing_sigma_s) ** 2
        accepted, y = self._gated_update(a.yaw_deg, r_var)
        self.last_compass_innovation_deg = y
        self._verdicts.append((t, not accepted))
        self._rejections += not accepted
        if accepted:
            self.compass_accepted += 1
            self._rejected_run.clear()
            self._compass = (t, a.yaw_deg, a.yaw_rate_deg_s)
            return
        self.compass_rejected += 1
        self._last_rejection = t
        self._rejected_run.append(y)
        run = self._rejected_run
        if len(run) >= cfg.reinit_after:
            centre = circular_mean(run)
            if max(abs(wrap180(v - centre)) for v in run) <= cfg.reinit_spread_deg:
                self.reinits += 1
                self._start(a.yaw_deg, a.yaw_rate_deg_s, t)
                self._compass = (t, a.yaw_deg, a.yaw_rate_deg_s)
            else:
                del run[0]

    def _on_position(self, p: GlobalPosition, t: float) -> None:
        cfg = self.config
        speed = p.ground_speed_m_s
        if self._t is None or speed < cfg.min_course_speed_m_s or t - self._t > cfg.stale_after_s:
            return
        course = math.degrees(math.atan2(p.ve_m_s, p.vn_m_s)) % 360.0
        rate = self._kf.rate
        cog_var = math.degrees(math.atan2(cfg.gps_velocity_sigma_m_s, speed)) ** 2 + (rate * cfg.timing_sigma_s) ** 2
        self._predict_to(t)
        if self.bias_judged and abs(wrap180(course + self._bias - self._kf.heading)) > 120.0:
            return  # driving backwards (a tracked vehicle can): the course is the heading's opposite
        accepted, _ = self._gated_update(course + self._bias, cog_var + self._bias_var)
        if accepted:
            self.course_accepted += 1
        else:
            self.course_rejected += 1
        compass = self._compass
        if self._straight_since is None or t - self._straight_since < cfg.straight_settle_s:
            return
        if compass is None or t - compass[0] > 0.5:  # no accepted compass reading to compare with
            return
        if self._rejecting or t - self._last_rejection < cfg.straight_settle_s:  # readings between glitches are suspect too
            return
        _, yaw, yaw_rate = compass
        self._bias_sample(t, wrap180(yaw + yaw_rate * (t - compass[0]) - course), cfg.compass_sigma_deg**2 + cog_var)

    # -- the bias filter -----------------------------------------------------------------------
    def _bias_sample(self, t: float, d: float, d_var: float) -> None:
        cfg = self.config
        dt = 0.0 if self._bias_t is None else min(max(t - self._bias_t, 0.0), 1.0)
        self._bias_t = t
        self._bias_var += cfg.bias_drift_deg_per_sqrt_s**2 * dt
        self._bias_window.append((d, d_var))
        y = wrap180(d - self._bias)
        if self.bias_samples and y * y / (self._bias_var + d_var) > cfg.gate:
            self.bias_rejected += 1
        else:
            self.bias_samples += 1
            self._bias_straight_s += dt
            gain = self._bias_var / (self._bias_var + d_var)
            self._bias = wrap180(self._bias + gain * y)
            self._bias_var *= 1.0 - gain
        # A bias that changed for good (the motors started): the mean of the recent samples, whose noise is
        # sqrt(n) times smaller than one sample's, is outside the gate. A lone glitch moves the mean too little.
        window = self._bias_window
        if len(window) == window.maxlen:
            mean = circular_mean([d for d, _ in window])
            mean_var = sum(v for _, v in window) / len(window) ** 2
            if wrap180(mean - self._bias) ** 2 / (self._bias_var + mean_var) > cfg.bias_change_gate:
                self.bias_reinits += 1
                self._bias, self._bias_var = mean, mean_var
                window.clear()

    # -- the verdict ---------------------------------------------------------------------------
    def _report_bias(self) -> None:
        """Log a compensated bias once measured, and again when it has changed by the report threshold."""
        cfg = self.config
        if self._bias_flagged or abs(self._bias) < cfg.bias_reported_deg:
            return
        if self._bias_reported is None or abs(wrap180(self._bias - self._bias_reported)) >= cfg.bias_reported_deg:
            self._bias_reported = self._bias
            log.warning("compass bias %+.1f° measured against the course over ground: compensated", self._bias)

    def _publish(self, now: float) -> None:
        cfg = self.config
        latest = self._verdicts[-1][0] if self._verdicts else now  # verdicts are stamped with measurement time (the autopilot's clock)
        while self._verdicts and self._verdicts[0][0] < latest - cfg.rejection_window_s:
            self._rejections -= self._verdicts.popleft()[1]
        share = self.rejected_share
        if share >= cfg.rejection_flag_share and self._rejections >= cfg.rejection_min_count:
            self._rejecting = True
        elif share < cfg.rejection_clear_share:
            self._rejecting = False
        judged = self.bias_judged
        if judged:
            limit = cfg.bias_clear_deg if self._bias_flagged else cfg.bias_threshold_deg
            self._bias_flagged = abs(self._bias) > limit
            self._report_bias()
        stale = self._attitude is None or now - self._attitude.time > cfg.stale_after_s
        ok: bool | None = None
        if not stale:
            ok = False if self._rejecting or self._bias_flagged else True if judged else None
        # heading_deg, with the verdict's ``judged``: the same bias taken off (or none), not judged again
        self._out.set("/heading/deg", None if stale or self._t is None else (self._kf.heading - (self._bias if judged else 0.0)) % 360.0)
        self._out.set("/heading/ok", ok)
        self._out.set("/heading/bias_deg", self._bias if judged else None)
        self._out.set("/heading/reason", self.reason if ok is False else "")
        self._out.set("/heading/last_update", None if self._attitude is None else self._attitude.time)
