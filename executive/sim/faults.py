"""Fault injection into the simulated vehicle: how the executive's failsafes are exercised.

A fault file (YAML, version 1) lists faults, each starting ``at_s`` seconds of simulated time after
the vehicle boots and lasting ``for_s`` seconds (or to the end)::

    version: 1
    faults:
      - {kind: link_loss, at_s: 60, for_s: 8}
      - {kind: rc_takeover, at_s: 90, for_s: 10, mode: MANUAL}

:func:`load_faults` validates it strictly, every error located as ``FILE:LINE:COL: FIELD: message``.
A :class:`FaultInjector` applies the faults: :class:`~executive.sim.server.SimServer` asks it each
iteration whether the link is up each way, lets it rewrite or drop the outgoing messages, and lets
it change the autopilot where a fault changes what the vehicle does (RC channels, mode, arming,
steering on a wrong compass), once at the start and end of a fault.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Iterable, Sequence
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from executive.io.mavlink.modes import PX4_MODES
from executive.mission.declaration import kind_spec, vehicle_profile
from executive.mission.errors import MissionError, Path
from executive.mission.loader import load_model
from executive.sim.firmware import FirmwareSim
from executive.world import geo
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.vehicles import PROFILES

log = logging.getLogger(__name__)

_STRICT = ConfigDict(strict=True, extra="forbid", frozen=True, allow_inf_nan=False)
_M = mavlink

MAX_TIME_S = 1e6
RC_FAILSAFE_TIMEOUT_S = 1.5  # ArduRover's FS_TIMEOUT default: RC lost this long before its failsafe acts
GLITCH_POS_VARIANCE = 1.0  # a GPS the EKF rejects: its position test ratio is over 1
MODE_NAME = r"^[A-Z][A-Z0-9_]*(\.[A-Z][A-Z0-9_]*)?$"  # ArduPilot's MANUAL, PX4's AUTO.LOITER


class _Fault(BaseModel):
    """What every fault has: when it starts and how long it lasts."""

    model_config = _STRICT
    at_s: float = Field(ge=0.0, le=MAX_TIME_S, description="start, seconds of simulated time after the vehicle boots")
    for_s: float | None = Field(None, gt=0.0, le=MAX_TIME_S, description="duration in seconds; omitted = until the end")

    @property
    def end_s(self) -> float:
        """When the fault ends (infinity if it never does)."""
        return math.inf if self.for_s is None else self.at_s + self.for_s


class LinkLoss(_Fault):
    """The vehicle's MAVLink link goes silent: uplink = the vehicle hears nothing, downlink = it sends nothing."""

    kind: Literal["link_loss"]
    direction: Literal["both", "uplink", "downlink"] = "both"


class EkfDegradation(_Fault):
    """EKF_STATUS_REPORT variances raised to ``variance``; with ``lose_position`` the horizontal position is lost."""

    kind: Literal["ekf_degradation"]
    variance: float = Field(1.0, ge=0.0, le=100.0, description="velocity/position/compass variances at least this (FS_EKF_THRESH is 0.8)")
    lose_position: bool = Field(False, description="flags lose POS_HORIZ_ABS and gain CONST_POS_MODE; position modes are refused")


class GpsGlitch(_Fault):
    """The reported position jumps ``offset_m`` toward ``bearing_deg``; the EKF flags GPS_GLITCHING."""

    kind: Literal["gps_glitch"]
    offset_m: float = Field(gt=0.0, le=100_000.0)
    bearing_deg: float = Field(0.0, ge=0.0, lt=360.0)


class CompassBias(_Fault):
    """The heading reads ``bias_deg`` too much, and the vehicle steers by it (so it really heads ``bias_deg`` off)."""

    kind: Literal["compass_bias"]
    bias_deg: float = Field(ge=-180.0, le=180.0)


class CompassGlitch(_Fault):
    """The heading swings by up to ``amplitude_deg`` (a sine of ``period_s``), as when the motors start; steering follows."""

    kind: Literal["compass_glitch"]
    amplitude_deg: float = Field(45.0, gt=0.0, le=180.0)
    period_s: float = Field(2.0, gt=0.0, le=3600.0)


