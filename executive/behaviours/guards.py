"""Guard conditions: SUCCESS when the condition holds, FAILURE (with the reason) when not.

Guards read the blackboard and nothing else; they never return RUNNING.

Unknown and stale are not healthy. Every guard says (:attr:`Guard.unknown_or_stale`, shown by the
catalogue and README's guard table) what it does with no reading yet and with a reading older than
its limit. A reading is *stale* when the autopilot has been heard (its HEARTBEAT) for longer than
the limit since it arrived, counted from when the link last came up if that is later
(:meth:`Guard.stale`): the autopilot talks but no longer says it. While no heartbeat arrives at
all, no reading can: the age stops growing and Link alive? (link_loss) stands for them all, so a
link loss is one failsafe with its own reaction, not one per reading. Each limit is a few of the
intervals the executive asks the autopilot for (:data:`executive.io.mavlink.streams.DEFAULT_RATES`,
SET_MESSAGE_INTERVAL), and covers a firmware that refused them and streams at its own default
(ArduRover and ArduPlane: 1 Hz per stream group, ``AP_MAV_DEFAULT_STREAM_RATE_*`` in
libraries/GCS_MAVLink/GCS_MAVLink_Parameters.cpp). A guard that passes without being able to judge
says so in its feedback, and its ``unknown_or_stale`` says why that is safe.

Every guard is debounced in vehicle time (the injected clock), so that its failsafe never flaps:
once it has passed, a condition must fail for ``hold_after_s`` before the guard fails (a shorter
bad spell passes, with a note), and once failed it must hold again for ``resume_after_s`` before
the guard passes. Each guard documents its two figures and why (the README's failsafe table lists
them). A guard that has never passed fails at once: there is nothing to hold yet (the EKF before
pre-flight, a first reading). Without a clock (a guard ticked on its own) the verdict is the raw one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, Protocol

from py_trees.common import Status

from executive.behaviours.base import ExecutiveBehaviour
from executive.clock import Clock
from executive.geo import distance
from executive.geofence import Geofence
from executive.mission.model import Mission, Range, RcConfig, Waypoint
from executive.state import Battery, EkfFlags, EkfStatus, GlobalPosition, HomePosition, Rangefinder, RcSwitches, SwitchPosition

_EPSILON_S = 1e-6  # ten ticks of 0.1 s add up to a hair under 1 s

#: What a guard of the vehicle's position does without one, or with an old one (its ``unknown_or_stale``).
_POSITION_RULE = (
    "no position yet: fails; an old position: judged as it is: GLOBAL_POSITION_INT carries the EKF's estimate, and EKF ok? "
    "fails when the EKF's reports stop or lose the position"
)


class Guard(ExecutiveBehaviour):
    """A condition on the blackboard; subclasses implement :meth:`check`."""

    catalogued = False  # a base: its subclasses are the guards

    #: When this guard fails a person has the vehicle: the executive keeps its hands off.
    pilot_in_control = False

    #: Set by :meth:`check` to qualify a pass (e.g. "battery not reported yet"); shown instead of "ok".
    note: str = ""

    #: Vehicle seconds the condition must fail (after having held) before the guard fails.
    hold_after_s: float = 0.0
    #: Vehicle seconds the condition must hold again, once the guard failed, before it passes.
    resume_after_s: float = 0.0

    #: What the guard does with no reading yet, and with a reading older than its limit (the catalogue and README say it).
    unknown_or_stale: str = ""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.clock: Clock | None = None
        self._passed = False  # has held at least once: from then on a failure is debounced
        self._failed = False  # the debounced verdict is "fails" (latched until it holds for resume_after_s)
        self._bad_since: float | None = None
        self._good_since: float | None = None

    def setup(self, **services: Any) -> None:
        super().setup(**services)
        self.clock = services.get("clock")

    def awaiting_recovery(self) -> Guard:
        """This guard, judged as failed already: it passes once the condition has held for ``resume_after_s`` (a wait for a recovery)."""
        self._passed = self._failed = True
        return self

    def check(self) -> str | None:
        """``None`` when the condition holds, else why it does not (the raw reading, not debounced)."""
        raise NotImplementedError

    def stale(self, received_at: float | None, limit_s: float, what: str) -> str | None:
        """Why ``what``, received at clock time ``received_at``, is too old to judge by; None when it is not (see the module's docstring).

        Its age runs from its arrival (or from when the link last came up, if later) to the autopilot's
        last HEARTBEAT (``/link/last_heartbeat``, ``/link/up_since``: a guard calling this reads both).
        Nothing heard yet, or no arrival time: not judged here.
        """
        heard: float | None = self.get("/link/last_heartbeat")
        if heard is None or received_at is None:
            return None
        up_since: float | None = self.get("/link/up_since")
        age = heard - max(received_at, up_since if up_since is not None else received_at)
        if age > limit_s + _EPSILON_S:
            return f"{what} {age:.1f} s old while the autopilot is heard (limit {limit_s:g} s)"
        return None

    def awaits(self) -> str | None:
        """The reading this guard cannot judge without and has not had yet (pre-flight waits for it), else None."""
        return None

    def judge(self) -> str | None:
        """The debounced verdict: ``None`` when the guard passes, else why it fails (see the module's docstring).

        Judging twice at the same vehicle time gives the same verdict (the tree and the failsafe both judge).
        """
        self.note = ""
        reason = self.check()
        if self.clock is None:
            return reason
        now = self.clock.now()
        if reason is None:
            self._bad_since = None
            if not self._failed:
                self._passed = True
                return None
            self._good_since = now if self._good_since is None else self._good_since
            if now - self._good_since >= self.resume_after_s - _EPSILON_S:
                self._failed, self._good_since, self._passed = False, None, True
                return None
            return f"recovering (holds for {now - self._good_since:.1f}/{self.resume_after_s:g} s)"
        self._good_since = None
        if self._failed or not self._passed:
            self._failed = self._passed
            return reason
        self._bad_since = now if self._bad_since is None else self._bad_since
        if now - self._bad_since >= self.hold_after_s - _EPSILON_S:
            self._failed, self._bad_since = True, None
            return reason
        self.note = f"{reason} for {now - self._bad_since:.1f}/{self.hold_after_s:g} s: not yet"
        return None

    def update(self) -> Status:
        reason = self.judge()
        self.feedback_message = reason or self.note or "ok"
        return Status.FAILURE if reason else Status.SUCCESS


class LinkAlive(Guard):
    """The autopilot's heartbeat is fresh.

    Debounce: holds at once (no heartbeat for ``link_timeout_s`` is already the bad spell);
    resumes after 2 s of fresh heartbeats (two at ArduPilot's 1 Hz).
    """

    resume_after_s = 2.0
    unknown_or_stale = (
        "no heartbeat yet: fails; none for link_timeout_s (3 s: three of ArduPilot's 1 Hz heartbeats): fails. "
        "It judges silence itself, and stands for every other reading while the link is lost"
    )

    reads = ("/link/up",)

    def __init__(self, name: str = "Link alive?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        return None if self.get("/link/up") else "no heartbeat from the autopilot"


class EkfOk(Guard):
    """The EKF has a horizontal position (not constant-position mode) and its variances are sane, and the autopilot's own EKF failsafe is not on.

    Debounce: holds at once (the flags are the EKF's own filtered verdict, and a vehicle driving
    without a position must stop within the reaction budget: one tick); resumes after 3 s of a
    sane EKF (several EKF_STATUS_REPORTs in a row). The autopilot's failsafe ("EKF failsafe" until
    "EKF failsafe cleared") fails it too: its HOLD can come before the report that shows why (a
    late or lost EKF_STATUS_REPORT), and meanwhile it refuses the position modes a leg asks for.
    """

    resume_after_s = 3.0
    #: EKF_STATUS_REPORT (PX4: ESTIMATOR_STATUS) is asked at 2 Hz: 3 s is six reports missed, three at the firmware's 1 Hz default.
    stale_after_s = 3.0
    unknown_or_stale = (
        "no EKF report yet: fails; a report older than 3 s while the autopilot is heard: fails (EKF_STATUS_REPORT or ESTIMATOR_STATUS "
        "asked at 2 Hz, 1 Hz by the firmware's default: three missed at least)"
    )

    reads = ("/vehicle/ekf", "/vehicle/ekf_failsafe", "/link/last_heartbeat", "/link/up_since")

    def __init__(self, name: str = "EKF ok?", variance_threshold: float = 0.8) -> None:
        super().__init__(name)
        self.variance_threshold = variance_threshold

    def awaits(self) -> str | None:
        return "an EKF report (EKF_STATUS_REPORT)" if self.get("/vehicle/ekf") is None else None

    def check(self) -> str | None:
        ekf: EkfStatus | None = self.get("/vehicle/ekf")
        if ekf is None:
            return "no EKF status yet"
        old = self.stale(ekf.time, self.stale_after_s, "the EKF report is")
        if old is not None:
            return old
        if self.get("/vehicle/ekf_failsafe"):
            return "the autopilot's EKF failsafe is on"
        if not ekf.position_ok():
            return f"EKF has no position estimate (flags 0x{int(ekf.flags):x})"
        if not ekf.variances_ok(self.variance_threshold):
            return f"EKF variances over {self.variance_threshold}"
        return None


class GpsNotGlitching(Guard):
    """The EKF does not flag a GPS glitch (EKF_STATUS_REPORT GPS_GLITCHING); no EKF report, or a stale one, fails: it cannot tell.

    Debounce: holds at once (the EKF raises the flag only after rejecting GPS: filtered already);
    resumes after 3 s without the flag.
    """

    resume_after_s = 3.0
    stale_after_s = EkfOk.stale_after_s  # the same report
    unknown_or_stale = "as EKF ok? (the flag is in the same report): no EKF report yet, or one older than 3 s while the autopilot is heard: fails"

    reads = ("/vehicle/ekf", "/link/last_heartbeat", "/link/up_since")

    def __init__(self, name: str = "GPS not glitching?") -> None:
        super().__init__(name)

    def awaits(self) -> str | None:
        return "an EKF report (EKF_STATUS_REPORT)" if self.get("/vehicle/ekf") is None else None

    def check(self) -> str | None:
        ekf: EkfStatus | None = self.get("/vehicle/ekf")
        if ekf is None:
            return "no EKF status yet: a GPS glitch cannot be ruled out"
        old = self.stale(ekf.time, self.stale_after_s, "the EKF report is")
        if old is not None:
            return old
        return "the EKF flags a GPS glitch (GPS_GLITCHING)" if ekf.flags & EkfFlags.GPS_GLITCHING else None


class Armed(Guard):
    """The vehicle is armed (disarmed mid-mission means the RC took over).

    Debounce: none either way (0 s, 0 s): arming is a person's (or the failsafe's) act, reported by
    the heartbeat, not a noisy reading.
    """

    reads = ("/vehicle/armed",)
    pilot_in_control = True
    unknown_or_stale = "the HEARTBEAT's armed flag: before the first one, disarmed (fails); no heartbeat: Link alive? judges the silence"

    def __init__(self, name: str = "Armed?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        return None if self.get("/vehicle/armed") else "vehicle is disarmed"


class ModeIs(Guard):
    """The autopilot is in a given flight mode.

    Debounce: none (0 s, 0 s): the heartbeat's mode is a fact, and the trees use this guard as a
    condition, not as a failsafe.
    """

    reads = ("/vehicle/mode",)
    unknown_or_stale = "the HEARTBEAT's mode: before the first one, no mode (fails); no heartbeat: Link alive? judges the silence"

    def __init__(self, mode: str, name: str | None = None) -> None:
        super().__init__(name or f"Mode is {mode}?")
        self.mode = mode.upper()

    def check(self) -> str | None:
        mode = self.get("/vehicle/mode")
        return None if mode == self.mode else f"mode is {mode}, not {self.mode}"


class RcNotTakingOver(Guard):
    """The RC take-over switch is not high (a missing transmitter is not a take-over).

    Debounce: fails at once (a person wins); passes again once the switch has been back for 1 s
    (a bouncing switch does not start the work again).
    """

    resume_after_s = 1.0

    reads = ("/rc/channels",)
    pilot_in_control = True
    from_mission = {"channel": "rc.takeover_channel", "above_us": "rc.takeover_above_us"}
    unknown_or_stale = (
        "no RC report, or a stale one: passes (a missing transmitter is not a person taking over; the autopilot's own RC failsafe "
        "and mode switch still work): RC not lost? and RC fresh? (rc_loss) judge the silence"
    )

    def __init__(self, channel: int, above_us: int, name: str = "RC not taking over?") -> None:
        super().__init__(name)
        self.channel = channel
        self.above_us = above_us

    def check(self) -> str | None:
        return _takeover(self.get("/rc/channels"), self.channel, self.above_us)


class RcChannelHigh(Guard):
    """An RC channel is high (above ``above_us``): the ASV's arm switch (channel 5 high = armed)."""

    reads = ("/rc/channels",)
    from_mission = {"channel": "rc.arm_channel", "above_us": "rc.takeover_above_us"}
    unknown_or_stale = "no RC report: the channel reads 0 (fails: not high); pre-flight waits on it, RC fresh? judges a stale one"

    def __init__(self, channel: int, above_us: int, name: str | None = None) -> None:
        super().__init__(name or f"RC channel {channel} high?")
        self.channel = channel
        self.above_us = above_us

    def check(self) -> str | None:
        channels: tuple[int, ...] = self.get("/rc/channels")
        value = channels[self.channel - 1] if len(channels) >= self.channel else 0
        return None if value > self.above_us else f"RC channel {self.channel} low ({value} µs)"


def _takeover(channels: tuple[int, ...], channel: int, above_us: int) -> str | None:
    value = channels[channel - 1] if len(channels) >= channel else 0
    return f"RC channel {channel} high ({value} µs): manual take-over" if value > above_us else None


_SWC_MEANS = {SwitchPosition.UP: "MANUAL", SwitchPosition.DOWN: "aux mode"}


class RcAutoMode(Guard):
    """The operator's mode switch is in AUTO.

    Debounce: as :class:`RcNotTakingOver`: fails at once, passes after 1 s back in AUTO.

    ``source="mavlink"``: the take-over channel is not high (as :class:`RcNotTakingOver`; a missing
    transmitter is not a take-over). ``source="can"``: switch C is in the middle (AgileX: up
    MANUAL, middle AUTO, down aux mode); no switch report yet fails.
    """

    reads = ("/rc/channels", "/rc/switches")
    resume_after_s = 1.0
    pilot_in_control = True
    unknown_or_stale = (
        "mavlink: as RC not taking over? (no report or a stale one passes: not a take-over). can: no switch C position yet fails; "
        "a stale one: RC not lost? (rc_loss) fails on it"
    )
    from_mission = {"source": "rc.source", "takeover_channel": "rc.takeover_channel", "takeover_above_us": "rc.takeover_above_us"}

    def __init__(
        self, source: Literal["mavlink", "can"] = "mavlink", takeover_channel: int = 6, takeover_above_us: int = 1700, name: str = "RC in auto?"
    ) -> None:
        super().__init__(name)
        self.source = source
        self.takeover_channel = takeover_channel
        self.takeover_above_us = takeover_above_us

    def check(self) -> str | None:
        if self.source == "mavlink":
            return _takeover(self.get("/rc/channels"), self.takeover_channel, self.takeover_above_us)
        switches: RcSwitches | None = self.get("/rc/switches")
        if switches is None or switches.swc is None:
            return "no RC switch C position yet"
        if switches.swc is not SwitchPosition.MIDDLE:
            return f"RC switch C {switches.swc} ({_SWC_MEANS[switches.swc]}), not MIDDLE (AUTO)"
        return None


def rc_auto_mode(rc: RcConfig, name: str = "RC in auto?") -> RcAutoMode:
    """The :class:`RcAutoMode` guard for a mission's ``rc:`` section."""
    return RcAutoMode(rc.source, rc.takeover_channel, rc.takeover_above_us, name)


class RcFresh(Guard):
    """RC reports arrive and are not frozen, and the transmitter is there (the RC reader judges: /rc/fresh).

    Debounce: fails at once (the reader judges staleness over time already); passes after 2 s of fresh reports.
    """

    resume_after_s = 2.0
    unknown_or_stale = "no RC report yet: fails; none within rc.fresh_timeout_s (1 s: RC_CHANNELS asked at 5 Hz), or a frozen CAN counter: fails"

    reads = ("/rc/fresh", "/rc/stale_reason")

    def __init__(self, name: str = "RC fresh?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        return None if self.get("/rc/fresh") else self.get("/rc/stale_reason") or "RC is stale"


class RcNotLost(Guard):
    """The RC transmitter seen earlier is still there; never seen passes with a note (a vehicle run without RC).

    Debounce: fails at once (the autopilot reports every channel 0 only after its own RC failsafe
    timeout; the CAN reader judges staleness over time); passes after 2 s of the transmitter back.

    ``source="mavlink"``: lost when the autopilot reports every channel 0 (/rc/connected false), or
    when its RC_CHANNELS stop while the autopilot is heard (older than ``stale_after_s``); reports
    that stop with the heartbeat are the link's business (a link loss is not an RC loss).
    ``source="can"``: lost when the RC reader finds the reports stale (/rc/fresh: after a signal
    loss the base repeats its last frame, the counter frozen).
    """

    reads = ("/rc/connected", "/rc/fresh", "/rc/stale_reason", "/rc/last_update", "/link/last_heartbeat", "/link/up_since")
    resume_after_s = 2.0
    #: RC_CHANNELS is asked at 5 Hz: 3 s is fifteen missed, three at the firmware's 1 Hz default (SRn_RC_CHAN).
    stale_after_s = 3.0
    from_mission = {"source": "rc.source"}
    unknown_or_stale = (
        "never seen: passes with a note (a vehicle may run without RC; the take-over switch then cannot be thrown). Seen, then "
        "mavlink: every channel 0, or RC_CHANNELS older than 3 s while the autopilot is heard (asked at 5 Hz): fails; "
        "can: no fresh frame within rc.fresh_timeout_s or a frozen counter: fails"
    )

    def __init__(self, source: Literal["mavlink", "can"] = "mavlink", name: str = "RC not lost?") -> None:
        super().__init__(name)
        self.source = source
        self._seen = False

    def check(self) -> str | None:
        if self.get("/rc/connected" if self.source == "mavlink" else "/rc/fresh"):
            self._seen = True
            return self.stale(self.get("/rc/last_update"), self.stale_after_s, "the RC report is") if self.source == "mavlink" else None
        if not self._seen:
            self.note = "no RC seen yet"
            return None
        return "RC transmitter gone (every channel 0)" if self.source == "mavlink" else self.get("/rc/stale_reason") or "RC is stale"


class _HasLatLon(Protocol):
    lat: float
    lon: float


class TargetWithin(Guard):
    """The current leg's target (/mission/target) is within ``max_distance_m`` of the vehicle (go-to refusal, 5 km).

    Debounce: none (0 s, 0 s): a refusal of the target, not a reading to filter.
    """

    reads = ("/mission/target", "/vehicle/position")
    from_mission = {"max_distance_m": "limits.max_goal_distance_m"}
    unknown_or_stale = _POSITION_RULE

    def __init__(self, max_distance_m: float, name: str | None = None) -> None:
        super().__init__(name or f"Target within {max_distance_m:g} m?")
        self.max_distance_m = max_distance_m

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        target: _HasLatLon | None = self.get("/mission/target")
        if position is None:
            return "no position"
        if target is None:
            return "no target: no leg is active"
        d = distance(position.lat, position.lon, target.lat, target.lon)
        return f"target is {d:.0f} m away, over {self.max_distance_m:g} m" if d > self.max_distance_m else None


class PositionKnown(Guard):
    """The autopilot reports where the vehicle is (/vehicle/position: a GLOBAL_POSITION_INT with a fix).

    Debounce: none (0 s, 0 s): used to wait for the first position.
    """

    reads = ("/vehicle/position",)
    unknown_or_stale = _POSITION_RULE

    def __init__(self, name: str = "Position known?") -> None:
        super().__init__(name)

    def awaits(self) -> str | None:
        return "a position (GLOBAL_POSITION_INT)" if self.get("/vehicle/position") is None else None

    def check(self) -> str | None:
        return None if self.get("/vehicle/position") is not None else "no position"


class AllWaypointsWithin(Guard):
    """Every waypoint is within ``max_distance_m`` of the vehicle's live position (the AUV's 1 km rule).

    Debounce: none (0 s, 0 s): judged once, to accept or refuse the mission.

    Each verdict is remembered with the position it was computed at: while every waypoint was
    within ``max_distance_m - moved`` there, the triangle inequality says they still are, and
    the waypoints are not measured again (a long route costs one distance per tick).
    """

    reads = ("/vehicle/position",)
    from_mission = {"waypoints": "waypoints", "max_distance_m": "limits.max_goal_distance_m"}
    unknown_or_stale = _POSITION_RULE

    def __init__(self, waypoints: Sequence[_HasLatLon], max_distance_m: float, name: str | None = None) -> None:
        super().__init__(name or f"All waypoints within {max_distance_m:g} m?")
        self.waypoints = tuple(waypoints)
        self.max_distance_m = max_distance_m
        self._measured: tuple[float, float, float] | None = None  # lat, lon, farthest waypoint there

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        if self._measured is not None:
            lat, lon, farthest = self._measured
            if farthest + distance(lat, lon, position.lat, position.lon) <= self.max_distance_m:
                return None
        self._measured = None
        farthest = 0.0
        for i, wp in enumerate(self.waypoints):
            d = distance(position.lat, position.lon, wp.lat, wp.lon)
            if d > self.max_distance_m:
                named = f" ({wp.name})" if getattr(wp, "name", None) else ""
                return f"waypoint {i}{named} is {d:.0f} m away, over {self.max_distance_m:g} m"
            farthest = max(farthest, d)
        self._measured = (position.lat, position.lon, farthest)
        return None


class RangefinderReaches(Guard):
    """The downward rangefinder can measure every altitude leg's height above the seabed (a mission's pre-flight check).

    Its range is what the autopilot reports in DISTANCE_SENSOR (min/max_distance: ArduPilot's
    RNGFND1_MIN and RNGFND1_MAX). An altitude leg is flown from the measured height
    (:mod:`executive.seabed`), so each ``altitude_m`` must lie ``margin_m`` inside that range;
    otherwise it fails naming the waypoint, the parameter and the value it needs. No downward
    rangefinder reported fails too. A route without altitude legs passes.

    Debounce: none (0 s, 0 s): judged once, to accept or refuse the mission.
    """

    reads = ("/vehicle/rangefinder",)
    from_mission = {"waypoints": "waypoints"}
    unknown_or_stale = (
        "no downward DISTANCE_SENSOR yet: fails (with an altitude leg); any age is fine: the range it checks is the sensor's "
        "configuration (RNGFND1_MIN/MAX), which does not age"
    )
    param_docs = {"margin_m": "how far inside the rangefinder's range each altitude leg's height must be"}

    def __init__(self, waypoints: Sequence[Waypoint], margin_m: float = 1.0, name: str = "Rangefinder reaches the altitude legs?") -> None:
        super().__init__(name)
        self.legs = [(i, wp) for i, wp in enumerate(waypoints) if wp.control_mode == "altitude" and wp.altitude_m is not None]
        self.margin_m = margin_m

    def check(self) -> str | None:
        if not self.legs:
            self.note = "no altitude leg"
            return None
        reading: Rangefinder | None = self.get("/vehicle/rangefinder")
        if reading is None:
            return "no downward rangefinder reported (DISTANCE_SENSOR, PITCH_270): an altitude leg needs one (RNGFND1_TYPE, RNGFND1_ORIENT 25)"
        for i, wp in self.legs:
            assert wp.altitude_m is not None
            named = f"waypoint {i}{f' ({wp.name})' if wp.name else ''} keeps {wp.altitude_m:g} m above the seabed"
            if wp.altitude_m + self.margin_m > reading.max_m:
                return f"{named}: the rangefinder reads to {reading.max_m:g} m: set RNGFND1_MAX to at least {wp.altitude_m + self.margin_m:g} m"
            if wp.altitude_m - self.margin_m < reading.min_m:
                return f"{named}: the rangefinder reads from {reading.min_m:g} m: set RNGFND1_MIN to at most {wp.altitude_m - self.margin_m:g} m"
        return None


def _speed(position: GlobalPosition | None, ground_speed: float | None) -> float | None:
    return position.ground_speed_m_s if position is not None else ground_speed


class SpeedWithin(Guard):
    """The vehicle is not faster than the mission allows.

    Debounce: fails after 2 s over the limit (a current, a wave or a settling speed controller
    overshoots briefly); passes after 2 s within it.

    Rule: FAILURE when the ground speed exceeds ``limit.max`` by more than
    ``max(tolerance_m_s, tolerance_fraction * limit.max)`` (an autopilot overshoots a little while
    settling on a speed). ``limit.min`` is never enforced: a vehicle is slower while accelerating,
    turning, holding or at a waypoint. The speed is the EKF's (/vehicle/position, horizontal),
    else VFR_HUD's (/vehicle/ground_speed_m_s); neither reported fails.
    """

    reads = ("/vehicle/position", "/vehicle/ground_speed_m_s")
    unknown_or_stale = (
        "no speed yet (no GLOBAL_POSITION_INT, no VFR_HUD): fails; an old one: judged as it is (the EKF's estimate: EKF ok? fails "
        "when its reports stop or lose the position)"
    )
    hold_after_s = 2.0
    resume_after_s = 2.0
    from_mission = {"limit": "limits.speed_m_s"}
    param_units = {"limit": "m/s"}
    param_docs = {
        "limit": "allowed speeds {min, max}: only max is enforced",
        "tolerance_m_s": "overshoot allowed over max, at least",
        "tolerance_fraction": "overshoot allowed over max, as a fraction of it, at least",
    }

    def __init__(self, limit: Range, tolerance_m_s: float = 0.3, tolerance_fraction: float = 0.1, name: str | None = None) -> None:
        super().__init__(name or f"Speed within {limit.max:g} m/s?")
        self.limit = limit
        self.allowed_m_s = limit.max + max(tolerance_m_s, tolerance_fraction * limit.max)

    def check(self) -> str | None:
        speed = _speed(self.get("/vehicle/position"), self.get("/vehicle/ground_speed_m_s"))
        if speed is None:
            return "speed not reported yet (no GLOBAL_POSITION_INT, no VFR_HUD)"
        if speed > self.allowed_m_s:
            return f"speed {speed:.1f} m/s over the limit {self.limit.max:g} m/s"
        return None


def _outside(value: float, limit: Range, tolerance: float) -> bool:
    return not limit.min - tolerance <= value <= limit.max + tolerance


class DepthWithin(Guard):
    """A sub's depth (-/vehicle/position.alt_rel_m) is in ``limit``, give or take ``tolerance_m`` (waves, sensor noise).

    Debounce: fails after 1 s outside (a wave, a pressure spike); passes after 2 s inside.
    """

    hold_after_s = 1.0
    resume_after_s = 2.0
    unknown_or_stale = _POSITION_RULE

    reads = ("/vehicle/position",)
    from_mission = {"limit": "limits.depth_m"}
    param_units = {"limit": "m"}

    def __init__(self, limit: Range, tolerance_m: float = 0.5, name: str | None = None) -> None:
        super().__init__(name or f"Depth within [{limit.min:g}, {limit.max:g}] m?")
        self.limit = limit
        self.tolerance_m = tolerance_m

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        depth = -position.alt_rel_m
        if _outside(depth, self.limit, self.tolerance_m):
            return f"depth {depth:.1f} m outside [{self.limit.min:g}, {self.limit.max:g}] m"
        return None


class AltitudeWithin(Guard):
    """A sub's height above the seabed (/vehicle/altitude_above_bottom_m) is in ``limit``, give or take ``tolerance_m``.

    Debounce: fails after 2 s without a good reading or outside (an echo sounder drops single
    pings over weed, fish or a steep slope); passes after 2 s of good readings inside.

    No valid rangefinder reading (none yet, too close, invalid) fails: the guard cannot tell the
    seabed is far enough. A seabed beyond the rangefinder's maximum (/vehicle/rangefinder too_far)
    is at least that far: it passes with a note when that maximum is within the limit (the
    sub dives to its altitude from there), and fails when the maximum is over the limit's top.
    ``altitude_legs_only``: judged only while the current leg (/mission/target) has control_mode
    ``altitude``; on other legs it passes with a note. A reading older than ``stale_after_s`` while
    the autopilot is heard fails too: the height it gave is no longer known.
    """

    reads = (
        "/vehicle/altitude_above_bottom_m",
        "/vehicle/rangefinder",
        "/vehicle/altitude_last_update",
        "/mission/target",
        "/link/last_heartbeat",
        "/link/up_since",
    )
    hold_after_s = 2.0
    resume_after_s = 2.0
    #: DISTANCE_SENSOR is asked at 5 Hz for a sub (ten missed); ArduSub streams it at 3 Hz by default (SRn_EXTRA3).
    stale_after_s = 2.0
    unknown_or_stale = (
        "no valid rangefinder reading yet: fails (the seabed beyond the sonar's range is a reading: at least that far); one older "
        "than 2 s while the autopilot is heard: fails (DISTANCE_SENSOR asked at 5 Hz)"
    )
    from_mission = {"limit": "limits.altitude_m"}
    param_units = {"limit": "m"}
    param_docs = {"altitude_legs_only": "judged only on legs with control_mode altitude (others pass with a note)"}

    def __init__(self, limit: Range, tolerance_m: float = 0.5, name: str | None = None, altitude_legs_only: bool = False) -> None:
        default = f"Altitude within [{limit.min:g}, {limit.max:g}] m{' on altitude legs' if altitude_legs_only else ''}?"
        super().__init__(name or default)
        self.limit = limit
        self.tolerance_m = tolerance_m
        self.altitude_legs_only = altitude_legs_only

    def check(self) -> str | None:
        if self.altitude_legs_only:
            target: Waypoint | None = self.get("/mission/target")
            if target is None or target.control_mode != "altitude":
                self.note = "not an altitude leg"
                return None
        old = self.stale(self.get("/vehicle/altitude_last_update"), self.stale_after_s, "the rangefinder reading is")
        if old is not None:
            return old
        altitude: float | None = self.get("/vehicle/altitude_above_bottom_m")
        reading: Rangefinder | None = self.get("/vehicle/rangefinder")
        if altitude is None and reading is not None and reading.status == "too_far":
            if reading.max_m > self.limit.max + self.tolerance_m:
                return f"the seabed is beyond the rangefinder's {reading.max_m:g} m: over {self.limit.max:g} m below"
            if reading.max_m >= self.limit.min - self.tolerance_m:
                self.note = f"the seabed is beyond the rangefinder's {reading.max_m:g} m: at least that far"
                return None
        if altitude is None:
            return "no altitude above the seabed (no valid rangefinder reading)"
        if _outside(altitude, self.limit, self.tolerance_m):
            return f"altitude {altitude:.1f} m above the seabed outside [{self.limit.min:g}, {self.limit.max:g}] m"
        return None


class HeadingSane(Guard):
    """The heading filter trusts the compass (/heading/ok); not judged yet passes with a note, an attitude gone stale fails.

    Debounce: fails at once (the filter judges the compass over time already: a bias estimate, repeated
    rejections); passes after 3 s of trust.

    The filter judges the compass against the course over ground, which needs straight driving: a
    vehicle standing still, or just started, has not been judged. That passes, with a note: the
    autopilot's own compass checks (pre-arm, the EKF's compass variance in EKF ok?) stand meanwhile.
    The attitude the filter is fed (ATTITUDE) older than ``stale_after_s`` while the autopilot is
    heard fails: the filter has nothing to judge by.
    """

    resume_after_s = 3.0
    #: ATTITUDE is asked at 10 Hz (twenty missed); the filter itself drops an attitude this old (HeadingFilterConfig.stale_after_s).
    stale_after_s = 2.0
    unknown_or_stale = (
        "not judged yet (no straight driving yet to compare the compass with the course): passes with a note, the autopilot's own "
        "compass checks and EKF ok?'s compass variance stand meanwhile; an ATTITUDE older than 2 s while the autopilot is heard "
        "(asked at 10 Hz): fails"
    )

    reads = ("/heading/ok", "/heading/reason", "/heading/bias_deg", "/heading/last_update", "/link/last_heartbeat", "/link/up_since")

    def __init__(self, name: str = "Heading sane?") -> None:
        super().__init__(name)

    def check(self) -> str | None:
        old = self.stale(self.get("/heading/last_update"), self.stale_after_s, "the attitude (ATTITUDE) is")
        if old is not None:
            return old
        ok: bool | None = self.get("/heading/ok")
        if ok is None:
            self.note = "not judged yet"
            return None
        if ok:
            bias: float | None = self.get("/heading/bias_deg")
            if bias is not None and abs(bias) >= 3.0:
                self.note = f"compass bias {bias:+.1f}° compensated"
            return None
        return self.get("/heading/reason") or "the heading filter does not trust the compass"


class BatteryAbove(Guard):
    """The battery is above ``floor_pct`` remaining and ``floor_v`` volts (either None: not checked).

    Debounce: fails after 2 s below (the voltage sags for a moment when the motors pull hard);
    passes after 5 s above (a sagging battery recovers while resting).

    A value a floor needs that the autopilot does not report fails: no SYS_STATUS yet, an 'unknown'
    field (battery_remaining -1: ArduPilot knows the remaining capacity only with a current
    monitor and BATT_CAPACITY), or a report older than ``stale_after_s`` while the autopilot is heard.
    """

    reads = ("/vehicle/battery", "/link/last_heartbeat", "/link/up_since")
    hold_after_s = 2.0
    resume_after_s = 5.0
    #: SYS_STATUS is asked at 1 Hz, ArduPilot's default too (SRn_EXT_STAT): 5 s is five reports missed.
    stale_after_s = 5.0
    unknown_or_stale = (
        "no SYS_STATUS yet, or the field a floor needs unknown (battery_remaining -1, voltage 65535): fails (pre-flight waits for it, "
        "then refuses; limits.battery_min_pct: null flies on voltage alone); a report older than 5 s while the autopilot is heard "
        "(asked at 1 Hz): fails"
    )
    from_mission = {"floor_pct": "limits.battery_min_pct", "floor_v": "limits.battery_min_v"}
    param_docs = {"floor_pct": "remaining battery below this fails (null: not checked)", "floor_v": "voltage below this fails (null: not checked)"}

    def __init__(self, floor_pct: float | None, floor_v: float | None = None, name: str = "Battery above floor?") -> None:
        super().__init__(name)
        self.floor_pct = floor_pct
        self.floor_v = floor_v

    def _unknown(self, battery: Battery) -> list[str]:
        """What a floor needs that this report leaves unknown."""
        fields = (("remaining % (battery_remaining)", self.floor_pct, battery.remaining_pct), ("voltage", self.floor_v, battery.voltage_v))
        return [what for what, floor, value in fields if floor is not None and value is None]

    def awaits(self) -> str | None:
        battery: Battery | None = self.get("/vehicle/battery")
        if battery is None:
            return "a battery report (SYS_STATUS)"
        unknown = self._unknown(battery)
        if not unknown:
            return None
        # ArduPilot's BATT_MONITOR defaults to none (AP_BattMonitor_Params.cpp): SYS_STATUS then says -1 (GCS_Common.cpp
        # battery_remaining_pct); seen on real ArduPlane QuadPlane SITL, whose default parameters set no monitor
        return (
            f"the battery's {' and '.join(unknown)} (SYS_STATUS reports it unknown: set the autopilot's battery monitor, "
            "ArduPilot BATT_MONITOR, or fly without this floor: limits.battery_min_pct: null)"
        )

    def check(self) -> str | None:
        battery: Battery | None = self.get("/vehicle/battery")
        if battery is None:
            return "battery not reported yet (no SYS_STATUS)"
        old = self.stale(battery.time, self.stale_after_s, "the battery report (SYS_STATUS) is")
        if old is not None:
            return old
        pct, volts = battery.remaining_pct, battery.voltage_v
        if self.floor_pct is not None and pct is not None and pct < self.floor_pct:
            return f"battery {pct}% below {self.floor_pct:g}%"
        if self.floor_v is not None and volts is not None and volts < self.floor_v:
            return f"battery {volts:.2f} V below {self.floor_v:g} V"
        unknown = self._unknown(battery)
        if unknown:
            return f"battery {' and '.join(unknown)} unknown: the floor cannot be checked"
        return None


class InsideGeofence(Guard):
    """The vehicle is inside ``fence``: its polygon, and its maximum distance from home.

    Debounce: fails at once (the EKF's position is filtered already, and outside is outside);
    passes after 2 s inside.

    Home is the autopilot's (/vehicle/home: where RTL goes and what its own fence measures from),
    else ``mission_home`` until the autopilot reports one; with neither, a fence with a maximum
    distance fails ("no home to measure the distance from").
    """

    reads = ("/vehicle/position", "/vehicle/home")
    resume_after_s = 2.0
    from_mission = {"fence": "geofence", "mission_home": "home"}
    unknown_or_stale = _POSITION_RULE + "; no home (the autopilot's or the mission's) with a maximum distance: fails"
    param_docs = {"fence": "the mission's geofence: section", "mission_home": "the mission's home, until the autopilot reports one"}

    def __init__(self, fence: Geofence, mission_home: tuple[float, float] | None = None, name: str = "Inside geofence?") -> None:
        super().__init__(name)
        self.fence = fence
        self.mission_home = mission_home

    def awaits(self) -> str | None:
        return "a position (GLOBAL_POSITION_INT)" if self.get("/vehicle/position") is None else None

    def check(self) -> str | None:
        position: GlobalPosition | None = self.get("/vehicle/position")
        if position is None:
            return "no position"
        home: HomePosition | None = self.get("/vehicle/home")
        return self.fence.why_outside(position.lat, position.lon, (home.lat, home.lon) if home else self.mission_home)


def inside_geofence(mission: Mission, name: str = "Inside geofence?") -> InsideGeofence | None:
    """The :class:`InsideGeofence` guard for a mission's ``geofence:`` section; None without one."""
    if mission.geofence is None:
        return None
    home = (mission.home.lat, mission.home.lon) if mission.home else None
    return InsideGeofence(mission.geofence.fence(), home, name)
