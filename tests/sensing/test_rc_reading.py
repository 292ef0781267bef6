"""One RC reading whatever its source: the rules the guards and the intervention watch ask of it, MAVLink and CAN side by side."""

from __future__ import annotations

import pytest

from executive.mission.model import RcConfig
from executive.sensing.rc import RcReading
from executive.world.state import RcSwitches, SwitchPosition

UP, MIDDLE, DOWN = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN


def board(**values: object):
    """A blackboard read of these keys (``rc__channels`` is /rc/channels), None for any other."""
    data = {"/" + k.replace("__", "/"): v for k, v in values.items()}
    return lambda key: data.get(key)


def switches(swc: SwitchPosition | None) -> RcSwitches:
    return RcSwitches(swa=None, swb=None, swc=swc, swd=None, knob=None, time=0.0)


MAVLINK = RcReading("mavlink", takeover_channel=6, takeover_above_us=1700)
CAN = RcReading("can")


@pytest.mark.parametrize(
    ("reading", "read", "not_in_auto", "person"),
    [
        (MAVLINK, board(rc__channels=(1500,) * 6), None, None),
        (MAVLINK, board(rc__channels=(1500,) * 5 + (1900,)), "RC channel 6 high (1900 µs): manual take-over",
         "RC channel 6 high (1900 µs): a person has the vehicle"),
        (MAVLINK, board(rc__channels=()), None, None),  # no transmitter: not a take-over
        (CAN, board(rc__switches=switches(MIDDLE)), None, None),
        (CAN, board(rc__switches=switches(UP)), "RC switch C UP (MANUAL), not MIDDLE (AUTO)", "RC switch C in MANUAL: a person has the vehicle"),
        (CAN, board(rc__switches=switches(DOWN)), "RC switch C DOWN (aux mode), not MIDDLE (AUTO)", None),  # aux mode: no person
        (CAN, board(), "no RC switch C position yet", None),
    ],
)  # fmt: skip
def test_whose_rc_it_is_by_the_source(reading: RcReading, read, not_in_auto: str | None, person: str | None) -> None:
    assert reading.not_in_auto(read) == not_in_auto
    assert reading.person_has_vehicle(read) == person


def test_the_transmitter_there_and_gone_by_the_source() -> None:
    assert (MAVLINK.present_key, MAVLINK.report_time_key) == ("/rc/connected", "/rc/last_update")
    assert (CAN.present_key, CAN.report_time_key) == ("/rc/fresh", None)  # the CAN reader judges freshness itself
    assert MAVLINK.gone(board()) == "RC transmitter gone (every channel 0)"
    assert CAN.gone(board(rc__stale_reason="RC counter frozen for 1.2 s")) == "RC counter frozen for 1.2 s"
    assert CAN.gone(board()) == "RC is stale"


def test_a_missions_rc_section_makes_its_reading() -> None:
    rc = RcConfig(source="can", takeover_channel=7, takeover_above_us=1800)
    assert RcReading.of(rc) == RcReading("can", 7, 1800)