class RcTakeover(_Fault):
    """A pilot flips RC channel ``channel`` to ``pwm``; optionally switches the autopilot ``mode`` or disarms."""

    kind: Literal["rc_takeover"]
    channel: int = Field(6, ge=1, le=16)
    pwm: int = Field(1900, ge=800, le=2200)
    mode: str | None = Field(None, pattern=MODE_NAME, description="mode the pilot switches to, e.g. MANUAL (PX4: AUTO.LOITER)")
    disarm: bool = False


class RcInput(_Fault):
    """The operator moves sticks and switches: RC channels take these PWM values (restored after ``for_s``, if given)."""

    kind: Literal["rc_input"]
    channels: dict[Annotated[int, Field(ge=1, le=16)], Annotated[int, Field(ge=800, le=2200)]] = Field(min_length=1)


class RcLoss(_Fault):
    """The RC receiver loses the transmitter: RC_CHANNELS all zero, RSSI 0. With ``failsafe_mode``, ArduRover's RC failsafe acts."""

    kind: Literal["rc_loss"]
    failsafe_mode: str | None = Field(None, pattern=MODE_NAME, description="FS_ACTION: the mode an armed vehicle enters (e.g. HOLD, RTL)")


class BatterySag(_Fault):
    """The battery reads ``drop_v`` volts and ``drop_pct`` percent lower."""

    kind: Literal["battery_sag"]
    drop_v: float = Field(0.0, ge=0.0, le=100.0)
    drop_pct: int = Field(0, ge=0, le=100)

    @model_validator(mode="after")
    def _drops_something(self) -> BatterySag:
        if self.drop_v == 0 and self.drop_pct == 0:
            raise ValueError("a battery sag needs drop_v or drop_pct")
        return self


class WeakBattery(_Fault):
    """The pack holds only ``share`` of its rated charge from the start (aged, or not fully charged): see executive.sim.battery."""

    kind: Literal["weak_battery"]
    share: float = Field(gt=0.0, le=1.0, description="the share of its rated charge it holds")


class Headwind(_Fault):
    """A headwind or a current: the vehicle draws ``factor`` times the current for the same work while it lasts."""

    kind: Literal["headwind"]
    factor: float = Field(gt=0.0, le=10.0, description="how many times the current it draws")


Fault = Annotated[
    LinkLoss | EkfDegradation | GpsGlitch | CompassBias | CompassGlitch | RcTakeover | RcInput | RcLoss | BatterySag | WeakBattery | Headwind,
    Field(discriminator="kind"),
]


class FaultPlan(BaseModel):
    """A fault file."""

    model_config = _STRICT
    version: Literal[1] = Field(description="fault file format version")
    description: str | None = Field(None, max_length=4096)
    faults: list[Fault] = Field(min_length=1, max_length=10_000)


class FaultFileError(MissionError):
    """A fault file was refused; carries every error found, in file order."""


def load_faults(path: str | os.PathLike[str], vehicle: str | None = None, autopilot: str = "ardupilot") -> FaultPlan:
    """Read and validate a fault file; raises :class:`FaultFileError` listing every problem.

    With ``vehicle`` (``rover``, ``boat``...), mode names are checked against that vehicle's firmware;
    with ``autopilot="px4"``, against PX4's modes (AUTO.LOITER, OFFBOARD...).
    """
    try:
        return load_model(path, FaultPlan, lambda plan: _mode_errors(plan, vehicle, autopilot), what="fault list")
    except MissionError as exc:
        raise FaultFileError(exc.errors) from None


def _mode_errors(plan: FaultPlan, vehicle: str | None, autopilot: str = "ardupilot") -> list[tuple[Path, str]]:
    """Modes the vehicle's firmware lacks (any vehicle's firmware, when the vehicle is not known)."""
    if autopilot == "px4":
        known, which = list(PX4_MODES), "PX4 mode"
    elif vehicle is not None and (vehicle in PROFILES or kind_spec(vehicle) is not None):
        known, which = [m for m in vehicle_profile(vehicle).modes if m != "INITIALISING"], f"{vehicle} mode"
    else:
        known, which = sorted({m for p in PROFILES.values() for m in p.modes} - {"INITIALISING"}), "mode"
    errors: list[tuple[Path, str]] = []
    for i, fault in enumerate(plan.faults):
        for field in ("mode", "failsafe_mode"):
            mode = getattr(fault, field, None)
            if mode is not None and mode not in known:
                errors.append((("faults", i, field), f"{mode!r}: not a {which} (known: {', '.join(known)})"))
    return errors


