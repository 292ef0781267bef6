"""Whose is the point the autopilot steers to: ours, or a person's (a ground station's Pause or Go-to).

A ground station can steer the vehicle without changing its mode: QGroundControl's Pause on PX4 is
MAV_CMD_DO_REPOSITION with a NaN position (PX4FirmwarePlugin::pauseVehicle; PX4 answers no
DO_PAUSE_CONTINUE), its Go-to a DO_REPOSITION with a point, and on ArduPilot in GUIDED a DO_REPOSITION,
a SET_POSITION_TARGET_GLOBAL_INT or a MISSION_ITEM with current=2 moves the GUIDED target. PX4 stays
in AUTO.LOITER, ArduPilot in GUIDED: the very modes the executive's legs fly in. What shows it is the
target the autopilot reports, POSITION_TARGET_GLOBAL_INT:

- PX4: the navigator's current setpoint (src/modules/mavlink/streams/POSITION_TARGET_GLOBAL_INT.hpp,
  sent while position control is on; 10 Hz on the onboard link, mavlink_main.cpp). A DO_REPOSITION
  sets it (navigator_main.cpp, VEHICLE_CMD_DO_REPOSITION: NaN lat/lon is the vehicle's position, or
  its stopping point on a multicopter; Loiter::reposition copies it to the setpoint).
- ArduRover: the mode's desired location (Rover/GCS_MAVLink_Rover.cpp send_position_target_global_int,
  ModeGuided::get_desired_location), in the EXTENDED_STATUS stream (GCS_MAVLink_Parameters.cpp).

Told apart from the autopilot's own: only the mode that follows our point is judged (the mode asked with it: GUIDED,
PX4's AUTO.LOITER for a reposition); other modes steer by themselves (PX4's RTL moves its setpoint from stage to
stage, navigator/rtl_direct.cpp), and in them nothing is judged. The autopilot sets a target of its own only when a mode starts
(PX4's Loiter::on_activation -> set_loiter_position, navigator/loiter.cpp; its take-off, RTL, mission;
ArduRover's ModeGuided::_enter, a stop): in a mode whose target it has reported as ours, with no mode
change since, neither firmware moves it by itself (PX4 changes the loiter setpoint only on a
reposition, Loiter::on_active; ArduRover's GUIDED target only on a GCS message, Rover/GCS_MAVLink_Rover.cpp
and GCS_Common.cpp handle_command_int_do_reposition). So: once the autopilot reports the point we
asked (ours, adopted), a report of another point, with the mode unchanged and no new ask of ours, is
a person's. Before that (a report of the previous target still on its way, PX4's stale or absent
setpoint in OFFBOARD, a local-frame setpoint) nothing is judged. Not covered: ArduRover's object
avoidance (OA_TYPE, off by default) reports its detour as the desired location.
"""

from __future__ import annotations

from dataclasses import dataclass

from executive.world import geo
from executive.world.state import GlobalPosition, PositionTarget, TargetAsk

#: A reported point this close to ours is ours (the report's 1e-7 degree resolution, PX4's float setpoint).
SAME_POINT_M = 1.0
#: A person's target this close to the vehicle holds it where it is (a Pause: PX4's reposition to its position, or
#: a multicopter's stopping point): at least this far, or as far as the vehicle goes in :data:`HELD_WITHIN_S`.
HELD_WITHIN_M = 10.0
HELD_WITHIN_S = 3.0


@dataclass(frozen=True, slots=True)
class PersonsTarget:
    """A target the autopilot reports that the executive did not ask for: where, and whether it holds the vehicle where it is."""

    lat: float
    lon: float
    held: bool  # within reach of where the vehicle was: a pause, not a go-to

    @property
    def what(self) -> str:
        """``held the vehicle (reposition to its position)`` or ``sent it to 47.39712, 8.54562``."""
        if self.held:
            return "held the vehicle (reposition to its position)"
        return f"sent it to {self.lat:.5f}, {self.lon:.5f}"


class TargetWatch:
    """Judges each new POSITION_TARGET_GLOBAL_INT against the point we asked last; call :meth:`judge` once per tick."""

    def __init__(self) -> None:
        self._adopted: TargetAsk | None = None  # our ask the autopilot has reported since the last mode change
        self._report: PositionTarget | None = None  # the last report judged
        self._mode: str | None = None
        #: Who set the reported target: ``us``, ``others``, or None (not judged).
        self.set_by: str | None = None

    def forget(self) -> None:
        """Nothing of ours is adopted any more (a resume: the leg's target goes out again and is judged from its report)."""
        self._adopted, self.set_by = None, None

    def judge(self, mode: str, report: PositionTarget | None, asked: TargetAsk | None, position: GlobalPosition | None) -> PersonsTarget | None:
        """A person's target, the first time the autopilot reports one; None otherwise (ours, not judged, or already said)."""
        if mode != self._mode:
            self._mode = mode
            self.forget()  # a new mode starts with a target of its own (the autopilot's): ours counts again once reported
        if self.set_by == "us" and asked is not self._adopted:
            self.set_by = None  # a new ask of ours, not reported yet
        if report is None or report is self._report:
            return None
        self._report = report
        if asked is None or asked.lat is None or asked.lon is None or asked.mode != mode:
            self.forget()  # nothing of ours to judge by in this mode: another mode's own targets (PX4's RTL stages) are its own
            return None
        if geo.distance(report.lat, report.lon, asked.lat, asked.lon) <= SAME_POINT_M:
            self._adopted, self.set_by = asked, "us"
            return None
        if self._adopted is not asked:
            self.set_by = None  # ours not reported yet (the previous target's report on its way), or never: nothing to judge
            return None
        if self.set_by == "others":
            return None
        self.set_by = "others"
        return PersonsTarget(report.lat, report.lon, _holds(report, position))


def _holds(report: PositionTarget, position: GlobalPosition | None) -> bool:
    if position is None:
        return False
    reach = max(HELD_WITHIN_M, HELD_WITHIN_S * position.ground_speed_m_s)
    return geo.distance(report.lat, report.lon, position.lat, position.lon) <= reach
