"""Will the rest of the route and the way home fit the battery? The estimate, re-made every battery report.

:class:`EnergyWatch` is a reader service (run each tick after the MAVLink reader, as the heading
filter is): it reads the battery (:mod:`executive.sensing.battery_energy`), learns the consumption
(:class:`~executive.sensing.consumption.ConsumptionModel`) from what the battery reports drawn while
armed, and writes ``/energy/estimate``: what is left above the reserve, what the rest of the route
and the way home need (with the model's 1-sigma uncertainty), and the margin. The energy guard
(:class:`~executive.behaviours.energy.EnergyEnough`) judges it; the status line, ``ctl status``, the
ground station and the journal show it. Each leg's estimate (and each move of the margin by more
than a twentieth of the capacity) is logged to the journal, so ``report`` tells where the energy went.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

from executive import blackboard, geo
from executive.clock import Clock
from executive.mission.lifecycle import MissionState
from executive.mission.model import EnergyConfig, Mission
from executive.sensing import battery_energy
from executive.sensing.consumption import HELD_BELOW_M_S, SEEDS, ConsumptionModel
from executive.sensing.heading import filterpy_ready, load_filterpy
from executive.sensing.vtol_flight import flies_as_plane
from executive.state import Battery, BatteryStatus, EkfStatus, GlobalPosition

log = logging.getLogger("executive.energy")  # the journal's event kind: "energy"

#: A mission that did not ask for the rule runs unjudged (warned) on a vehicle that sends no BATTERY_STATUS by then.
NO_REPORT_S = 5.0
#: How long the capacity parameter may take to come: the parameter watch asks 10 times, 1 s apart (autopilot_link.parameters).
PARAMS_WAIT_S = 12.0
WINDOW_S = 10.0  # consumption measured over windows this long: ten 1 Hz reports, the current's noise averaged
# A VTOL hovers to climb and to land: ArduPlane's QuadPlane climbs at Q_WP_SPEED_UP 2.5 m/s and descends at Q_WP_SPEED_DN
# 1.5 m/s (libraries/AC_WPNav/AC_WPNav.cpp WPNAV_WP_SPEED_UP_CMS, _DOWN_CMS), the last Q_LAND_FINAL_ALT 6 m at
# Q_LAND_FINAL_SPD 0.5 m/s (ArduPlane/quadplane.cpp): seconds of hover the route's distance does not count.
CLIMB_M_S, DESCENT_M_S, FINAL_ALT_M, FINAL_M_S = 2.5, 1.5, 6.0, 0.5
# Between points on the lift motors: AC_WPNav's WPNAV_WP_SPEED 500 cm/s (libraries/AC_WPNav/AC_WPNav.h), PX4 MPC_XY_CRUISE 5 m/s.
HOVER_M_S = 5.0
# Seconds on the lift motors a transition costs. To FW: ArduPlane holds them until the airspeed passes Q_ASSIST_SPEED, then
# blends them out over Q_TRANSITION_MS 5 s (ArduPlane/quadplane.cpp SLT_Transition::update: ~9 s at 2 m/s/s to 18 m/s + 5 s);
# PX4 VT_F_TRANS_DUR 5 s once VT_ARSP_TRANS is reached. To MC: PX4 VT_B_TRANS_DUR 10 s
# (src/modules/vtol_att_control/vtol_att_control_params.c); ArduPlane slows to a hover on them in QLOITER/QRTL.
TO_FW_S, TO_MC_S = 15.0, 10.0


@dataclass(frozen=True, slots=True)
class Held:
    """Seconds the rest of the route (``route_s``) and the way home (``home_s``) spend held: hover, transitions, samples."""

    route_s: float
    home_s: float


def held_s(mission: Mission, leg_index: int, take_off: bool, to_fw_ahead: bool, hovering_at_m: float | None = None) -> Held:
    """The seconds held ahead from leg ``leg_index``: a VTOL's take-off climb and hover point (``take_off``), its transition
    to FW (``to_fw_ahead``), the transition back and the landing descent home (``hovering_at_m``: the route flown and the
    aircraft on its lift motors at that height: no transition back, the descent from there); every sample point's
    ``sampling.duration_s``."""
    route = 0.0
    if mission.sampling is not None:
        route += mission.sampling.duration_s * sum(1 for w in mission.waypoints[leg_index:] if w.sample)
    if mission.vehicle != "vtol":
        return Held(route, 0.0)
    options = mission.vtol
    takeoff_alt = options.takeoff_alt_m if options else 0.0
    if take_off:
        route += takeoff_alt / CLIMB_M_S
        point = options.hover_enu if options else None
        if point is not None:
            route += math.hypot(point.east_m, point.north_m) / HOVER_M_S + abs(point.up_m - takeoff_alt) / CLIMB_M_S
    if to_fw_ahead:
        route += TO_FW_S
    alt = max([w.alt_m for w in mission.waypoints] + [takeoff_alt]) if hovering_at_m is None else max(0.0, hovering_at_m)
    back = TO_MC_S if hovering_at_m is None else 0.0
    return Held(route, back + max(0.0, alt - FINAL_ALT_M) / DESCENT_M_S + min(alt, FINAL_ALT_M) / FINAL_M_S)


@dataclass(frozen=True, slots=True)
class EnergyEstimate:
    """One estimate, Wh. ``has_wh``: left above the reserve now; ``route_wh``: the rest of the route from where the vehicle is;
    ``home_wh``: from its end home; ``sigma_wh``: 1 sigma of their sum; ``margin_wh`` = has - (route + home + sigma)."""

    has_wh: float
    route_wh: float
    home_wh: float
    sigma_wh: float
    capacity_wh: float
    reserve_pct: float
    drawn_wh: float  # since the start
    wh_per_km: float
    wh_per_min: float
    leg_index: int
    time: float

    @property
    def margin_wh(self) -> float:
        return self.has_wh - (self.route_wh + self.home_wh + self.sigma_wh)

    @property
    def fits(self) -> bool:
        return self.margin_wh >= 0.0

    def figures(self) -> str:
        """``needs 41 Wh + 9 Wh home (+/- 6), has 38 Wh above the 20 % reserve``"""
        places = 0 if max(self.route_wh, self.home_wh, self.has_wh) >= 10 else 1
        return (
            f"needs {wh(self.route_wh, places)} Wh + {wh(self.home_wh, places)} Wh home (+/- {wh(self.sigma_wh, places)}), "
            f"has {wh(self.has_wh, places)} Wh above the {self.reserve_pct:g} % reserve"
        )


def wh(value: float, places: int | None = None) -> str:
    """Watt-hours as a person reads them: whole ones, tenths under 10 (or ``places``)."""
    places = (0 if abs(value) >= 10 else 1) if places is None else places
    return f"{value:.{places}f}"


def path_length(points: list[tuple[float, float]], start: tuple[float, float]) -> float:
    """Metres from ``start`` through ``points`` (lat, lon)."""
    metres = 0.0
    lat, lon = start
    for plat, plon in points:
        metres += geo.distance(lat, lon, plat, plon)
        lat, lon = plat, plon
    return metres


def planned(mission: Mission) -> EnergyEstimate | str | None:
    """What can be said without a vehicle (``validate``): the estimate from home (else the first waypoint) on a full pack
    of ``energy.capacity_wh`` with the seeds; a string when only the vehicle can tell; None without an ``energy:`` block (the
    rule's defaults then can only be judged on the vehicle: validate says nothing of them) or with ``check: off``."""
    config = mission.energy_rule() if mission.energy is not None else None
    if config is None:
        return None
    if config.capacity_wh is None or not mission.waypoints:
        return "judged on the vehicle (its capacity from the autopilot's BATT_CAPACITY or BAT1_CAPACITY)"
    seed_km, seed_min = SEEDS[mission.vehicle]
    model = ConsumptionModel(config.wh_per_km or seed_km, config.wh_per_min or seed_min)
    points = [(w.lat, w.lon) for w in mission.waypoints]
    home = (mission.home.lat, mission.home.lon) if mission.home is not None else points[0]
    route_m = path_length(points, home)
    back = list(reversed(points[:-1])) if config.return_by == "route" else []
    home_m = path_length([*back, home], points[-1])
    held = held_s(mission, 0, take_off=True, to_fw_ahead=True)
    route_s, home_s = held.route_s, held.home_s
    kept = config.capacity_wh * (config.reserve_pct + 100.0 - config.usable_pct) / 100.0
    return EnergyEstimate(
        config.capacity_wh - kept, model.need(route_m, route_s)[0], model.need(home_m, home_s)[0],
        model.need(route_m + home_m, route_s + home_s)[1], config.capacity_wh, config.reserve_pct, 0.0, seed_km, seed_min, 0, 0.0,
    )  # fmt: skip


class EnergyWatch:
    """Writes ``/energy/estimate`` (an :class:`EnergyEstimate`) and ``/energy/unknown`` (why none can be made, else "")."""

    def __init__(self, clock: Clock, state: MissionState, autopilot: Callable[[], str] = lambda: "ardupilot") -> None:
        """``autopilot``: the firmware driving the vehicle (its battery parameters' names), asked each time."""
        self._clock = clock
        self._state = state
        self._autopilot = autopilot
        self._in = blackboard.reader(
            "energy watch in",
            [
                "/vehicle/battery_status",
                "/vehicle/battery",
                "/vehicle/params",
                "/vehicle/position",
                "/vehicle/home",
                "/vehicle/armed",
                "/vehicle/ekf",
                "/vehicle/ground_speed_m_s",
                "/vehicle/vtol_state",
            ],
        )
        self._out = blackboard.writer("energy watch", blackboard.keys_under("/energy/"))
        self._mission: Mission | None = None
        self._rest_v: float | None = None  # the pack's voltage before arming (kept from mission to mission: the same pack)
        self._begin(None)
        load_filterpy()

    def _begin(self, mission: Mission | None) -> None:
        """A mission's own count: its seeds, its start, its windows (a mission uploaded in ``--wait`` starts afresh)."""
        self._mission = mission
        self._model: ConsumptionModel | None = None
        self._start: tuple[float, int] | None = None  # (drawn Wh, remaining %) when the mission's energy was first counted
        self._window: tuple[float, float, float, float] | None = None  # (time, drawn Wh, metres, held s) at the window's start
        self._metres = 0.0
        self._held_s = 0.0  # armed and slower than HELD_BELOW_M_S
        self._ticked_at: float | None = None
        self._last_position: GlobalPosition | None = None
        self._said: tuple[int, float] | None = None  # (leg, margin) last logged
        self._vtol = False
        self._wing_borne = False  # a VTOL has flown as a plane: its transition to FW is behind it
        self._hovering = False  # a VTOL armed on its lift motors now
        self._since = 0.0  # when the mission's energy was first looked at

    def service(self) -> None:
        mission = self._state.mission
        config = mission.energy_rule() if mission is not None else None
        if mission is None or config is None:
            return
        if mission is not self._mission:
            self._begin(mission)
        if self._model is None:
            if not filterpy_ready():
                self._unknown("")  # the consumption model is loading (filterpy, in the background): nothing to say yet
                return
            seed_km, seed_min = SEEDS[mission.vehicle]
            self._model = ConsumptionModel(config.wh_per_km or seed_km, config.wh_per_min or seed_min)
            self._since = self._clock.now()
        self._vtol = mission.vehicle == "vtol"
        status: BatteryStatus | None = self._in.get("/vehicle/battery_status")
        battery: Battery | None = self._in.get("/vehicle/battery")
        params = self._in.get("/vehicle/params") or {}
        self._track_distance()
        said = mission.energy is not None
        if status is None:
            if not said and self._clock.now() - self._since >= NO_REPORT_S:
                self._not_judged(f"the autopilot sent no BATTERY_STATUS in {NO_REPORT_S:g} s")
            else:
                self._unknown("no BATTERY_STATUS from the autopilot yet")
            return
        if status.voltage_v and (not self._in.get("/vehicle/armed") or self._rest_v is None):
            # the pack at rest (else as first seen: an armed vehicle): its cells counted where the autopilot does not say its voltage
            self._rest_v = status.voltage_v if self._start is None or self._rest_v is None else self._rest_v
        name = battery_energy.capacity_param(self._autopilot())
        if config.capacity_wh is None and name not in params and self._clock.now() - self._since < PARAMS_WAIT_S:
            self._unknown("")  # the parameter watch is still asking for it: nothing to say yet (the pre-flight's wait not begun)
            return
        capacity = battery_energy.judgeable(config, said, status, battery, params, self._autopilot(), self._rest_v)
        if isinstance(capacity, battery_energy.NotJudged):
            self._not_judged(capacity.why)
            return
        if isinstance(capacity, str):
            self._unknown(capacity)
            return
        remaining = battery_energy.remaining_pct(status, battery)
        assert remaining is not None  # judgeable said so
        counted = battery_energy.drawn_wh(status, battery) if battery_energy.counts_current(status) else None
        # no current measured: the drawn energy is the remaining charge's fall, in its 1 % steps
        drawn = counted if counted is not None else capacity.wh * (100 - remaining) / 100.0
        if self._start is None:
            self._start = (drawn, remaining)
        self._learn(drawn, 0.0 if counted is not None else capacity.wh / 100.0)
        self._publish(mission, config, capacity.wh, drawn - self._start[0])

    # -- learning ------------------------------------------------------------------------------
    def _track_distance(self) -> None:
        now = self._clock.now()
        speed: float | None = self._in.get("/vehicle/ground_speed_m_s")
        # a VTOL on its lift motors pays by the second however it moves: its metres are the plane's (the way home is flown as one)
        hovering = self._vtol and not flies_as_plane(self._in.get("/vehicle/vtol_state"), speed)
        self._wing_borne = self._wing_borne or (self._vtol and not hovering)
        self._hovering = hovering and bool(self._in.get("/vehicle/armed"))
        held = speed is None or speed < HELD_BELOW_M_S or hovering
        if self._in.get("/vehicle/armed") and self._ticked_at is not None and held:
            self._held_s += now - self._ticked_at  # hover, loiter, station keeping, a stop: its seconds cost, not its metres
        self._ticked_at = now
        position: GlobalPosition | None = self._in.get("/vehicle/position")
        ekf: EkfStatus | None = self._in.get("/vehicle/ekf")
        # only a position the EKF vouches for: ArduPlane sends one dead-reckoned from 0, 0 before its GPS fix (docs/autopilots.md)
        if position is None or position is self._last_position or ekf is None or not ekf.position_ok():
            return
        if self._last_position is not None and self._in.get("/vehicle/armed") and not hovering:
            self._metres += geo.distance(self._last_position.lat, self._last_position.lon, position.lat, position.lon)
        self._last_position = position

    def _learn(self, drawn: float, resolution_wh: float) -> None:
        now = self._clock.now()
        if not self._in.get("/vehicle/armed"):
            self._window = None
            return
        if self._window is None:
            self._window = (now, drawn, self._metres, self._held_s)
            return
        t0, wh0, m0, h0 = self._window
        if now - t0 < WINDOW_S:
            return
        used, metres, held = drawn - wh0, self._metres - m0, self._held_s - h0
        assert self._model is not None
        # the counter's resolution (0.1 Wh in hJ, 1 mAh) and the current's noise averaged over the window
        self._model.update(used, metres, held, noise_wh=0.05 + 0.1 * abs(used) + resolution_wh)
        self._window = (now, drawn, self._metres, self._held_s)

    # -- the estimate --------------------------------------------------------------------------
    def _legs_ahead(self, mission: Mission) -> tuple[list[tuple[float, float]], tuple[float, float]]:
        """The points still to go (lat, lon) from the current leg on, and home."""
        route = self._state.route
        ahead = [(w.lat, w.lon) for w in route.waypoints[self._state.leg_index :]]
        home = self._in.get("/vehicle/home")
        if home is not None:
            where = (home.lat, home.lon)
        elif mission.home is not None:
            where = (mission.home.lat, mission.home.lon)
        elif self._last_position is not None and self._start is not None:
            where = (self._last_position.lat, self._last_position.lon)
        else:
            where = (ahead[0][0], ahead[0][1]) if ahead else (0.0, 0.0)
        return ahead, where

    def _publish(self, mission: Mission, config: EnergyConfig, capacity_wh: float, drawn_since_start: float) -> None:
        assert self._model is not None and self._start is not None
        ahead, home = self._legs_ahead(mission)
        here = (self._last_position.lat, self._last_position.lon) if self._last_position else (ahead[0][0], ahead[0][1]) if ahead else home
        route_m = path_length(ahead, here)
        end = ahead[-1] if ahead else here
        back = list(reversed([(w.lat, w.lon) for w in self._state.route.waypoints[:-1]])) if config.return_by == "route" else []
        home_m = path_length([*back, home], end)
        take_off = not self._in.get("/vehicle/armed") and self._state.leg_index == 0
        legs = len(self._state.route.waypoints)
        done = self._state.leg_index >= legs
        landing = self._last_position.alt_rel_m if done and self._hovering and self._last_position is not None else None
        held = held_s(mission, self._state.leg_index, take_off, not self._wing_borne and not done, landing)
        route_s, home_s = held.route_s, held.home_s
        route_wh = self._model.need(route_m, route_s)[0]
        home_wh = self._model.need(home_m, home_s)[0]
        _, sigma = self._model.need(route_m + home_m, route_s + home_s)
        kept = capacity_wh * (config.reserve_pct + 100.0 - config.usable_pct) / 100.0
        has = capacity_wh * self._start[1] / 100.0 - drawn_since_start - kept
        estimate = EnergyEstimate(
            has, route_wh, home_wh, sigma, capacity_wh, config.reserve_pct, drawn_since_start,
            self._model.wh_per_m * 1000.0, self._model.wh_per_s * 60.0, self._state.leg_index, self._clock.now(),
        )  # fmt: skip
        self._out.set("/energy/estimate", estimate)
        self._out.set("/energy/unknown", "")
        self._out.set("/energy/not_judged", "")
        self._journal(estimate)

    def _journal(self, estimate: EnergyEstimate) -> None:
        said = self._said
        if said is not None and said[0] == estimate.leg_index and abs(said[1] - estimate.margin_wh) < 0.05 * estimate.capacity_wh:
            return
        self._said = (estimate.leg_index, estimate.margin_wh)
        legs = len(self._state.route.waypoints)
        where = f"leg {estimate.leg_index + 1}/{legs}" if estimate.leg_index < legs else "the end of the route"
        log.info(
            "energy at %s: %s: margin %s Wh; drawn %.1f Wh so far; %.1f Wh/km + %.2f Wh/min",
            where, estimate.figures(), wh(estimate.margin_wh), estimate.drawn_wh, estimate.wh_per_km, estimate.wh_per_min,
        )  # fmt: skip

    def _unknown(self, why: str) -> None:
        self._out.set("/energy/estimate", None)
        self._out.set("/energy/unknown", why)
        self._out.set("/energy/not_judged", "")

    def _not_judged(self, why: str) -> None:
        self._out.set("/energy/estimate", None)
        self._out.set("/energy/unknown", "")
        self._out.set("/energy/not_judged", why)