def describe(fault: Fault) -> str:
    """A fault in one line, e.g. ``link_loss at 60 s for 8 s (direction=both)``."""
    when = f"at {fault.at_s:g} s" + (f" for {fault.for_s:g} s" if fault.for_s is not None else " to the end")
    details = ", ".join(f"{k}={v}" for k, v in fault.model_dump(exclude={"kind", "at_s", "for_s"}).items() if v is not None)
    return f"{fault.kind} {when}" + (f" ({details})" if details else "")


class FaultInjector:
    """Applies faults to a simulated vehicle, in ``clock`` time measured from the vehicle's boot.

    Times count from the injector's creation until :meth:`attach` (which the server calls when it
    creates its autopilot) restarts them. :meth:`update` applies the effects on the autopilot;
    :meth:`transform` rewrites or drops outgoing messages; :attr:`receiving` tells whether incoming
    ones get through. Not thread-safe: the server calls it under its lock.
    """

    def __init__(self, faults: FaultPlan | Iterable[Fault], clock: Clock) -> None:
        self.faults: tuple[Fault, ...] = tuple(faults.faults if isinstance(faults, FaultPlan) else faults)
        self._spans = tuple((f, f.at_s, f.end_s) for f in self.faults)
        self._active: tuple[float, tuple[Fault, ...]] = (math.nan, ())  # the faults in force at one time: asked for many times a step
        self.clock = clock
        self._t0 = clock.now()
        self._started: set[int] = set()  # indices of faults whose start effects were applied
        self._ended: set[int] = set()
        self._failsafe_done: set[int] = set()
        self._saved_rc: dict[int, int] = {}  # fault index -> the channel value it replaced
        self._saved_inputs: dict[int, dict[int, int]] = {}  # rc_input fault index -> the channel values it replaced
        # state the injector owns only if some fault needs it: otherwise left alone
        self._loses_position = any(isinstance(f, EkfDegradation) and f.lose_position for f in self.faults)
        self._steers = any(isinstance(f, CompassBias | CompassGlitch) for f in self.faults)
        self._cuts_link = any(isinstance(f, LinkLoss) for f in self.faults)  # asked twice a step: no search without one
        self._warned_steering = False

    def attach(self, autopilot: FirmwareSim) -> None:
        """Count fault times from now, the boot of ``autopilot`` (which must run on the same clock)."""
        if autopilot.clock is not self.clock:
            raise ValueError("the fault injector and the simulated autopilot must share one clock")
        self._t0 = self.clock.now()

    @property
    def elapsed_s(self) -> float:
        """Clock time since boot."""
        return self.clock.now() - self._t0

    def active(self, t: float | None = None) -> list[Fault]:
        """The faults in force ``t`` seconds after boot (default: now)."""
        t = self.elapsed_s if t is None else t
        if t != self._active[0]:
            self._active = (t, tuple(f for f, start, end in self._spans if start <= t < end))  # each fault's [at_s, end_s)
        return list(self._active[1])

    @property
    def receiving(self) -> bool:
        """False while a link loss stops the vehicle hearing anything (what is sent meanwhile is lost)."""
        return not self._cuts_link or not any(isinstance(f, LinkLoss) and f.direction != "downlink" for f in self.active())

    @property
    def sending(self) -> bool:
        """False while a link loss stops the vehicle sending anything."""
        return not self._cuts_link or not any(isinstance(f, LinkLoss) and f.direction != "uplink" for f in self.active())

    def heading_offset_deg(self, t: float | None = None) -> float:
        """What the compass faults add to the heading ``t`` seconds after boot (default: now)."""
        t = self.elapsed_s if t is None else t
        offset = 0.0
        for f in self.active(t):
            if isinstance(f, CompassBias):
                offset += f.bias_deg
            elif isinstance(f, CompassGlitch):
                offset += f.amplitude_deg * math.sin(2.0 * math.pi * (t - f.at_s) / f.period_s)
        return offset

    # -- effects on the autopilot ----------------------------------------------------------------

    def update(self, autopilot: FirmwareSim) -> None:
        """Apply what starts or ends now to ``autopilot``, and steer it by the compass it has now."""
        t = self.elapsed_s
        for i, (fault, start, end) in enumerate(self._spans):
            if i not in self._started and t >= start:
                self._started.add(i)
                log.info("fault injection: %s starts", describe(fault))
                self._start(i, fault, autopilot)
            if t >= end and i in self._started and i not in self._ended:
                self._ended.add(i)
                log.info("fault injection: %s ends", describe(fault))
                self._end(i, fault, autopilot)
            if isinstance(fault, RcLoss) and start <= t < end and t >= start + RC_FAILSAFE_TIMEOUT_S and i not in self._failsafe_done:
                self._failsafe_done.add(i)
                self._rc_failsafe(fault, autopilot)
        active = self.active(t)
        autopilot.load_factor = math.prod(f.factor for f in active if isinstance(f, Headwind))
        if self._loses_position:
            autopilot.ekf_position_lost = any(isinstance(f, EkfDegradation) and f.lose_position for f in active)
        if self._steers:
            if hasattr(autopilot.vehicle, "heading_bias_deg"):
                autopilot.vehicle.heading_bias_deg = self.heading_offset_deg(t)
            elif not self._warned_steering:
                self._warned_steering = True
                log.warning("fault injection: the %s model cannot steer by a wrong compass; only the telemetry is biased", autopilot.profile.kind)

    def _start(self, i: int, fault: Fault, autopilot: FirmwareSim) -> None:
        if isinstance(fault, WeakBattery):
            autopilot.battery.start_charge = fault.share
        if isinstance(fault, RcInput):
            self._saved_inputs[i] = {ch: autopilot.rc_channels[ch - 1] for ch in fault.channels}
            for ch, pwm in fault.channels.items():
                autopilot.rc_channels[ch - 1] = pwm
        if isinstance(fault, RcTakeover):
            self._saved_rc[i] = autopilot.rc_channels[fault.channel - 1]
            autopilot.rc_channels[fault.channel - 1] = fault.pwm
            if fault.mode is not None:
                self._set_mode(autopilot, fault.mode, "pilot take-over")
            if fault.disarm:
                autopilot.disarm()

    def _end(self, i: int, fault: Fault, autopilot: FirmwareSim) -> None:
        if isinstance(fault, RcInput):
            for ch, pwm in self._saved_inputs.pop(i).items():
                autopilot.rc_channels[ch - 1] = pwm
        if isinstance(fault, RcTakeover):  # the switch goes back; the mode stays where the pilot left it
            autopilot.rc_channels[fault.channel - 1] = self._saved_rc.pop(i)

    def _rc_failsafe(self, fault: RcLoss, autopilot: FirmwareSim) -> None:
        # ArduRover acts only when armed, and does not switch back when the RC returns
        if fault.failsafe_mode is not None and autopilot.armed:
            self._set_mode(autopilot, fault.failsafe_mode, "RC failsafe")

    @staticmethod
    def _set_mode(autopilot: FirmwareSim, mode: str, why: str) -> None:
        number = autopilot.profile.modes.get(mode)
        if number is None or not autopilot.set_mode(number):
            log.warning("fault injection: %s: %s refused mode %s", why, autopilot.FIRMWARE, mode)

    # -- effects on the link ---------------------------------------------------------------------

    def transform(self, messages: Sequence[MAVLinkMessage]) -> list[MAVLinkMessage]:
        """The messages as the faults in force now let them out (rewritten in place, or dropped)."""
        if not self.sending:
            return []
        active = self.active()
        if not active:
            return list(messages)
        heading = self.heading_offset_deg()
        for msg in messages:
            self._rewrite(msg, active, heading)
        return list(messages)

    def _rewrite(self, msg: MAVLinkMessage, active: list[Fault], heading_deg: float) -> None:
        kind = msg.get_type()
        glitches = [f for f in active if isinstance(f, GpsGlitch)]
        if kind == "ATTITUDE" and heading_deg:
            msg.yaw = (msg.yaw + math.radians(heading_deg) + math.pi) % (2.0 * math.pi) - math.pi
        elif kind == "VFR_HUD" and heading_deg:
            msg.heading = round(msg.heading + heading_deg) % 360
        elif kind == "GLOBAL_POSITION_INT":
            if heading_deg and msg.hdg != 65535:
                msg.hdg = round(msg.hdg + heading_deg * 100) % 36000
            msg.lat, msg.lon = _shifted(msg.lat, msg.lon, glitches)
        elif kind == "GPS_RAW_INT":
            msg.lat, msg.lon = _shifted(msg.lat, msg.lon, glitches)
        elif kind == "EKF_STATUS_REPORT":
            for f in active:
                if isinstance(f, EkfDegradation):
                    for field in ("velocity_variance", "pos_horiz_variance", "pos_vert_variance", "compass_variance"):
                        setattr(msg, field, max(getattr(msg, field), f.variance))
                    if f.lose_position:
                        msg.flags = (msg.flags & ~_M.EKF_POS_HORIZ_ABS) | _M.EKF_CONST_POS_MODE
                elif isinstance(f, GpsGlitch):
                    msg.flags |= _M.EKF_GPS_GLITCHING
                    msg.pos_horiz_variance = max(msg.pos_horiz_variance, GLITCH_POS_VARIANCE)
        elif kind == "ESTIMATOR_STATUS":  # PX4's estimator health: innovation test ratios (the position loss is the autopilot's own)
            for f in active:
                if isinstance(f, EkfDegradation):
                    for field in ("vel_ratio", "pos_horiz_ratio", "pos_vert_ratio", "mag_ratio"):
                        setattr(msg, field, max(getattr(msg, field), f.variance))
                elif isinstance(f, GpsGlitch):
                    msg.flags |= _M.ESTIMATOR_GPS_GLITCH
                    msg.pos_horiz_ratio = max(msg.pos_horiz_ratio, GLITCH_POS_VARIANCE)
        elif kind == "RC_CHANNELS" and any(isinstance(f, RcLoss) for f in active):
            msg.chancount, msg.rssi = 0, 0
            for n in range(1, 19):
                setattr(msg, f"chan{n}_raw", 0)
        elif kind == "SYS_STATUS":
            if any(isinstance(f, RcLoss) for f in active):
                msg.onboard_control_sensors_health &= ~_M.MAV_SYS_STATUS_SENSOR_RC_RECEIVER
            if any(isinstance(f, EkfDegradation) and f.variance > 1.0 for f in active):
                # every test ratio over 1: NavEKF3_core::healthy() is false, and with it the AHRS bit (GCS.cpp)
                msg.onboard_control_sensors_health &= ~_M.MAV_SYS_STATUS_AHRS
            for f in active:
                if isinstance(f, BatterySag):
                    if msg.voltage_battery != 65535:  # 65535: voltage unknown
                        msg.voltage_battery = max(0, msg.voltage_battery - round(f.drop_v * 1000))
                    if msg.battery_remaining >= 0:  # -1: unknown
                        msg.battery_remaining = max(0, msg.battery_remaining - f.drop_pct)


def _shifted(lat_e7: int, lon_e7: int, glitches: list[GpsGlitch]) -> tuple[int, int]:
    """A position (degrees * 1e7) moved by every GPS glitch in force."""
    if not glitches or (lat_e7 == 0 and lon_e7 == 0):  # 0, 0: no position to move
        return lat_e7, lon_e7
    lat, lon = lat_e7 * 1e-7, lon_e7 * 1e-7
    for glitch in glitches:
        lat, lon = geo.destination(lat, lon, glitch.bearing_deg, glitch.offset_m)
    return round(lat * 1e7), round(lon * 1e7)
