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

from executive.mission.declaration import kind_spec
from executive.mission.lifecycle import MissionState
from executive.mission.model import EnergyConfig, Mission, Waypoint
from executive.mission.return_path import DRIVEN_KINDS, ReturnPlanner
from executive.sensing import battery_energy
from executive.sensing.consumption import HELD_BELOW_M_S, SEEDS, VERTICAL_SEEDS, ConsumptionModel
from executive.sensing.heading import filterpy_ready, load_filterpy
from executive.sensing.vtol_flight import flies_as_plane
from executive.world import blackboard, geo
from executive.world.clock import Clock
from executive.world.state import Battery, BatteryStatus, EkfStatus, GlobalPosition

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
# PX4's RTL climbs to RTL_RETURN_ALT above home (default 60 m) before it flies home, unless higher already
# (src/modules/navigator/rtl_params.c, rtl.cpp: rtl_alt = max(alt, destination + RTL_RETURN_ALT), upstream a70a558393).
PX4_RTL_RETURN_ALT_M = 60.0
# A VTOL climbing as a plane: a metre of height costs what GLIDE_RATIO metres of cruise do (energy m g h against the cruise's
# drag m g / (L/D) per metre, at the same propulsive efficiency); 10, a small fixed-wing VTOL's lift-to-drag with its lift motors.
GLIDE_RATIO = 10.0


def return_climb_m(mission: Mission, autopilot: str, params: dict[str, float]) -> float:
    """Metres of height a VTOL's return climbs before it flies home: PX4's to RTL_RETURN_ALT (read at pre-flight, else its
    default) from the route's last height."""
    if mission.vehicle != "vtol" or autopilot != "px4" or not mission.waypoints:
        return 0.0
    return_alt = params.get("RTL_RETURN_ALT", PX4_RTL_RETURN_ALT_M)
    return max(0.0, return_alt - mission.waypoints[-1].alt_m)


@dataclass(frozen=True, slots=True)
class Held:
    """Seconds the rest of the route (``route_s``) and the way home (``home_s``) spend held: hover, transitions, samples."""

    route_s: float
    home_s: float


@dataclass(frozen=True, slots=True)
class Ahead:
    """The route still to go from leg ``leg`` of ``waypoints``: its next and last points (lat, lon), the metres between them."""

    waypoints: list[Waypoint]
    leg: int
    next: tuple[float, float] | None
    last: tuple[float, float] | None
    along_m: float


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


def waypoint_depth(waypoint: Waypoint, mission: Mission, seabed_m: float | None) -> float | None:
    """How deep a sub goes for ``waypoint``, m; None: it keeps its depth. An altitude above the seabed is a depth under the
    chart's ``limits.water_depth_m``, else the seabed the sonar reads now (``seabed_m``), else the deepest the mission allows
    (the estimate errs deep); never closer to the seabed than ``limits.altitude_m.min`` (the floor, executive.world.seabed)."""
    limits = mission.limits
    seabed = limits.water_depth_m or seabed_m
    if waypoint.control_mode == "altitude" and waypoint.altitude_m is not None:
        depth = (seabed if seabed is not None else limits.depth_m.max) - waypoint.altitude_m
    elif waypoint.depth_m is not None:
        depth = waypoint.depth_m
    else:
        return None
    floor = seabed - limits.altitude_m.min if seabed is not None else depth
    return max(0.0, min(depth, floor, limits.depth_m.max))


def depth_changes(mission: Mission, ahead: list[Waypoint], depth_m: float, seabed_m: float | None = None) -> tuple[float, float]:
    """A sub's metres of depth changed on the legs ``ahead`` from ``depth_m``, and on its way home: the surfacing from the route's
    end. A sub comes home by surfacing where it is (ArduSub has no RTL: the failsafe's ``surface``; the make-safe's SURFACE
    then POSHOLD, autopilot_link/safe_state.py), so its way home is that climb, no horizontal leg. (0, 0) for other kinds."""
    if mission.vehicle != "sub":
        return 0.0, 0.0
    route = 0.0
    for waypoint in ahead:
        target = waypoint_depth(waypoint, mission, seabed_m)
        if target is not None:
            route, depth_m = route + abs(target - depth_m), target
    return route, depth_m


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
    model = seeded(mission, config)
    points = [(w.lat, w.lon) for w in mission.waypoints]
    home = (mission.home.lat, mission.home.lon) if mission.home is not None else points[0]
    route_m = path_length(points, home)
    home_m = home_metres(mission, config, points, home, points[-1])
    held = held_s(mission, 0, take_off=True, to_fw_ahead=True)
    route_s, home_s = held.route_s, held.home_s
    route_z, home_z = depth_changes(mission, mission.waypoints, 0.0)
    kept = config.capacity_wh * (config.reserve_pct + 100.0 - config.usable_pct) / 100.0
    return EnergyEstimate(
        config.capacity_wh - kept, model.need(route_m, route_s, route_z)[0], model.need(home_m, home_s, home_z)[0],
        model.need(route_m + home_m, route_s + home_s, route_z + home_z)[1], config.capacity_wh, config.reserve_pct, 0.0,
        model.wh_per_m * 1000.0, model.wh_per_s * 60.0, 0, 0.0,
    )  # fmt: skip


