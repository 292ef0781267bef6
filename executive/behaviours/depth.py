"""A sub's vertical motion: its depth, its height above the seabed (both held off the seabed floor), surfacing.

Setpoints have no ack: a setpoint action re-sends its target and watches the vehicle get there.
The current leg's waypoint comes from ``/mission/target``.
"""

from __future__ import annotations

from typing import Literal

from py_trees.common import Status

from executive.autopilot import AutopilotPort, Request
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS, TimedBehaviour
from executive.behaviours.commands import CommandAction
from executive.behaviours.motion import seabed_log
from executive.mission.model import Waypoint
from executive.world.seabed import depth_floor, depth_for_altitude
from executive.world.state import GlobalPosition, Outcome


class _VerticalSetpoint(TimedBehaviour):
    """A sub's vertical target for the current leg, held where the vehicle is when the action starts.

    The setpoint (no ack exists) is re-sent every ``resend_s`` at that same point; SUCCESS once the
    vehicle shows the target within ``tolerance_m``; FAILURE after ``timeout_s``. SUCCESS at once
    when the leg has no target of this kind.
    """

    reads = ("/mission/target", "/vehicle/position", "/vehicle/mode")
    needs = ("clock", "autopilot")
    autopilot: AutopilotPort
    what = ""
    catalogued = False
    param_docs = {"tolerance_m": "reached within this of the target"}

    def __init__(self, name: str, tolerance_m: float, timeout_s: float, resend_s: float) -> None:
        super().__init__(name)
        self.tolerance_m = tolerance_m
        self.timeout_s = timeout_s
        self.resend_s = resend_s
        self.target_m: float | None = None

    def wanted(self, waypoint: Waypoint) -> float | None:
        """The leg's target of this kind, if it has one."""
        raise NotImplementedError

    def measured(self, position: GlobalPosition) -> float | None:
        """The vehicle's current value of that kind, if known."""
        raise NotImplementedError

    def send(self, lat: float, lon: float, target_m: float) -> None:
        raise NotImplementedError

    def refuse(self) -> str | None:
        """Why the setpoint cannot be sent now (None: it can)."""
        return None

    def initialise(self) -> None:
        super().initialise()
        waypoint: Waypoint | None = self.get("/mission/target")
        self.target_m = self.wanted(waypoint) if waypoint is not None else None
        self.goal_m = self.target_m  # what is sent and judged: the target, or what of it can be flown now (ChangeDepth's floor)
        self._here: tuple[float, float] | None = None
        self._last_sent = float("-inf")

    def update(self) -> Status:
        if self.target_m is None:
            self.feedback_message = f"no {self.what} for this leg"
            return SUCCESS
        refusal = self.refuse()
        if refusal is not None:
            self.feedback_message = refusal
            return FAILURE
        position: GlobalPosition | None = self.get("/vehicle/position")
        if self._here is None and position is not None:
            self._here = (position.lat, position.lon)
        now = self.clock.now()
        goal = self.target_m if self.goal_m is None else self.goal_m
        if self._here is not None and now - self._last_sent >= self.resend_s:
            self.send(*self._here, goal)
            self._last_sent = now
        value = self.measured(position) if position is not None else None
        if value is not None and abs(value - goal) <= self.tolerance_m and self._last_sent > float("-inf"):
            self.feedback_message = f"{self.what} {value:.1f} m (target {goal:g} m)"
            return SUCCESS
        now_at = f"{value:.1f} m" if value is not None else "unknown"
        if self.elapsed > self.timeout_s:
            self.feedback_message = f"{self.what} {now_at}, target {goal:g} m, not reached after {self.timeout_s:g} s"
            return FAILURE
        self.feedback_message = f"{self.what} {now_at} -> {goal:g} m"
        return RUNNING


