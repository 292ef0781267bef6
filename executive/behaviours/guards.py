"""Guard conditions: SUCCESS when the condition holds, FAILURE (with the reason) when not.

Guards read the blackboard and nothing else; they never return RUNNING.

Unknown and stale are not healthy. Every guard says (:attr:`Guard.unknown_or_stale`, shown by the
catalogue and the guard table of docs/failsafes.md) what it does with no reading yet and with a reading older than
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
the guard passes. Each guard documents its two figures and why (docs/failsafes.md's failsafe table lists
them). A guard that has never passed fails at once: there is nothing to hold yet (the EKF before
pre-flight, a first reading). Without a clock (a guard ticked on its own) the verdict is the raw one.
"""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from executive.behaviours.base import FAILURE, SUCCESS, ExecutiveBehaviour
from executive.world.clock import Clock
from executive.world.state import Battery, EkfFlags, EkfStatus

_EPSILON_S = 1e-6  # ten ticks of 0.1 s add up to a hair under 1 s
#: The flag's bit, tested on the flags as an int: an IntFlag's ``&`` is Python code, and its class's members slow to read
#: (executive.behaviours.base.RUNNING says why); the test is the same.
_GPS_GLITCHING = int(EkfFlags.GPS_GLITCHING)


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

    #: What the guard does with no reading yet, and with a reading older than its limit (the catalogue and docs/failsafes.md say it).
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
        since = up_since if up_since is not None and up_since > received_at else received_at  # max(): a builtin call costs more
        age = heard - since
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
        return FAILURE if reason else SUCCESS


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
        return "the EKF flags a GPS glitch (GPS_GLITCHING)" if int(ekf.flags) & _GPS_GLITCHING else None


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
