"""PX4 on a standard VTOL in the simulated autopilot: vtol_att_control's transitions, hovering and fixed-wing flight."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from executive.sim.firmware import DEFAULT_HOME, Command, CommandHandler, Home
from executive.sim.physics.aircraft import QUADPLANE_LIMITS, AircraftLimits, QuadPlaneModel, Regime
from executive.sim.physics.vehicle import VehicleModel
from executive.sim.px4.base import Px4Sim
from executive.sim.px4.parameters import NAV_ACC_RAD, TRANSITION_AIRSPEED_M_S, VT_B_TRANS_DUR
from executive.world.clock import Clock
from executive.world.dialect import mavlink
from executive.world.vehicles import VehicleProfile

_M = mavlink

MAV_TYPE_VTOL_FIXEDROTOR = 22  # a standard VTOL ("VTOL_RESERVED2" in pymavlink's older dialect)


class Px4VtolSim(Px4Sim):
    """PX4 on a standard VTOL, flying the simulated QuadPlane airframe (the ArduPilot VTOL's, for like-for-like runs)."""

    BATTERY_OF = "vtol"

    MAV_TYPE = MAV_TYPE_VTOL_FIXEDROTOR
    FLIES = True
    #: ROMFS init.d/rc.vtol_defaults: a mission must end in a landing (2) (the real SIH standard_vtol reads 2).
    PARAMS = {**Px4Sim.PARAMS, "MIS_TKO_LAND_REQ": 2.0}
    INT_PARAMS = Px4Sim.INT_PARAMS | {"MIS_TKO_LAND_REQ"}

    vehicle: QuadPlaneModel

    def __init__(
        self, profile: VehicleProfile, clock: Clock, home: Home = DEFAULT_HOME, *, limits: AircraftLimits = QUADPLANE_LIMITS, **options: float
    ) -> None:
        self._limits = limits
        self._vtol = _M.MAV_VTOL_STATE_MC
        self._back_started = 0.0
        self._mission_climb: float | None = None  # a mission started on the ground: the altitude it climbs to first
        super().__init__(profile, clock, home, **options)

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return QuadPlaneModel(home[0], home[1], home[2], self._limits)

    @property
    def vtol_state(self) -> int:
        """EXTENDED_SYS_STATE vtol_state (MAV_VTOL_STATE)."""
        return self._vtol

    def _throttle(self) -> float:
        return 0.0 if not self.armed or self._landed else self.vehicle.throttle()

    def _servo_outputs(self) -> Sequence[int]:
        """MAIN1-4 the lift motors, MAIN5 the pusher."""
        outputs = [0] * 16
        flying = self.armed and not self._landed
        lifting = flying and self._vtol != _M.MAV_VTOL_STATE_FW
        outputs[0:4] = [1500 if lifting else 900] * 4
        outputs[4] = round(1000 + 1000 * self._throttle()) if flying and self.vehicle.regime is Regime.FIXED_WING else 1000
        return outputs

    def _detect_landed(self) -> bool:
        v = self.vehicle
        return v.on_ground and not (self.armed and v.velocity_ned[2] < -0.1)

    def _hold_here(self) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            self._fly_to(v.lat, v.lon, v.alt_m)
        else:
            self._fly_to(*v.stopping_point(), v.alt_m)

    def _steer(self) -> None:
        """Give the airframe the order that takes it to the goal in the present VTOL state."""
        v, goal = self.vehicle, self._goal
        if goal is None or self._landing:
            return
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            v.orbit(*goal, self._goal_radius)
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_FW:
            v.cruise(goal[2])
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_MC:
            v.hover_at(*v.stopping_point(), goal[2])
        else:
            v.hover_at(*goal)

    def _start_landing(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_FW, _M.MAV_VTOL_STATE_TRANSITION_TO_FW):
            self._back_transition()  # a VTOL lands on its lift motors
        self._landing = True
        self._goal = None
        if not self._landed:
            self.vehicle.land()

    def _reached(self, lat: float, lon: float, alt: float) -> bool:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW:
            return v.distance_to(lat, lon) <= self._goal_radius * 1.1
        return v.distance_to(lat, lon) <= NAV_ACC_RAD and abs(v.alt_m - alt) <= 1.0

    def _update_return(self, lat: float, lon: float) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_FW and v.distance_to(lat, lon) <= self._goal_radius * 1.1:
            self._back_transition()  # over the point: back to the lift motors
        elif self._vtol == _M.MAV_VTOL_STATE_MC and v.distance_to(lat, lon) <= NAV_ACC_RAD and v.arrived:
            self._start_landing()

    # -- transitions (vtol_att_control) ----------------------------------------------------------

    def _transition_to(self, state: int) -> None:
        if state == _M.MAV_VTOL_STATE_FW:
            self._front_transition()
        else:
            self._back_transition()

    def _front_transition(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_MC, _M.MAV_VTOL_STATE_TRANSITION_TO_MC):
            self._vtol = _M.MAV_VTOL_STATE_TRANSITION_TO_FW
            self._text(_M.MAV_SEVERITY_INFO, "Transition to fixed-wing")
            self._steer()

    def _back_transition(self) -> None:
        if self._vtol in (_M.MAV_VTOL_STATE_FW, _M.MAV_VTOL_STATE_TRANSITION_TO_FW):
            self._vtol, self._back_started = _M.MAV_VTOL_STATE_TRANSITION_TO_MC, self.elapsed_s
            self._text(_M.MAV_SEVERITY_INFO, "Transition to multicopter")
            self._steer()

    def _climbing_first(self, alt: float) -> bool:
        """navigator/mission.cpp handleTakeoff: a mission item started on the ground is preceded by a climb straight up to its
        altitude ("Climb to 30.0 meters above home" on the real SIH standard_vtol, tests/data/px4/README.md)."""
        v = self.vehicle
        if self._mission_climb is None and self._landed:
            self._mission_climb, self._goal = alt, (v.lat, v.lon, alt)
            self._steer()
        if self._mission_climb is not None and v.alt_m < self._mission_climb - 0.5:
            self._mission_item = None  # the item starts once the climb is done
            return True
        self._mission_climb = None
        return False

    def _update_airframe(self) -> None:
        if self._landed:
            self._vtol = _M.MAV_VTOL_STATE_MC
            return
        self._update_transition()

    def _update_transition(self) -> None:
        v = self.vehicle
        if self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_FW and v.speed_m_s >= TRANSITION_AIRSPEED_M_S:
            self._vtol = _M.MAV_VTOL_STATE_FW
            self._text(_M.MAV_SEVERITY_INFO, "Transition to fixed-wing complete")
            self._steer()
        elif self._vtol == _M.MAV_VTOL_STATE_TRANSITION_TO_MC and (
            v.speed_m_s <= self._limits.mc_speed_m_s or self.elapsed_s - self._back_started >= VT_B_TRANS_DUR
        ):
            self._vtol = _M.MAV_VTOL_STATE_MC
            self._text(_M.MAV_SEVERITY_INFO, "Transition to multicopter complete")
            if self._landing:
                v.land()
            else:
                self._steer()

    # -- commands --------------------------------------------------------------------------------

    def _command_handlers(self) -> dict[int, CommandHandler]:
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_VTOL_TRANSITION: self._cmd_vtol_transition,
            _M.MAV_CMD_DO_CHANGE_SPEED: self._cmd_change_speed,
        }

    def _cmd_vtol_transition(self, cmd: Command) -> int:
        """vtol_att_control: a transition in flight; refused on the ground and, to fixed wing, in Takeoff, Land and Return."""
        state = int(cmd.params[0] + 0.5)
        if state not in (_M.MAV_VTOL_STATE_MC, _M.MAV_VTOL_STATE_FW):
            return _M.MAV_RESULT_DENIED
        if self._landed or (state == _M.MAV_VTOL_STATE_FW and self.mode in ("AUTO.TAKEOFF", "AUTO.LAND", "AUTO.RTL")):
            return _M.MAV_RESULT_TEMPORARILY_REJECTED
        self._transition_to(state)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_change_speed(self, cmd: Command) -> int:
        """The navigator's cruise speed (param2, m/s; ground and air speed alike): here the multicopter speed."""
        if not cmd.params[1] > 0:
            return _M.MAV_RESULT_DENIED
        self._limits = dataclasses.replace(self._limits, mc_speed_m_s=cmd.params[1])
        self.vehicle.limits = self._limits
        return _M.MAV_RESULT_ACCEPTED