def seeded(mission: Mission, config: EnergyConfig) -> ConsumptionModel:
    """The consumption model at the mission's seeds, else its kind's."""
    spec = kind_spec(mission.vehicle)
    seed_km, seed_min = SEEDS[mission.vehicle] if spec is None else spec.energy_seeds
    return ConsumptionModel(config.wh_per_km or seed_km, config.wh_per_min or seed_min, VERTICAL_SEEDS.get(mission.vehicle, 0.0))


def home_metres(
    mission: Mission, config: EnergyConfig, points: list[tuple[float, float]], home: tuple[float, float], end: tuple[float, float]
) -> float:
    """Metres of the way home from ``end``: the straight line, or the route back (``return_by: route``); none for a sub
    (it surfaces where it is: :func:`depth_changes`); for a rover or a boat on a mission with keep-out zones or rally points,
    the way the executive's own return drives (behaviours.returning): around the zones to the nearest rally point or home."""
    if mission.vehicle == "sub" and config.return_by == "straight":
        return 0.0
    if config.return_by == "straight" and mission.vehicle in DRIVEN_KINDS:
        planner = ReturnPlanner(mission)
        way = planner.plan(end[0], end[1], home) if planner.needed else None
        if way is not None:
            return way.length_m
    back = list(reversed(points[:-1])) if config.return_by == "route" else []
    return path_length([*back, home], end)


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
                "/vehicle/altitude_above_bottom_m",
            ],
        )
        self._out = blackboard.writer("energy watch", blackboard.keys_under("/energy/"))
        self._mission: Mission | None = None
        self._rest_v: float | None = None  # the pack's voltage before arming (kept from mission to mission: the same pack)
        self._rule: tuple[Mission, EnergyConfig | None, EnergyConfig | None] | None = None  # (mission, its energy block, its rule)
        self._judged = battery_energy.JudgedCapacity()
        self._begin(None)
        load_filterpy()

    def _rule_of(self, mission: Mission) -> EnergyConfig | None:
        """The mission's energy rule, asked again only when its ``energy:`` block is another (its defaults are a new model each time)."""
        if self._rule is None or self._rule[0] is not mission or self._rule[1] is not mission.energy:
            self._rule = (mission, mission.energy, mission.energy_rule())
        return self._rule[2]

    def _begin(self, mission: Mission | None) -> None:
        """A mission's own count: its seeds, its start, its windows (a mission uploaded in ``--wait`` starts afresh)."""
        self._mission = mission
        self._model: ConsumptionModel | None = None
        self._start: tuple[float, int] | None = None  # (drawn Wh, remaining %) when the mission's energy was first counted
        self._window: tuple[float, float, float, float, float] | None = None  # (time, Wh, metres, held s, vertical m) at its start
        self._metres = 0.0
        self._vertical_m = 0.0  # a sub's depth changed, armed
        self._home_way: tuple[object, list[Waypoint], float] | None = None  # ((route end, home), route, metres home): the last planned
        self._held_s = 0.0  # armed and slower than HELD_BELOW_M_S
        self._ticked_at: float | None = None
        self._last_position: GlobalPosition | None = None
        self._said: tuple[int, float] | None = None  # (leg, margin) last logged
        self._vtol = False
        self._wing_borne = False  # a VTOL has flown as a plane: its transition to FW is behind it
        self._hovering = False  # a VTOL armed on its lift motors now
        self._since = 0.0  # when the mission's energy was first looked at
        self._ahead: Ahead | None = None
        self._armed = False  # /vehicle/armed at this tick
        self._needs: tuple[tuple[object, ...], tuple[float, ...]] = ((), ())  # (inputs, _estimate's figures)

    def service(self) -> None:
        mission = self._state.mission
        config = self._rule_of(mission) if mission is not None else None
        if mission is None or config is None:
            return
        if mission is not self._mission:
            self._begin(mission)
        if self._model is None:
            if not filterpy_ready():
                self._unknown("")  # the consumption model is loading (filterpy, in the background): nothing to say yet
                return
            self._model = seeded(mission, config)
            self._since = self._clock.now()
        self._vtol = mission.vehicle == "vtol"
        status: BatteryStatus | None = self._in.get("/vehicle/battery_status")
        battery: Battery | None = self._in.get("/vehicle/battery")
        params = self._in.get("/vehicle/params") or {}
        self._armed = bool(self._in.get("/vehicle/armed"))  # read once a tick: each step below asks it
        self._track_distance()
        said = mission.energy is not None
        if status is None:
            if not said and self._clock.now() - self._since >= NO_REPORT_S:
                self._not_judged(f"the autopilot sent no BATTERY_STATUS in {NO_REPORT_S:g} s")
            else:
                self._unknown("no BATTERY_STATUS from the autopilot yet")
            return
        if status.voltage_v and (not self._armed or self._rest_v is None):
            # the pack at rest (else as first seen: an armed vehicle): its cells counted where the autopilot does not say its voltage
            self._rest_v = status.voltage_v if self._start is None or self._rest_v is None else self._rest_v
        autopilot = self._autopilot()
        name = battery_energy.capacity_param(autopilot)
        if config.capacity_wh is None and name not in params and self._clock.now() - self._since < PARAMS_WAIT_S:
            self._unknown("")  # the parameter watch is still asking for it: nothing to say yet (the pre-flight's wait not begun)
            return
        capacity = self._judged.get(config, said, status, battery, params, autopilot, self._rest_v)
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
        self._publish(mission, config, capacity.wh, drawn - self._start[0], autopilot, params)

    # -- learning ------------------------------------------------------------------------------
    def _track_distance(self) -> None:
        now = self._clock.now()
        speed: float | None = self._in.get("/vehicle/ground_speed_m_s")
        # a VTOL on its lift motors pays by the second however it moves: its metres are the plane's (the way home is flown as one)
        hovering = self._vtol and not flies_as_plane(self._in.get("/vehicle/vtol_state"), speed)
        self._wing_borne = self._wing_borne or (self._vtol and not hovering)
        self._hovering = hovering and self._armed
        position: GlobalPosition | None = self._in.get("/vehicle/position")
        # a sub diving or climbing in place pays by the metre of depth (consumption.py), not by the second
        diving = self._mission is not None and self._mission.vehicle == "sub" and position is not None and abs(position.vd_m_s) >= HELD_BELOW_M_S
        held = (speed is None or speed < HELD_BELOW_M_S or hovering) and not diving
        if self._armed and self._ticked_at is not None and held:
            self._held_s += now - self._ticked_at  # hover, loiter, station keeping, a stop: its seconds cost, not its metres
        self._ticked_at = now
        ekf: EkfStatus | None = self._in.get("/vehicle/ekf")
        # only a position the EKF vouches for: ArduPlane sends one dead-reckoned from 0, 0 before its GPS fix (docs/autopilots.md)
        if position is None or position is self._last_position or ekf is None or not ekf.position_ok():
            return
        if self._last_position is not None and self._armed and not hovering:
            self._metres += geo.distance(self._last_position.lat, self._last_position.lon, position.lat, position.lon)
            if self._mission is not None and self._mission.vehicle == "sub":
                self._vertical_m += abs(position.alt_rel_m - self._last_position.alt_rel_m)
        self._last_position = position

    def _learn(self, drawn: float, resolution_wh: float) -> None:
        now = self._clock.now()
        if not self._armed:
            self._window = None
            return
        if self._window is None:
            self._window = (now, drawn, self._metres, self._held_s, self._vertical_m)
            return
        t0, wh0, m0, h0, z0 = self._window
        if now - t0 < WINDOW_S:
            return
        used, metres, held, vertical = drawn - wh0, self._metres - m0, self._held_s - h0, self._vertical_m - z0
        assert self._model is not None
        # the counter's resolution (0.1 Wh in hJ, 1 mAh) and the current's noise averaged over the window
        self._model.update(used, metres, held, noise_wh=0.05 + 0.1 * abs(used) + resolution_wh, vertical_m=vertical)
        self._window = (now, drawn, self._metres, self._held_s, self._vertical_m)

    # -- the estimate --------------------------------------------------------------------------
    def _legs_ahead(self, mission: Mission) -> Ahead:
        """The waypoints still to go from the current leg on: walked once per route and leg, not every tick (a long route's
        geodesics cost milliseconds; an edited route is a new list, MissionState.set_route)."""
        waypoints, leg = mission.waypoints, self._state.legs.leg_index
        if self._ahead is None or self._ahead.waypoints is not waypoints or self._ahead.leg != leg:
            points = [(w.lat, w.lon) for w in waypoints[leg:]]
            along = path_length(points[1:], points[0]) if points else 0.0
            self._ahead = Ahead(waypoints, leg, points[0] if points else None, points[-1] if points else None, along)
        return self._ahead

    def _home(self, mission: Mission, ahead: Ahead) -> tuple[float, float]:
        home = self._in.get("/vehicle/home")
        if home is not None:
            return (home.lat, home.lon)
        if mission.home is not None:
            return (mission.home.lat, mission.home.lon)
        if self._last_position is not None and self._start is not None:
            return (self._last_position.lat, self._last_position.lon)
        return ahead.next if ahead.next is not None else (0.0, 0.0)

    def _publish(
        self, mission: Mission, config: EnergyConfig, capacity_wh: float, drawn_since_start: float, autopilot: str, params: dict[str, float]
    ) -> None:
        assert self._model is not None and self._start is not None
        below: float | None = self._in.get("/vehicle/altitude_above_bottom_m")
        inputs = (
            mission, self._state.legs.leg_index, config, capacity_wh, drawn_since_start, autopilot, params, self._in.get("/vehicle/home"),
            self._last_position, self._start, self._armed, self._wing_borne, self._hovering, below, self._model.windows,
        )  # fmt: skip
        if inputs != self._needs[0]:
            self._needs = (inputs, self._estimate(mission, config, capacity_wh, drawn_since_start, autopilot, params, below))
        has, route_wh, home_wh, sigma, wh_per_km, wh_per_min = self._needs[1]
        estimate = EnergyEstimate(
            has, route_wh, home_wh, sigma, capacity_wh, config.reserve_pct, drawn_since_start,
            wh_per_km, wh_per_min, self._state.legs.leg_index, self._clock.now(),
        )  # fmt: skip
        self._out.set("/energy/estimate", estimate)
        self._out.set("/energy/unknown", "")
        self._out.set("/energy/not_judged", "")
        self._journal(estimate)

    def _estimate(
        self,
        mission: Mission,
        config: EnergyConfig,
        capacity_wh: float,
        drawn_since_start: float,
        autopilot: str,
        params: dict[str, float],
        below: float | None,
    ) -> tuple[float, float, float, float, float, float]:
        """(has, route, home, sigma) Wh and the model's Wh/km and Wh/min, from what :meth:`_publish` keys them on: worked out
        again only when one of those is another.

        Between two position reports (5 Hz, ticks at 10 Hz) and battery reports (1 Hz) every input is the same object (the
        reader writes a new one for each message; the model's state changes only in its ``update``, which counts its
        ``windows``), and the same inputs give the same figures."""
        assert self._model is not None and self._start is not None
        ahead = self._legs_ahead(mission)
        home = self._home(mission, ahead)
        here = (self._last_position.lat, self._last_position.lon) if self._last_position else ahead.next or home
        route_m = path_length([ahead.next], here) + ahead.along_m if ahead.next is not None else 0.0
        end = ahead.last or here
        home_m = self._home_metres(mission, config, home, end)
        home_m += GLIDE_RATIO * return_climb_m(mission, autopilot, params)
        take_off = not self._armed and self._state.legs.leg_index == 0
        legs = len(mission.waypoints)
        done = self._state.legs.leg_index >= legs
        landing = self._last_position.alt_rel_m if done and self._hovering and self._last_position is not None else None
        held = held_s(mission, self._state.legs.leg_index, take_off, not self._wing_borne and not done, landing)
        route_s, home_s = held.route_s, held.home_s
        depth = max(0.0, -self._last_position.alt_rel_m) if self._last_position is not None else 0.0
        seabed = None if below is None else depth + below
        route_z, home_z = depth_changes(mission, mission.waypoints[self._state.legs.leg_index :], depth, seabed)
        route_wh = self._model.need(route_m, route_s, route_z)[0]
        home_wh = self._model.need(home_m, home_s, home_z)[0]
        _, sigma = self._model.need(route_m + home_m, route_s + home_s, route_z + home_z)
        kept = capacity_wh * (config.reserve_pct + 100.0 - config.usable_pct) / 100.0
        has = capacity_wh * self._start[1] / 100.0 - drawn_since_start - kept
        return has, route_wh, home_wh, sigma, self._model.wh_per_m * 1000.0, self._model.wh_per_s * 60.0

    def _home_metres(self, mission: Mission, config: EnergyConfig, home: tuple[float, float], end: tuple[float, float]) -> float:
        """:func:`home_metres`, planned once per route end and home (a return around zones is an A* search: not every report)."""
        waypoints = mission.waypoints
        key = (end, home)
        if self._home_way is None or self._home_way[0] != key or self._home_way[1] is not waypoints:
            self._home_way = (key, waypoints, home_metres(mission, config, [(w.lat, w.lon) for w in waypoints], home, end))
        return self._home_way[2]

    def _journal(self, estimate: EnergyEstimate) -> None:
        said = self._said
        if said is not None and said[0] == estimate.leg_index and abs(said[1] - estimate.margin_wh) < 0.05 * estimate.capacity_wh:
            return
        self._said = (estimate.leg_index, estimate.margin_wh)
        legs = self._state.legs.leg_count
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
