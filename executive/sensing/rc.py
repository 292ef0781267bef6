"""The RC reader: each tick, whether the operator's RC is fresh, and (MAVLink source) where its switches are.

For ``rc.source: mavlink`` the switches come from the autopilot's RC channels (/rc/channels, as
the MAVLink reader wrote them), one channel per switch as ``rc.switch_channels`` says:

- a switch: PWM below 1300 µs is UP, 1300..1700 µs MIDDLE, above 1700 µs DOWN (the FlySky/AgileX
  transmitters send a low pulse for a switch pushed away from the operator); 0 or a missing
  channel is no position (None);
- the knob: 1000..2000 µs maps linearly onto -100..100 (clamped); 0 or missing is None.

RC is fresh when the last RC report (/rc/last_update) is at most ``rc.fresh_timeout_s`` old and,
for the MAVLink source, the transmitter is there (some channel non-zero: ArduPilot reports 0 on
every channel without a signal). For ``rc.source: can`` the CAN reader writes /rc/switches and
/rc/last_update; it must only advance /rc/last_update when the 0x241 frame's rolling counter
moves, because the base keeps repeating the last frame after an RC signal loss.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

from executive.mission.model import RcConfig
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import RcSwitches, SwitchPosition

log = logging.getLogger(__name__)

#: A blackboard read: key -> value (a guard's ``get``, a reader's client ``get``).
Read = Callable[[str], object]
_SWC_MEANS = {SwitchPosition.UP: "MANUAL", SwitchPosition.DOWN: "aux mode"}


@dataclass(frozen=True)
class RcReading:
    """The operator's RC as guards and the intervention watch judge it, whatever its source (``rc.source``).

    MAVLink: the autopilot's RC channels; a person takes over with the take-over channel high; the
    transmitter is there while some channel is non-zero (/rc/connected), its reports timed by
    /rc/last_update. CAN (the AgileX base): switch C (up MANUAL, middle AUTO, down aux mode); the
    transmitter is there while the RC reader finds its frames fresh (/rc/fresh). Every rule reads the
    blackboard only, through ``read``.
    """

    source: Literal["mavlink", "can"] = "mavlink"
    takeover_channel: int = 6
    takeover_above_us: int = 1700

    @classmethod
    def of(cls, rc: RcConfig) -> RcReading:
        return cls(rc.source, rc.takeover_channel, rc.takeover_above_us)

    def channel_high(self, read: Read) -> str | None:
        """The take-over channel's value when it is high (MAVLink), as ``RC channel N high (V µs)``; None when it is not."""
        channels: tuple[int, ...] = read("/rc/channels") or ()  # type: ignore[assignment]
        value = channels[self.takeover_channel - 1] if len(channels) >= self.takeover_channel else 0
        return f"RC channel {self.takeover_channel} high ({value} µs)" if value > self.takeover_above_us else None

    def not_in_auto(self, read: Read) -> str | None:
        """Why the operator's mode switch is not in AUTO; None when it is (MAVLink: a missing transmitter is not a take-over;
        CAN: no switch C position yet is not AUTO)."""
        if self.source == "mavlink":
            high = self.channel_high(read)
            return f"{high}: manual take-over" if high else None
        switches = read("/rc/switches")
        if not isinstance(switches, RcSwitches) or switches.swc is None:
            return "no RC switch C position yet"
        if switches.swc is not SwitchPosition.MIDDLE:
            return f"RC switch C {switches.swc} ({_SWC_MEANS[switches.swc]}), not MIDDLE (AUTO)"
        return None

    def person_has_vehicle(self, read: Read) -> str | None:
        """Why the RC says a person has the vehicle (the take-over channel high, or switch C in MANUAL), if it does."""
        if self.source == "mavlink":
            high = self.channel_high(read)
            return f"{high}: a person has the vehicle" if high else None
        switches = read("/rc/switches")
        up = isinstance(switches, RcSwitches) and switches.swc == SwitchPosition.UP
        return "RC switch C in MANUAL: a person has the vehicle" if up else None

    @property
    def present_key(self) -> str:
        """The key that says the transmitter is there: /rc/connected (MAVLink) or /rc/fresh (CAN)."""
        return "/rc/connected" if self.source == "mavlink" else "/rc/fresh"

    @property
    def report_time_key(self) -> str | None:
        """The key of the last report's time, when the reports' age is judged beside the link's (MAVLink); None (CAN: the
        RC reader judges freshness itself)."""
        return "/rc/last_update" if self.source == "mavlink" else None

    def gone(self, read: Read) -> str:
        """Why the transmitter seen earlier is gone."""
        if self.source == "mavlink":
            return "RC transmitter gone (every channel 0)"
        reason = read("/rc/stale_reason")
        return reason if isinstance(reason, str) and reason else "RC is stale"


