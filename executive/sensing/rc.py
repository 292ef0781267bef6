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
from collections.abc import Mapping

from executive import blackboard
from executive.clock import Clock
from executive.mission.model import RcConfig
from executive.state import RcSwitches, SwitchPosition

log = logging.getLogger(__name__)

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
