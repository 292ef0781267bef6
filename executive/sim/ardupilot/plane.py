"""ArduPlane with QuadPlane lift motors as the simulated VTOL's autopilot; its modes fly a :class:`~executive.sim.physics.aircraft.QuadPlaneModel`.

What follows ArduPlane's source (4.x, a standard "SLT" QuadPlane with default parameters):

- HEARTBEAT type is MAV_TYPE_FIXED_WING (Q_MAV_TYPE=0 means "fixed wing").
- The flight mode decides the regime. Q modes (QSTABILIZE, QHOVER, QLOITER, QLAND, QRTL) and a
  GUIDED take-off or VTOL hover fly as a multicopter (vtol_state MC). Any other mode flies the
  wing: in the air, out of a Q mode, that starts a transition (TRANSITION_TO_FW), then FW. On the
  ground a fixed-wing mode reports FW at once (no transition is needed there). The transition is
  SLT_Transition::update() (ArduPlane/quadplane.cpp): the lift motors hold the height
  (TRANSITION_AIRSPEED_WAIT) until the airspeed is above AIRSPEED_MIN *and* the lift motors are no
  longer assisting (QuadPlane::should_assist: airspeed below Q_ASSIST_SPEED means assist), so the
  threshold is max(AIRSPEED_MIN, Q_ASSIST_SPEED) ("Transition airspeed reached 18.2" on SITL with
  quadplane.parm: AIRSPEED_MIN 13, Q_ASSIST_SPEED 18); then TRANSITION_TIMER blends the lift
  throttle down over Q_TRANSITION_MS (5000 ms) from that moment, "Transition done". Entered while
  assisting, "Transition airspeed wait" is not said (should_assist already set the start time);
  airspeed falling below Q_ASSIST_SPEED starts it over ("Transition started airspeed ...").
  The aircraft flies with quadplane.parm's AIRSPEED_CRUISE (25 m/s) and LIM_ROLL_CD (65 deg): from a
  hover, at 2 m/s/s, ~81 m to 18 m/s, then ~112 m of Q_TRANSITION_MS: FW ~190 m and ~14 s on.
- MAV_CMD_DO_VTOL_TRANSITION is accepted in AUTO only ("VTOL transition only in AUTO"); elsewhere
  the transition is made by changing mode.
- MAV_CMD_NAV_TAKEOFF (param7 = height above the current position) is accepted in GUIDED, armed,
  on the ground only ("User Takeoff only in GUIDED mode", "Must be armed for takeoff", "Already
  flying - no takeoff"): a vertical climb (landed_state TAKEOFF), then a hover there. ArduPlane has
  no COMMAND_LONG handler for NAV_VTOL_TAKEOFF, NAV_VTOL_LAND or NAV_LAND (UNSUPPORTED): they are
  mission items. To land, QLAND (or QRTL): descend, slower below Q_LAND_FINAL_ALT, "Land complete"
  once the land detector is sure (4 s), then disarm.
- GUIDED targets: DO_REPOSITION (in GUIDED, or with the change-mode flag; FAILED otherwise) sets
  the guided waypoint and ends any VTOL hover: the aircraft transitions and circles the point at
  WP_LOITER_RAD (60 m, or param3) as a plane. With Q_GUIDED_MODE=1 (QuadPlane::guided_mode_enabled,
  Plane::update_loiter_update_nav -> QuadPlane::guided_start) it flies the last ~140 m as a VTOL
  approach (QPOS_POSITION1, "VTOL Position1 d=...") and hovers there: a target that near is flown on
  the lift motors, and a wing-borne leg ends on them (a reposition 300 m ahead from a hover never
  shows FW: the transition is not done when the approach begins). The approach reports
  TRANSITION_TO_MC until POSITION2 (within 5 m of the point, "VTOL position2 started"), then MC
  (SLT_Transition::get_mav_vtol_state): SITL's 1 -> 2 -> 3. SET_POSITION_TARGET_GLOBAL_INT
  changes only the altitude of the guided target in ArduPlane (its lat/lon are not used);
  SET_POSITION_TARGET_LOCAL_NED, only an altitude change in MAV_FRAME_LOCAL_OFFSET_NED (not
  simulated: the message is ignored here). Entering GUIDED targets the current position.
- LOITER and CIRCLE circle where they start; RTL flies home and circles at 100 m (ALT_HOLD_RTL,
  Q_RTL_MODE=0). QRTL returns on the lift motors at no less than Q_RTL_ALT (15 m) and lands; entered
  while wing-borne it first brakes (reported TRANSITION_TO_MC, an approximation of ArduPlane's
  airbrake phase).
- EXTENDED_SYS_STATE (vtol_state, landed_state) is not in ArduPlane's default streams: it is sent
  once requested (SET_MESSAGE_INTERVAL / REQUEST_MESSAGE), like any other message.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from enum import Enum
from typing import ClassVar

import executive
from executive.sim.ardupilot.base import (
    GLOBAL_FRAMES,
    NAVIGATION,
    RATE_ATTITUDE,
    TARGET_REPORT_MASK,
    ArduPilotSim,
)
from executive.sim.firmware import DEFAULT_HOME, Command, Home, e7, valid_latlon
from executive.sim.physics.aircraft import QUADPLANE_LIMITS, AircraftLimits, QuadPlaneModel, Regime
from executive.sim.physics.vehicle import VehicleModel
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.vehicles import PLANE_MODES, VehicleProfile

_M = mavlink

Q_MODES = frozenset({"QSTABILIZE", "QHOVER", "QLOITER", "QLAND", "QRTL", "QACRO", "QAUTOTUNE", "LOITER_ALT_QLAND"})
#: Modes that stop the lift motors at once (QuadPlane::update: transition forced complete).
MOTORS_OFF_MODES = frozenset({"MANUAL", "ACRO", "TRAINING"})
TRANSITION_MS = 5000  # Q_TRANSITION_MS (ArduPlane/quadplane.cpp default)
LOITER_RADIUS_M = 60.0  # WP_LOITER_RAD
#: With Q_GUIDED_MODE=1 a wing-borne GUIDED approach becomes a VTOL one (QPOS_POSITION1) this far from the point:
#: ArduPlane 4.7 SITL, quadplane.parm, a DO_REPOSITION 300 m ahead: "VTOL Position1 d=143.4" (issue 14).
VTOL_APPROACH_M = 140.0
#: QuadPlane::vtol_position_controller: POSITION1 ends (POSITION2, the hold over the point) within 5 m of it.
POSITION2_M = 5.0
RTL_ALT_M = 100.0  # ALT_HOLD_RTL
QRTL_ALT_M = 15.0  # Q_RTL_ALT
#: Tools/autotest/default_params/quadplane.parm (the SITL of issue 14): AIRSPEED_MIN, Q_ASSIST_SPEED, AIRSPEED_CRUISE, LIM_ROLL_CD
AIRSPEED_MIN_M_S = 13.0
ASSIST_SPEED_M_S = 18.0
AIRSPEED_CRUISE_M_S = 25.0
ROLL_LIMIT_DEG = 65.0
#: The QuadPlane of quadplane.parm: our aircraft (QUADPLANE_LIMITS) at its cruise airspeed and bank limit.
QUADPLANE_PARM_LIMITS = dataclasses.replace(QUADPLANE_LIMITS, cruise_m_s=AIRSPEED_CRUISE_M_S, bank_deg=ROLL_LIMIT_DEG)
LAND_DETECT_S = 4.0  # land_detector(4000)


class TransitionState(Enum):
    """SLT_Transition's states."""

    AIRSPEED_WAIT = 0
    TIMER = 1
    DONE = 2