class ChangeDepth(_VerticalSetpoint):
    """Sub: dive (or rise) to the current leg's ``depth_m`` where the vehicle is; SUCCESS when ``/vehicle/position`` shows it.

    The depth goes as ``alt = -depth`` in the relative-altitude frame, which ArduSub takes in
    GUIDED (with the position: the vehicle holds where it was when the action started) and in
    ALT_HOLD (the depth alone). A leg with control_mode ``altitude`` or no depth: SUCCESS at once
    (ChangeAltitude's job, or nothing to do), so one tree can put both in every leg.

    The seabed floor (:func:`executive.world.seabed.depth_floor`): never deeper than ``clearance_m`` above
    the seabed as the sonar reads it. A depth the water cannot hold is, by ``too_deep``: ``hold``,
    held at the floor and the leg judged reached there (a warning with the figures, a journal event);
    ``fail``, FAILURE once the sonar shows it. With the sonar lost the descent stops where the sub
    is, RUNNING (until ``timeout_s``) until a reading comes back.
    """

    reads = (*_VerticalSetpoint.reads, "/vehicle/rangefinder")
    what = "depth"
    from_mission = {"clearance_m": "limits.altitude_m.min", "too_deep": "limits.seabed_floor"}
    param_docs = {
        **_VerticalSetpoint.param_docs,
        "clearance_m": "never closer to the seabed than this, as the sonar reads it",
        "too_deep": "a depth the water cannot hold: hold (at the floor, judged there) or fail",
    }

    def __init__(
        self,
        name: str = "Change depth",
        tolerance_m: float = 0.5,
        timeout_s: float = 120.0,
        resend_s: float = 1.0,
        clearance_m: float = 2.0,
        too_deep: Literal["hold", "fail"] = "hold",
    ) -> None:
        if too_deep not in ("hold", "fail"):
            raise ValueError(f"too_deep must be hold or fail, not {too_deep!r}")
        super().__init__(name, tolerance_m, timeout_s, resend_s)
        self.clearance_m = clearance_m
        self.too_deep = too_deep

    def initialise(self) -> None:
        super().initialise()
        self._told: str | None = None  # the floor's kind last warned of, once each

    def update(self) -> Status:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if self.target_m is None or position is None:
            return super().update()
        floor = depth_floor(-position.alt_rel_m, self.get("/vehicle/rangefinder"), self.clearance_m, self.clock.now())
        held = floor is not None and floor.depth_m < self.target_m - self.tolerance_m
        self.goal_m = round(floor.depth_m, 1) if held and floor is not None else self.target_m
        if not held or floor is None:
            return super().update()
        said = f"depth {self.target_m:g} m deeper than the water holds: {floor.why}, {self.clearance_m:g} m above it is {floor.depth_m:.1f} m"
        if floor.kind == "seabed" and self.too_deep == "fail":
            self.feedback_message = f"{said} (limits.seabed_floor: fail)"
            seabed_log.warning("%s: %s", self.name, self.feedback_message)
            return FAILURE
        if floor.kind == "lost" and self._told != "lost":
            self._last_sent = float("-inf")  # stop now, not at the next re-send
        status = super().update()
        if floor.kind == "lost":
            self._tell("lost", f"descent stopped at {floor.depth_m:.1f} m: {floor.why} (target {self.target_m:g} m)")
            if status == SUCCESS:  # holding where it is is no depth reached: wait for the sonar
                self.feedback_message = f"descent stopped at {floor.depth_m:.1f} m: {floor.why}; waiting for the sonar (target {self.target_m:g} m)"
                return RUNNING
            return status
        if floor.kind == "seabed":
            self._tell("seabed", f"{said}: held there (limits.altitude_m.min)")
            self.feedback_message = f"{self.feedback_message}; held at the seabed floor: {said}"
            if status == SUCCESS:
                seabed_log.warning("%s: leg judged at the seabed floor: %s", self.name, self.feedback_message)
        return status

    def _tell(self, kind: str, text: str) -> None:
        """A warning (a journal event) the first time the floor of this kind holds the leg."""
        if self._told != kind:
            self._told = kind
            seabed_log.warning("%s: %s", self.name, text)

    def wanted(self, waypoint: Waypoint) -> float | None:
        return None if waypoint.control_mode == "altitude" else waypoint.depth_m

    def measured(self, position: GlobalPosition) -> float | None:
        return -position.alt_rel_m

    def send(self, lat: float, lon: float, target_m: float) -> None:
        self.autopilot.hold_depth(lat, lon, depth_m=target_m)


