"""Guards of the operator's RC: a person taking over, the mode switch, the transmitter there and its reports fresh.

The debounce and the rules for unknown and stale readings are the guards' (:mod:`executive.behaviours.guards`).
"""

from __future__ import annotations

from typing import Literal

from executive.behaviours.guards import Guard
from executive.mission.model import RcConfig
from executive.sensing.rc import RcReading


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
        self.rc = RcReading("mavlink", channel, above_us)  # as RcAutoMode's: made once, not at every check

    def check(self) -> str | None:
        return self.rc.not_in_auto(self.get)


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
        self.rc = RcReading(source, takeover_channel, takeover_above_us)

    def check(self) -> str | None:
        return self.rc.not_in_auto(self.get)


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
        self.rc = RcReading(source)
        self._seen = False

    def check(self) -> str | None:
        if self.get(self.rc.present_key):
            self._seen = True
            timed = self.rc.report_time_key
            return self.stale(self.get(timed), self.stale_after_s, "the RC report is") if timed is not None else None
        if not self._seen:
            self.note = "no RC seen yet"
            return None
        return self.rc.gone(self.get)