class QuadPlaneSim(ArduPilotSim):
    """ArduPlane on a QuadPlane; ``q_guided_mode`` is Q_GUIDED_MODE (0: GUIDED targets are circled as a plane)."""

    FIRMWARE = "ArduPlane"
    BATTERY_OF = "vtol"
    READY_TEXT = "Ready to FLY"
    #: ArduPlane/Parameters.cpp, FLIGHT_MODE_CHANNEL 8; WP_LOITER_RAD; Q_GUIDED_MODE (its option: the mission's simulator section)
    PARAMS: ClassVar[Mapping[str, float]] = {
        "FLTMODE_CH": 8,
        "WP_LOITER_RAD": LOITER_RADIUS_M,
        "Q_GUIDED_MODE": 0,
        "AIRSPEED_MIN": AIRSPEED_MIN_M_S,
        "Q_ASSIST_SPEED": ASSIST_SPEED_M_S,
        "AIRSPEED_CRUISE": AIRSPEED_CRUISE_M_S,
        "Q_TRANSITION_MS": TRANSITION_MS,
    }
    INITIAL_MODE = "MANUAL"
    MANUAL_INPUT_MODES = frozenset(PLANE_MODES) - {"INITIALISING"}  # STICK_MIXING enabled
    STABILIZE_MODES = frozenset(PLANE_MODES) - {"MANUAL", "INITIALISING"}
    AUTOPILOT_MODES = frozenset({"AUTO", "RTL", "LOITER", "THERMAL", "AVOID_ADSB", "GUIDED", "CIRCLE", "TAKEOFF", "QRTL", "LOITER_ALT_QLAND"})
    # No mode change is refused for want of a position estimate: Plane::set_mode (ArduPlane/system.cpp) and Mode::enter
    # (ArduPlane/mode.cpp) check none (refusals come from a fence recovery, FLTMODE_GCSBLOCK, Q_ENABLE 0); a QuadPlane's own
    # failsafes put it in QLAND whatever its position (ArduPlane/events.cpp).
    POSITION_MODES: frozenset[str] = frozenset()
    NOT_SIMULATED = frozenset({"AUTO", "AUTOTUNE", "TAKEOFF", "AVOID_ADSB", "THERMAL", "QACRO", "QAUTOTUNE", "LOITER_ALT_QLAND", "INITIALISING"})

    vehicle: QuadPlaneModel

    def __init__(
        self,
        profile: VehicleProfile,
        clock: Clock,
        home: Home = DEFAULT_HOME,
        *,
        q_guided_mode: int = 0,
        limits: AircraftLimits = QUADPLANE_PARM_LIMITS,
        **options: float,
    ) -> None:
        self._limits = limits
        self.transition = TransitionState.DONE
        self._transition_started = False  # transition_start_ms set: "Transition airspeed wait" said, or assisting
        self._timer_start = 0.0
        self._guided_vtol = False  # auto_state.vtol_loiter: GUIDED hovers on the lift motors
        self._position1 = False  # poscontrol QPOS_POSITION1: the VTOL approach, before POSITION2 holds over the point
        self._guided_takeoff = False
        self._guided_radius = LOITER_RADIUS_M
        self._guided_ccw = False
        self._airbrake = False  # QRTL braking from wing-borne flight
        self._returning = False  # QRTL on its way home
        self._final_said = False
        self._touchdown_at: float | None = None
        self._auto_vtol = False  # auto_state.vtol_mode, set by DO_VTOL_TRANSITION in AUTO
        super().__init__(dataclasses.replace(profile, mav_type=_M.MAV_TYPE_FIXED_WING), clock, home, **options)
        self.params["Q_GUIDED_MODE"] = q_guided_mode

    def _make_vehicle(self, home: Home) -> VehicleModel:
        return QuadPlaneModel(home[0], home[1], home[2], self._limits)

    # -- the state ArduPlane reports ----------------------------------------------------------

    @property
    def in_vtol_mode(self) -> bool:
        """Flying (or standing) on the lift motors: QuadPlane::in_vtol_mode()."""
        return self.mode in Q_MODES or (self.mode == "GUIDED" and self._guided_vtol) or (self.mode == "AUTO" and self._auto_vtol)

    @property
    def flying(self) -> bool:
        """Plane::is_flying(): off the ground, or climbing off it."""
        return self.armed and (not self.vehicle.on_ground or self._guided_takeoff)

    @property
    def vtol_state(self) -> int:
        """EXTENDED_SYS_STATE vtol_state (MAV_VTOL_STATE)."""
        if self.in_vtol_mode:  # SLT_Transition::get_mav_vtol_state(): QPOS_AIRBRAKE and QPOS_POSITION1 are TRANSITION_TO_MC
            return _M.MAV_VTOL_STATE_TRANSITION_TO_MC if self._airbrake or self._position1 else _M.MAV_VTOL_STATE_MC
        if self.transition is TransitionState.DONE:
            return _M.MAV_VTOL_STATE_FW
        return _M.MAV_VTOL_STATE_TRANSITION_TO_FW

    @property
    def landed_state(self) -> int:
        """EXTENDED_SYS_STATE landed_state (MAV_LANDED_STATE)."""
        if not self.flying:
            return _M.MAV_LANDED_STATE_ON_GROUND
        if self._guided_takeoff:
            return _M.MAV_LANDED_STATE_TAKEOFF
        if self.vehicle.landing:
            return _M.MAV_LANDED_STATE_LANDING
        return _M.MAV_LANDED_STATE_IN_AIR

    def _system_status(self) -> int:
        if self.mode == self.BOOT_MODE:
            return _M.MAV_STATE_CALIBRATING
        return _M.MAV_STATE_ACTIVE if self.flying else _M.MAV_STATE_STANDBY

    def _control_sensors(self) -> tuple[int, int]:
        """GCS_Plane::update_vehicle_sensor_status_flags (ArduPlane/GCS_Plane.cpp): which controllers each mode uses."""
        present = RATE_ATTITUDE | NAVIGATION | _M.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
        if self.mode in self.AUTOPILOT_MODES:  # AUTO, RTL, LOITER, GUIDED, CIRCLE, QRTL... (and the newer TAKEOFF, THERMAL)
            return present, present
        if self.mode in ("ACRO", "QACRO"):
            return present, _M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
        if self.mode in ("MANUAL", "INITIALISING"):
            return present, 0
        return present, RATE_ATTITUDE  # the stabilised modes, Q modes included

    def _throttle(self) -> float:
        return 0.0 if not self.armed or not self.flying else self.vehicle.throttle()

    def _servo_outputs(self) -> Sequence[int]:
        """SERVO1-4 aileron, elevator, throttle, rudder; SERVO5-8 the four lift motors."""
        outputs = [0] * 16
        outputs[0] = outputs[1] = outputs[3] = 1500
        lifting = (self.flying and self.vehicle.regime is Regime.MULTICOPTER) or self.vtol_state == _M.MAV_VTOL_STATE_TRANSITION_TO_FW
        forward = self.flying and self.vehicle.regime is Regime.FIXED_WING
        outputs[2] = round(1000 + 1000 * self._throttle()) if forward else 1000
        outputs[4:8] = [1500 if lifting else 1000] * 4
        return outputs

    # -- modes -------------------------------------------------------------------------------

    def _enter_mode(self, mode: str) -> bool:
        v = self.vehicle
        if mode in self.NOT_SIMULATED:
            return False
        self._guided_vtol = self._guided_takeoff = self._airbrake = self._returning = self._position1 = False
        if mode in ("QSTABILIZE", "QHOVER", "QLOITER"):
            v.hover()
        elif mode == "QLAND":
            self._start_landing()
        elif mode == "QRTL":
            if self.home is None:
                return False
            self._airbrake = self.flying and v.regime is Regime.FIXED_WING
            v.hover()
        elif mode == "GUIDED":
            # ModeGuided::_enter(): the guided waypoint is where the aircraft is (or will have stopped, with Q_GUIDED_MODE)
            here = v.stopping_point() if self.q_guided_mode else (v.lat, v.lon)
            self._guided_radius, self._guided_ccw = LOITER_RADIUS_M, False
            self._set_guided_wp(*here, v.alt_m)
        elif mode in ("LOITER", "CIRCLE"):
            v.orbit(v.lat, v.lon, v.alt_m, LOITER_RADIUS_M)
        elif mode == "RTL":
            if self.home is None:
                return False
            v.orbit(*self.home, max(RTL_ALT_M, v.alt_m) if self.flying else v.alt_m, LOITER_RADIUS_M)
        else:  # the pilot's fixed-wing modes
            v.cruise(v.alt_m)
        return True

    def _set_guided_wp(self, lat: float, lon: float, alt_m: float) -> None:
        """Plane::set_guided_WP(): a new guided waypoint starts in fixed-wing flight (no VTOL hover)."""
        self._guided_vtol = self._guided_takeoff = self._position1 = False
        self.vehicle.orbit(lat, lon, alt_m, self._guided_radius, self._guided_ccw)

    def _start_landing(self) -> None:
        self.vehicle.land()
        self._final_said, self._touchdown_at = False, None

    def _update_mode(self) -> None:
        v = self.vehicle
        if not self.armed:
            self._guided_takeoff = False
        self._update_transition()
        if self.mode == "GUIDED":
            self._update_guided()
        elif self.mode == "QRTL":
            self._update_qrtl()
        if v.landing:
            self._update_landing()

    def _update_transition(self) -> None:
        """SLT_Transition: VTOL_update() in VTOL modes, update() in the others."""
        if self.in_vtol_mode:
            # ready for the next fixed-wing mode: on the ground none is needed, in the air it starts over
            self.transition = TransitionState.AIRSPEED_WAIT if self.flying else TransitionState.DONE
            self._transition_started = False
            return
        if self.mode in MOTORS_OFF_MODES or not self.flying:
            self.transition = TransitionState.DONE if self.mode in MOTORS_OFF_MODES else self.transition
            return
        speed = self.vehicle.speed_m_s
        assist = self.params["Q_ASSIST_SPEED"]
        assisting = assist > 0 and speed < assist  # QuadPlane::should_assist, by Q_ASSIST_SPEED
        if assisting:
            if self.transition is not TransitionState.AIRSPEED_WAIT:
                self._text(_M.MAV_SEVERITY_INFO, f"Transition started airspeed {speed:.1f}")
            self.transition, self._transition_started = TransitionState.AIRSPEED_WAIT, True
        if self.transition is TransitionState.AIRSPEED_WAIT:
            if not self._transition_started:
                self._transition_started = True
                self._text(_M.MAV_SEVERITY_INFO, "Transition airspeed wait")
            self._timer_start = self.elapsed_s  # transition_low_airspeed_ms: the timer runs from the last wait
            if speed > self.params["AIRSPEED_MIN"] and not assisting:
                self.transition = TransitionState.TIMER
                self._text(_M.MAV_SEVERITY_INFO, f"Transition airspeed reached {speed:.1f}")
        elif self.transition is TransitionState.TIMER and self.elapsed_s - self._timer_start > self.params["Q_TRANSITION_MS"] / 1000:
            self.transition, self._transition_started = TransitionState.DONE, False
            self._text(_M.MAV_SEVERITY_INFO, "Transition done")

    def _update_guided(self) -> None:
        v = self.vehicle
        if self._guided_takeoff and v.alt_m >= v.target_alt_m - 0.1:
            self._guided_takeoff = False  # reached: the VTOL position controller holds there
        elif not self._guided_vtol and self.q_guided_mode and self.flying and (v.arrived or v.distance_to(*v.target) < self._approach_m):
            # Q_GUIDED_MODE: the VTOL approach (QPOS_POSITION1) to a hover over the point
            self._guided_vtol = self._position1 = True
            self._text(_M.MAV_SEVERITY_INFO, f"VTOL Position1 d={v.distance_to(*v.target):.1f}")
            v.hover_at(*v.target, v.target_alt_m)
        elif self._position1 and v.distance_to(*v.target) < POSITION2_M:
            self._position1 = False  # QuadPlane::vtol_position_controller: POSITION1 -> POSITION2 within 5 m of the point
            self._text(_M.MAV_SEVERITY_INFO, f"VTOL position2 started v={v.speed_m_s:.1f} d={v.distance_to(*v.target):.1f}")

    @property
    def q_guided_mode(self) -> int:
        """Q_GUIDED_MODE, as the parameter reads (PARAM_VALUE)."""
        return int(self.params["Q_GUIDED_MODE"])

    @q_guided_mode.setter
    def q_guided_mode(self, value: int) -> None:
        self.params["Q_GUIDED_MODE"] = value

    @property
    def _approach_m(self) -> float:
        return max(self._guided_radius, VTOL_APPROACH_M)

    def _update_qrtl(self) -> None:
        v = self.vehicle
        if self._airbrake and v.speed_m_s <= self._limits.mc_speed_m_s:
            self._airbrake = False
        if self._airbrake or v.landing or self.home is None or not self.flying:
            return
        if not self._returning:
            self._returning = True
            v.hover_at(*self.home, max(QRTL_ALT_M, v.alt_m))
        elif v.distance_to(*self.home) <= 2.0:
            self._text(_M.MAV_SEVERITY_INFO, "Land descend started")
            self._start_landing()

    def _update_landing(self) -> None:
        v = self.vehicle
        if not self._final_said and v.alt_m <= self._limits.land_final_alt_m and self.flying:
            self._final_said = True
            self._text(_M.MAV_SEVERITY_INFO, "Land final started")
        if not v.on_ground or not self.armed:
            self._touchdown_at = None
            return
        if self._touchdown_at is None:
            self._touchdown_at = self.elapsed_s
        elif self.elapsed_s - self._touchdown_at >= LAND_DETECT_S:
            self._text(_M.MAV_SEVERITY_INFO, "Land complete")
            self.disarm()

    def _desired_location(self) -> tuple[float, float] | None:
        return None if self.mode == "MANUAL" else self.vehicle.target

    # -- messages and commands ---------------------------------------------------------------

    def _message_handlers(self) -> dict[str, Callable[[MAVLinkMessage], None]]:
        return {**super()._message_handlers(), "SET_POSITION_TARGET_GLOBAL_INT": self._on_position_target}

    def _message_builders(self) -> dict[int, Callable[[], MAVLinkMessage | None]]:
        return {**super()._message_builders(), _M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self._msg_extended_sys_state}

    def _command_handlers(self) -> dict[int, Callable[[Command], int]]:
        modes = self.profile.modes
        return {
            **super()._command_handlers(),
            _M.MAV_CMD_DO_VTOL_TRANSITION: self._cmd_vtol_transition,
            _M.MAV_CMD_NAV_TAKEOFF: self._cmd_takeoff,
            _M.MAV_CMD_DO_REPOSITION: self._cmd_reposition,
            _M.MAV_CMD_NAV_LOITER_UNLIM: lambda cmd: self._mode_accepted(modes["LOITER"]),
            _M.MAV_CMD_NAV_RETURN_TO_LAUNCH: lambda cmd: self._mode_accepted(modes["RTL"]),
        }

    def _mode_accepted(self, number: int) -> int:
        self.set_mode(number)  # ArduPlane acks these ACCEPTED whether the mode changed or not
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_vtol_transition(self, cmd: Command) -> int:
        if self.mode != "AUTO":
            self._text(_M.MAV_SEVERITY_NOTICE, "VTOL transition only in AUTO")
            return _M.MAV_RESULT_FAILED
        state = int(cmd.params[0])
        if state == _M.MAV_VTOL_STATE_MC:
            if not self._auto_vtol:
                self._text(_M.MAV_SEVERITY_NOTICE, "Entered VTOL mode")
            self._auto_vtol = True
            return _M.MAV_RESULT_ACCEPTED
        if state == _M.MAV_VTOL_STATE_FW:
            if self._auto_vtol:
                self._text(_M.MAV_SEVERITY_NOTICE, "Exited VTOL mode")
            self._auto_vtol = False
            return _M.MAV_RESULT_ACCEPTED
        self._text(_M.MAV_SEVERITY_NOTICE, "Invalid VTOL mode")
        return _M.MAV_RESULT_FAILED

    def _cmd_takeoff(self, cmd: Command) -> int:
        height = cmd.params[6]
        if cmd.is_int:  # as a COMMAND_INT, only the vehicle-relative NED frame (z down)
            if cmd.frame != _M.MAV_FRAME_LOCAL_OFFSET_NED:
                return _M.MAV_RESULT_DENIED
            height = -height
        if self.mode != "GUIDED":
            self._text(_M.MAV_SEVERITY_INFO, "User Takeoff only in GUIDED mode")
            return _M.MAV_RESULT_FAILED
        if not self.armed:
            self._text(_M.MAV_SEVERITY_INFO, "Must be armed for takeoff")
            return _M.MAV_RESULT_FAILED
        if self.flying:
            self._text(_M.MAV_SEVERITY_INFO, "Already flying - no takeoff")
            return _M.MAV_RESULT_FAILED
        v = self.vehicle
        self._guided_vtol = self._guided_takeoff = True
        v.hover_at(v.lat, v.lon, v.alt_m + height)
        return _M.MAV_RESULT_ACCEPTED

    def _cmd_reposition(self, cmd: Command) -> int:
        lat, lon = cmd.lat_lon
        alt = cmd.params[6]
        if not valid_latlon(lat, lon) or cmd.frame not in GLOBAL_FRAMES:
            return _M.MAV_RESULT_DENIED
        # Location::sanitize() fills in a zero lat/lon or a zero relative altitude: ArduPlane refuses such a target
        if (lat == 0.0 and lon == 0.0) or (alt == 0.0 and cmd.frame not in (_M.MAV_FRAME_GLOBAL, _M.MAV_FRAME_GLOBAL_INT)):
            return _M.MAV_RESULT_DENIED
        if not int(cmd.params[1]) & _M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE and self.mode != "GUIDED":
            return _M.MAV_RESULT_FAILED
        if self.mode != "GUIDED" and not self.set_mode(self.profile.modes["GUIDED"]):
            return _M.MAV_RESULT_FAILED
        if cmd.params[2] > 0:
            self._guided_radius = cmd.params[2]
        self._guided_ccw = not (math.isnan(cmd.params[3]) or cmd.params[3] == 0.0)
        self._set_guided_wp(lat, lon, alt)  # home is at 0 m: every frame's altitude is the same here
        return _M.MAV_RESULT_ACCEPTED

    def _on_position_target(self, msg: MAVLinkMessage) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT: in GUIDED, ArduPlane takes only the altitude; never acknowledged."""
        if self.mode != "GUIDED":
            return
        if msg.coordinate_frame not in GLOBAL_FRAMES:
            self._text(_M.MAV_SEVERITY_WARNING, "Invalid coord frame in SET_POSTION_TARGET_GLOBAL_INT")  # sic
            return
        if not msg.type_mask & _M.POSITION_TARGET_TYPEMASK_Z_IGNORE:
            self.vehicle.set_target_alt(msg.alt)

    def _msg_extended_sys_state(self) -> MAVLinkMessage:
        return self._mav.extended_sys_state_encode(self.vtol_state, self.landed_state)

    def _msg_nav_controller_output(self) -> MAVLinkMessage | None:
        """Sent in every mode but MANUAL: the distance and bearing to the current target, and the altitude error."""
        target = self._desired_location()
        if target is None:
            return None
        v = self.vehicle
        distance, bearing = v.distance_to(*target), round(v.bearing_to(*target))
        return self._mav.nav_controller_output_encode(0.0, 0.0, bearing, bearing, min(round(distance), 65535), v.target_alt_m - v.alt_m, 0.0, 0.0)

    def _msg_position_target_global_int(self) -> MAVLinkMessage | None:
        target = self._desired_location()
        if target is None:
            return None
        return self._mav.position_target_global_int_encode(
            self._ms(), _M.MAV_FRAME_GLOBAL, TARGET_REPORT_MASK, e7(target[0]), e7(target[1]), self.vehicle.target_alt_m, 0, 0, 0, 0, 0, 0, 0, 0
        )


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Transition is TransitionState
    return executive.moved_attribute(__name__, name)