SWITCH_UP_BELOW_US = 1300
SWITCH_DOWN_ABOVE_US = 1700
KNOB_MIN_US, KNOB_MAX_US = 1000, 2000


def switch_position(pwm: int | None) -> SwitchPosition | None:
    """The switch position a PWM value means; None for no signal (0) or no channel."""
    if not pwm:
        return None
    if pwm < SWITCH_UP_BELOW_US:
        return SwitchPosition.UP
    if pwm > SWITCH_DOWN_ABOVE_US:
        return SwitchPosition.DOWN
    return SwitchPosition.MIDDLE


def knob_value(pwm: int | None) -> int | None:
    """The knob's position in [-100, 100]; None for no signal (0) or no channel."""
    if not pwm:
        return None
    pwm = min(max(pwm, KNOB_MIN_US), KNOB_MAX_US)
    return round((pwm - KNOB_MIN_US) * 200 / (KNOB_MAX_US - KNOB_MIN_US)) - 100


def switches_from_channels(channels: tuple[int, ...], rc: RcConfig, time: float) -> RcSwitches:
    """SWA..SWD and the knob from RC channel PWM values, by ``rc.switch_channels``."""

    def pwm(channel: int) -> int | None:
        return channels[channel - 1] if len(channels) >= channel else None

    c = rc.switch_channels
    return RcSwitches(
        swa=switch_position(pwm(c.swa)),
        swb=switch_position(pwm(c.swb)),
        swc=switch_position(pwm(c.swc)),
        swd=switch_position(pwm(c.swd)),
        knob=knob_value(pwm(c.knob)),
        time=time,
    )


class RcReader:
    """Keeps /rc/fresh, /rc/stale_reason and (MAVLink source) /rc/switches; call :meth:`service` every tick after the readers drain."""

    def __init__(self, rc: RcConfig, clock: Clock, channels: Mapping[int, str] | None = None) -> None:
        """``channels``: the RC channels the mission reads (channel -> what it is), checked against the receiver's channel count."""
        self.rc = rc
        self._clock = clock
        self.channels = dict(channels or {})
        self._warned_for: int | None = None
        self._in = blackboard.reader("rc reader in", ["/rc/channels", "/rc/last_update", "/rc/chancount"])
        self._out = blackboard.writer("rc reader", ["/rc/fresh", "/rc/stale_reason", "/rc/switches"])
        self._seen: tuple[float | None, tuple[int, ...]] | None = None

    def service(self) -> None:
        channels: tuple[int, ...] = self._in.get("/rc/channels")
        last: float | None = self._in.get("/rc/last_update")
        if self.rc.source == "mavlink" and (last, channels) != self._seen:  # written only when a report changes it
            self._seen = (last, channels)
            self._out.set("/rc/switches", None if last is None else switches_from_channels(channels, self.rc, last))
        chancount: int | None = self._in.get("/rc/chancount")
        if chancount is not None and chancount != self._warned_for:
            self._warned_for = chancount
            beyond = [f"{ch} ({what})" for ch, what in self.channels.items() if ch > chancount]
            if beyond:
                log.warning(
                    "RC: the autopilot reports %d channels (chancount) and the mission reads %s beyond them: their values are read as sent",
                    chancount, ", ".join(beyond),
                )  # fmt: skip
        reason = self._stale_reason(channels, last)
        if reason != self._out.get("/rc/stale_reason"):
            self._out.set("/rc/stale_reason", reason)
            self._out.set("/rc/fresh", not reason)

    def _stale_reason(self, channels: tuple[int, ...], last: float | None) -> str:
        if last is None:
            return "no RC report yet"
        if self._clock.now() - last > self.rc.fresh_timeout_s:
            return f"no RC report within {self.rc.fresh_timeout_s:g} s"
        if self.rc.source == "mavlink" and not any(channels):
            return "RC transmitter gone (every channel 0)"
        return ""
