"""What the real firmware said while the executive made it safe (issue 44, item 4), replayed: the safe state read as it came.

Cut from runs against the firmware in software-in-the-loop (tests/data/make_safe/README.md): the executive's
make-safe from 2 s before its first ask to the end of the run. The vehicle, shown in the mode asked, is not yet
in the plan's safe state, and reaches it later, read by the same :func:`~executive.autopilot_link.safe_state.settled`
the make-safe waits on.
"""

from __future__ import annotations

import pytest
from tlog_replay import DATA, Replay

from executive.autopilot_link.safe_state import SafePlan, Until, settled

MAKE_SAFE = DATA / "make_safe"


def replayed(recording: str, vehicle: str, until_s: float | None = None) -> Replay:
    return Replay(vehicle=vehicle).play(MAKE_SAFE / recording, until_s=until_s)


@pytest.mark.parametrize(
    ("recording", "vehicle", "plan", "mode"),
    [
        pytest.param("vtol_transit-quadplane-abort-landing.tlog", "vtol", SafePlan("QLAND", Until.LANDED), "QLAND", id="arduplane-qland"),
        pytest.param("vtol_transit-px4-abort-landing.tlog", "vtol", SafePlan("QLAND", Until.LANDED), "AUTO.LAND", id="px4-auto-land"),
        pytest.param("auv_survey-ardusub-sigterm.tlog", "sub", SafePlan("SURFACE", Until.SURFACED), "SURFACE", id="ardusub-surface"),
    ],
)
def test_the_real_firmware_reaches_the_safe_state_the_make_safe_waits_for(recording: str, vehicle: str, plan: SafePlan, mode: str) -> None:
    whole = replayed(recording, vehicle)
    shown = whole.when("/vehicle/mode", mode)
    assert not settled(plan, replayed(recording, vehicle, shown).bb.get)  # in the mode, not there yet
    # the first change after it from which the replay is in the safe state (a sub then goes on to POSHOLD, asked by the executive)
    changes = sorted({t for t, _, _ in whole.seen if t > shown})
    done = next((t for t in changes if settled(plan, replayed(recording, vehicle, t).bb.get)), None)
    assert done is not None, f"never {plan.until}"
    print(f"\n{recording}: {mode} shown at {shown:.1f} s, {plan.until} by {done:.1f} s (wall time of a run at 2x)")


def test_ardusub_holds_the_surface_in_alt_hold_itself_the_autopilots_change_then_poshold_is_ours() -> None:
    replay = replayed("auv_survey-ardusub-sigterm.tlog", "sub")
    changes = [(key, value) for _, key, value in replay.seen if key in ("/vehicle/mode", "/vehicle/mode_set_by")]
    assert changes[-4:] == [
        ("/vehicle/mode", "ALT_HOLD"),
        ("/vehicle/mode_set_by", "autopilot"),  # SURFACE_COMPLETE (ArduSub/mode_surface.cpp), judged by executive.autopilot.mode_cause
        ("/vehicle/mode", "POSHOLD"),
        ("/vehicle/mode_set_by", "us"),
    ]
