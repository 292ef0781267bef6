"""The RC reader: switch and knob mapping from RC channels, freshness, a transmitter gone, the CAN source."""

from __future__ import annotations

import py_trees
import pytest

from executive.mission.model import RcConfig, SwitchChannels
from executive.runtime.assembly import build_runtime
from executive.sensing.rc import RcReader, knob_value, switch_position
from executive.testing import AUTOPILOT
from executive.world import blackboard
from executive.world.state import RcSwitches, SwitchPosition

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def bb(key: str):
    return py_trees.blackboard.Blackboard.get(key)


@pytest.fixture
def rc_report(clock):
    """``rc_report(channels)``: an RC_CHANNELS report arrives now, as the MAVLink reader writes it."""
    writer = blackboard.writer("test mavlink reader", ["/rc/channels", "/rc/last_update", "/rc/connected"])

    def report(channels: tuple[int, ...]) -> None:
        writer.set("/rc/channels", channels)
        writer.set("/rc/last_update", clock.now())
        writer.set("/rc/connected", any(channels))

    return report


@pytest.mark.parametrize(
    ("pwm", "position"),
    [(None, None), (0, None), (982, UP), (1000, UP), (1299, UP), (1300, MIDDLE), (1500, MIDDLE), (1700, MIDDLE), (1701, DOWN), (2006, DOWN)],
)
def test_switch_position(pwm, position):
    assert switch_position(pwm) == position


@pytest.mark.parametrize(
    ("pwm", "value"),
    [(None, None), (0, None), (1000, -100), (1250, -50), (1500, 0), (1627, 25), (2000, 100), (900, -100), (2100, 100)],
)
def test_knob_value(pwm, value):
    assert knob_value(pwm) == value


def test_switches_from_the_default_channels(clock, rc_report):
    reader = RcReader(RcConfig(), clock)
    #            1     2     3     4     5 SWA 6 SWB 7 SWC 8 SWD 9 knob
    rc_report((1500, 1500, 1000, 1500, 1100, 1500, 1500, 1900, 1750))
    reader.service()
    assert bb("/rc/switches") == RcSwitches(UP, MIDDLE, MIDDLE, DOWN, 50, 100.0)
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (True, "")


def test_switches_from_configured_channels(clock, rc_report):
    rc = RcConfig(switch_channels=SwitchChannels(swa=1, swb=2, swc=3, swd=4, knob=12))
    reader = RcReader(rc, clock)
    rc_report((1900, 1100, 1100, 1500, 1500, 1500, 1500, 1500))  # 8 channels: no knob channel
    reader.service()
    assert bb("/rc/switches") == RcSwitches(DOWN, UP, UP, MIDDLE, None, 100.0)


def test_switches_are_replaced_only_by_a_new_report(clock, rc_report):
    reader = RcReader(RcConfig(), clock)
    assert bb("/rc/switches") is None
    reader.service()
    assert bb("/rc/switches") is None  # no report yet
    rc_report((1500,) * 9)
    reader.service()
    first = bb("/rc/switches")
    clock.advance(0.1)
    reader.service()
    assert bb("/rc/switches") is first  # same report: not rewritten
    rc_report((1500,) * 6 + (1100, 1500, 1500))
    reader.service()
    assert (bb("/rc/switches").swc, bb("/rc/switches").time) == (UP, 100.1)


def test_freshness_times_out_and_recovers(clock, rc_report):
    reader = RcReader(RcConfig(fresh_timeout_s=1.0), clock)
    seen = []
    for dt, report in ((0.0, False), (0.0, True), (0.5, False), (0.5, False), (0.1, False), (0.2, True), (0.0, False)):
        clock.advance(dt)
        if report:
            rc_report((1500,) * 9)
        reader.service()
        seen.append((bb("/rc/fresh"), bb("/rc/stale_reason")))
    assert seen == [
        (False, "no RC report yet"),
        (True, ""),
        (True, ""),
        (True, ""),  # exactly the timeout old: still fresh
        (False, "no RC report within 1 s"),
        (True, ""),
        (True, ""),
    ]


def test_transmitter_gone_is_stale_and_has_no_switches(clock, rc_report):
    reader = RcReader(RcConfig(), clock)
    rc_report((1500,) * 9)
    reader.service()
    rc_report((0,) * 9)  # ArduPilot keeps reporting, every channel 0
    reader.service()
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (False, "RC transmitter gone (every channel 0)")
    assert bb("/rc/switches") == RcSwitches(None, None, None, None, None, 100.0)
    rc_report(())  # no channels at all
    reader.service()
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (False, "RC transmitter gone (every channel 0)")


def test_can_source_leaves_the_switches_to_the_can_reader(clock, rc_report):
    can = blackboard.writer("test can reader", ["/rc/switches", "/rc/last_update"])
    reader = RcReader(RcConfig(source="can", fresh_timeout_s=0.5), clock)
    rc_report((0,) * 9)  # the autopilot has no receiver of its own on a CAN base: not a missing transmitter
    frame = RcSwitches(UP, MIDDLE, MIDDLE, DOWN, -80, clock.now())
    can.set("/rc/switches", frame)
    reader.service()
    assert bb("/rc/switches") is frame
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (True, "")
    clock.advance(0.6)  # the CAN reader stopped advancing /rc/last_update: the 0x241 counter froze
    reader.service()
    assert (bb("/rc/fresh"), bb("/rc/stale_reason")) == (False, "no RC report within 0.5 s")
    assert bb("/rc/switches") is frame
    can.set("/rc/last_update", clock.now())
    reader.service()
    assert bb("/rc/fresh") is True


def test_the_runtime_judges_rc_after_draining_the_link(square_mission, link, clock):
    runtime = build_runtime(square_mission, link, clock, root=py_trees.behaviours.Running("idle"))
    link.incoming.append(AUTOPILOT.heartbeat(10, 3, 0, 4, 4))
    runtime.tick()
    assert (bb("/rc/fresh"), bb("/rc/switches")) == (False, None)
    channels = (1500,) * 6 + (1500, 1900, 1250) + (0,) * 9
    link.incoming.append(AUTOPILOT.rc_channels(0, 9, *channels, 200))
    runtime.tick()
    assert bb("/rc/fresh") is True
    assert bb("/rc/switches") == RcSwitches(MIDDLE, MIDDLE, MIDDLE, DOWN, -50, clock.now())


def test_a_mission_channel_past_the_receivers_count_is_warned_about_once(clock, rc_report, caplog):
    """Issue 13: with chancount 8 the knob on channel 9 was silently not read; it is read now, with a warning."""
    chancount = blackboard.writer("test chancount", ["/rc/chancount"])
    reader = RcReader(RcConfig(), clock, {5: "switch A", 8: "switch D", 9: "knob VRA"})
    chancount.set("/rc/chancount", 8)
    rc_report((1500, 1500, 1000, 1500, 1100, 1500, 1500, 1900, 1750))
    reader.service()
    reader.service()
    assert bb("/rc/switches").knob == 50
    warnings = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert warnings == [
        "RC: the autopilot reports 8 channels (chancount) and the mission reads 9 (knob VRA) beyond them: their values are read as sent"
    ]