class ChangeAltitude(_VerticalSetpoint):
    """Sub: reach the current leg's ``altitude_m`` above the seabed (control_mode ``altitude``), where the vehicle is.

    Flown as depth targets computed from the measured depth and the downward rangefinder
    (:func:`executive.world.seabed.depth_for_altitude`), re-sent every ``resend_s`` as the reading
    changes: ArduSub silently drops a terrain-frame target. With the seabed beyond the
    rangefinder's reach it dives, without overshooting, until the reading is good. Confirmed by the
    rangefinder (``/vehicle/altitude_above_bottom_m``). Other legs: SUCCESS at once. A reading
    that is invalid or silent (:func:`executive.world.seabed.depth_floor`: the sonar lost) holds the depth
    the sub is at: no descent on a sonar that says nothing.
    """

    reads = (*_VerticalSetpoint.reads, "/vehicle/altitude_above_bottom_m", "/vehicle/rangefinder")
    what = "altitude"

    def __init__(self, name: str = "Change altitude", tolerance_m: float = 0.5, timeout_s: float = 120.0, resend_s: float = 1.0) -> None:
        super().__init__(name, tolerance_m, timeout_s, resend_s)

    def wanted(self, waypoint: Waypoint) -> float | None:
        return waypoint.altitude_m if waypoint.control_mode == "altitude" else None

    def measured(self, position: GlobalPosition) -> float | None:
        value: float | None = self.get("/vehicle/altitude_above_bottom_m")
        return value

    def send(self, lat: float, lon: float, target_m: float) -> None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return
        here, reading = -position.alt_rel_m, self.get("/vehicle/rangefinder")
        floor = depth_floor(here, reading, target_m, self.clock.now())
        if floor is not None and floor.kind == "lost":  # no reading to trust (invalid, or silent): the descent stops where it is
            self.autopilot.hold_depth(lat, lon, depth_m=here)
            return
        depth = depth_for_altitude(here, reading, target_m)
        if depth is not None:
            self.autopilot.hold_depth(lat, lon, depth_m=depth)


class Surface(CommandAction):
    """Sub: come up with ArduSub's SURFACE mode; SUCCESS once the vehicle is at the surface and SURFACE is done.

    SURFACE climbs at PILOT_SPEED_UP (``climb_m_s``, 0.5 m/s by default) and hands over to
    ALT_HOLD by itself at the surface (ModeReason SURFACE_COMPLETE). Confirmed by the depth
    (``/vehicle/position``, within ``surface_m``) in any mode but SURFACE: the heartbeat may never
    show SURFACE at all when the vehicle is nearly up. Already there: SUCCESS without a command.
    Refused (no depth sensor...): FAILURE; not up after the climb's time plus ``margin_s``: FAILURE.
    """

    reads = ("/vehicle/position", "/vehicle/mode")
    outcome = Outcome.MODE
    param_docs = {
        "surface_m": "at the surface within this depth",
        "climb_m_s": "the climb rate (ArduSub's PILOT_SPEED_UP), for the time allowed",
        "margin_s": "time allowed over the climb's",
    }

    def __init__(self, name: str = "Surface", surface_m: float = 0.5, climb_m_s: float = 0.5, margin_s: float = 30.0) -> None:
        super().__init__(name, margin_s)
        self.surface_m = surface_m
        self.climb_m_s = climb_m_s
        self.margin_s = margin_s

    def _depth(self) -> float | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        return -position.alt_rel_m if position is not None else None

    def initialise(self) -> None:
        depth = self._depth()
        self.confirm_timeout_s = self.margin_s + max(0.0, depth or 0.0) / self.climb_m_s
        super().initialise()

    def request(self) -> Request:
        return self.autopilot.set_mode("SURFACE")

    def confirmed(self) -> bool:
        depth = self._depth()
        return depth is not None and depth <= self.surface_m and self.get("/vehicle/mode") != "SURFACE"

    def progress(self) -> str | None:
        depth = self._depth()
        return f"depth {depth:.1f} m in {self.get('/vehicle/mode')}" if depth is not None else "no position"
