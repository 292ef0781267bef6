"""PX4 as the simulated vehicles' autopilot: a standard VTOL (the simulated QuadPlane airframe) and a rover.

It shares what every simulated autopilot does (:mod:`executive.sim.firmware`: clock, telemetry streams,
command dispatch, mission store, fault injection) and does what PX4 does, as PX4 main (2025) behaved over
MAVLink (issue 12) and as its source reads. One module per concept: :mod:`.parameters` (the firmware's
numbers), :mod:`.modes`, :mod:`.raw_messages` (messages outside the dialect), :mod:`.streams` (what it
sends), :mod:`.mission_store`, :mod:`.base` (commander and navigator), :mod:`.vtol`, :mod:`.rover`.



- HEARTBEAT autopilot 12 (MAV_AUTOPILOT_PX4), type 22 for a standard VTOL, 10 for a rover; ``custom_mode`` packs
  the main mode in bits 16-23 and the sub mode in bits 24-31; it sits in AUTO.LOITER (0x03040000)
  from boot, on the ground too.
- Commands go from the MAVLink receiver to the commander (src/modules/mavlink/mavlink_receiver.cpp,
  handle_message_command_both): the receiver acks only its own few (message intervals, autopilot
  version, REQUEST_MESSAGE), the commander (src/modules/commander/Commander.cpp, handle_command /
  answer_command) acks the rest on its next loop, here the next :meth:`update`. MAV_CMD_DO_SET_MODE
  is acked twice: the receiver passes it on yet acks it ACCEPTED at once, then the commander's result (ACCEPTED, or TEMPORARILY_REJECTED after a
  STATUSTEXT "Switching to <mode> is currently not available", Commander::printRejectMode). A
  SET_MODE message is a DO_SET_MODE for the commander: its ack carries command 176.
- Arming is refused (TEMPORARILY_REJECTED, "Arming denied: Resolve system health failures first")
  until the estimator has a position, ~3 s after boot on the SIH simulation; param2 21196 does not
  skip the checks for a command from outside (Commander::arm runs them when ``from_external``).
  Armed and never taken off, it disarms itself after COM_SPOOLUP_TIME + COM_DISARM_PRFLT (1 + 10 s),
  "Disarmed by auto preflight disarming"; landed after a flight, after COM_DISARM_LAND (2 s), "Disarmed by
  landing" (Commander::handleAutoDisarm; defaults in src/modules/commander/commander_params.c).
- Estimator health is in ESTIMATOR_STATUS flags and SYS_STATUS health bits; there is no
  EKF_STATUS_REPORT. At rest on the ground the flags carry ESTIMATOR_CONST_POS_MODE (128) beside the
  GNSS position: 0x3ff, as the real SITL showed before arming (src/modules/ekf2/EKF/ekf_helper.cpp
  get_ekf_soln_status sets it for ``vehicle_at_rest``, which src/modules/land_detector/LandDetector.cpp
  publishes as landed and no IMU vibration for 1 s); armed, the spinning motors shake the IMU: 0x37f on
  the ground (real SITL, 0.8 s after arming) and in flight, 0x3ff again 1 s after a landing's disarm.
- Disarmed (by landing, pre-flight, a command), it goes back to the last mode a user asked for that
  does not prevent arming (Commander::disarm -> UserModeIntention::onDisarm; AUTO.RTL, AUTO.LAND and
  AUTO.PRECLAND prevent it, ModeUtil/mode_requirements.cpp; the take-off's and the mission's end in
  AUTO.LOITER count as asked): after a take-off and an RTL landing, AUTO.LOITER, as the real SITL showed.
- OFFBOARD needs a recent setpoint (SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT younger than
  COM_OF_LOSS_T = 1 s, HealthAndArmingChecks/checks/offboardCheck.cpp); a gap longer than that in
  OFFBOARD is the offboard failsafe (failsafe/failsafe.cpp checkModeFallback): without RC, POSCTL
  (holding), then AUTO.LAND after COM_FAIL_ACT_T, then it disarms on the ground.
- NAV_TAKEOFF param7 is an altitude AMSL (NaN: MIS_TAKEOFF_ALT above home): AUTO.TAKEOFF, then
  AUTO.LOITER once there (Commander::checkForMissionUpdate). Finite param5/param6 are the take-off
  point's latitude and longitude (navigator_main.cpp, VEHICLE_CMD_NAV_TAKEOFF; NaN: here): the
  multicopter takes off only if the straight climb towards it asks for more than 0.3 m/s upwards
  (flight_mode_manager FlightTaskAuto.cpp ``_want_takeoff``, FlightTask::_checkTakeoff): 0, 0, a point
  thousands of kilometres off, is ACCEPTED, shows AUTO.TAKEOFF and never climbs (as the real SITL did)
  until the pre-flight auto-disarm. DO_REPOSITION needs the change-mode
  flag (else UNSUPPORTED) and flies to the point in AUTO.LOITER.
- Missions: the upload is driven with MISSION_REQUEST_INT and item 0 is the first item (no home
  slot); AUTO.MISSION is refused for ~1 s after the upload while PX4 checks it; a finished mission
  shows MISSION_CURRENT mission_state 5 (COMPLETE) and the vehicle loiters (AUTO.LOITER) in the air.
- MAV_CMD_DO_VTOL_TRANSITION in flight: EXTENDED_SYS_STATE vtol_state 3 (MC) -> 1 (TRANSITION_TO_FW)
  -> 4 (FW) once the airspeed reaches ~9.7 m/s (as the real standard VTOL did), and 2
  (TRANSITION_TO_MC) -> 3 back. In FW, holding a point is circling it at NAV_LOITER_RAD (80 m).
- It watches the HEARTBEATs of ground stations and mission computers (Commander::dataLinkCheck): after
  COM_DL_LOSS_T (10 s) without one from a GCS, "Connection to ground station lost"; after COM_OBC_LOSS_T
  (5 s) without one from an onboard controller (the executive), "Connection to mission computer lost";
  each says "... regained" when they resume. With NAV_DLL_ACT at its default (disabled) nothing else happens.
- Messages outside the ardupilotmega dialect go out as raw MAVLink 2 frames (CURRENT_EVENT_SEQUENCE
  411, TIME_ESTIMATE_TO_TARGET 380), and OPEN_DRONE_ID_LOCATION; STATUSTEXTs over 50 bytes go in
  chunks sharing an ``id`` (``chunk_seq`` 0, 1...).

Not simulated, or simplified: RC (so the manual modes, POSCTL included, cannot be selected), velocity
and acceleration setpoints (they keep OFFBOARD alive; the vehicle holds), events (EVENT, 410), the
return to OFFBOARD when the stream comes back during the failsafe, parameters; RTL flies straight to
home at RTL_RETURN_ALT (no climb first, no descent stage); in fixed-wing flight every point is
circled at NAV_LOITER_RAD and a waypoint counts as reached on that circle; the failsafe texts are
ours (PX4 reports them as events); unknown mission items are passed over.
"""
