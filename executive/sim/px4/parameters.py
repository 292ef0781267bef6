"""The simulated PX4's numbers: its parameters' defaults (commander_params.c, navigator, ROMFS) and timings measured on the real SITL."""

from __future__ import annotations

FORCE_ARM_DISARM = 21196  # Commander.cpp: param2 that forces a disarm (and an internal arm)
ESTIMATOR_READY_S = 3.0  # the SIH estimator's position came 2-4 s after boot (issue 12)
HOME_AMSL_M = 584.0  # the start point's altitude above sea level (ArduPilot SITL's CMAC field)
COM_OF_LOSS_T = 1.0  # offboard signal lost after this long without a setpoint
COM_FAIL_ACT_T = 5.0  # failsafe: hold this long before the action
COM_DISARM_PRFLT = 10.0  # armed without taking off: disarm this long after the spool-up
COM_SPOOLUP_TIME = 1.0  # the motors' spool-up after arming (counted before COM_DISARM_PRFLT)
MPC_XY_CRUISE = 5.0  # the multicopter's cruise speed along a straight path (m/s)
WANT_TAKEOFF_M_S = 0.3  # FlightTaskAuto: a take-off needs an upward velocity setpoint over this
COM_DISARM_LAND = 2.0  # landed: disarm after this long
MIS_TAKEOFF_ALT = 2.5  # NAV_TAKEOFF with param7 NaN: this high above home
NAV_LOITER_RAD = 80.0  # fixed-wing loiter radius
NAV_ACC_RAD = 10.0  # mission waypoint acceptance radius (multicopter)
RTL_RETURN_ALT = 60.0  # RTL flies home at least this high
ROVER_NAV_ACC_RAD = 0.5  # a rover's waypoint acceptance radius (ROMFS rc.rover_differential_defaults)
TRANSITION_AIRSPEED_M_S = 9.7  # the real standard VTOL's front transition ended at ~9.7 m/s (issue 12)
VT_B_TRANS_DUR = 4.0  # back transition: at most this long
MISSION_CHECK_S = 1.0  # after an upload, AUTO.MISSION is refused this long (issue 12)
COM_DL_LOSS_T = 10.0  # no ground-station HEARTBEAT this long: "Connection to ground station lost"
COM_OBC_LOSS_T = 5.0  # no onboard-computer HEARTBEAT this long: "Connection to mission computer lost"
#: LandDetector::UpdateVehicleAtRest: at rest once no movement for this long (and landed).
AT_REST_AFTER_S = 1.0
