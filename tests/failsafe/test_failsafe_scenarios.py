"""Each failsafe in the simulator: the fault file of missions/faults/ injected into a running mission, in the lock-step simulation.

The mission drives a straight 60 m line north in four legs (25 m, 25 m, then 5 m and 5 m: what comes after the faulty
second leg only has to be driven to the end). The fault files are timed for
missions/rover_square.yaml (EKF ready at 40 s); here the EKF is ready at 2 s, so every fault comes
38 s earlier: on the second leg. Each scenario checks that the policy's reaction leaves in the tick
its guard fails (the condition true on the blackboard for the guard's hold time: most hold at once) or the next, that
the failsafe does not flap (one hold, at most one resume: each fault file is one episode), the recovery (the same leg resumes and
the mission completes, or it aborts with the vehicle in the reaction's mode) and the journal's event.
"""

from __future__ import annotations

import json
import logging
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
import yaml

from executive.behaviours import (
    BatteryAbove,
    EkfOk,
    GpsNotGlitching,
    HeadingSane,
    InsideGeofence,
    LinkAlive,
    RcNotLost,
    RcNotTakingOver,
)
from executive.cli import main
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission
from executive.observers.journal import Journal, JournalLogHandler, journal_recorder
from executive.runtime.loop import Runtime
from executive.sim.faults import load_faults
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.geofence import Geofence
from executive.world.state import EkfFlags
from tests_support import LINE_EKF_READY_S, LINE_HOME, line_mission, run_in_lockstep

ROOT = Path(__file__).parents[2]
FAULTS = ROOT / "missions" / "faults"
SHIFT_S = 38.0  # the fault files' EKF is ready at 40 s, this mission's at 2 s
HOME = LINE_HOME
FENCE_M = 110.0
BB_KEYS = ["/link/up", "/vehicle/ekf", "/rc/channels", "/rc/connected", "/heading/ok", "/vehicle/battery", "/vehicle/position", "/mission/leg_index"]


def failsafe_line(**changes: Any) -> Mission:
    """The line mission, its EKF ready 38 s before the fault files' (their times are shifted by SHIFT_S), its last two legs 5 m."""
    assert LINE_EKF_READY_S == 40.0 - SHIFT_S
    waypoints = [{"lat": HOME[0] + 0.0002248 * north_m / 25.0, "lon": HOME[1]} for north_m in (25.0, 50.0, 55.0, 60.0)]
    return line_mission("failsafe line", waypoints=waypoints, **changes)


Fact = Callable[[dict[str, Any]], bool]
#: Each condition's guard's hold time (executive/behaviours/guards.py; the README's failsafe table).
HOLD_AFTER_S = {
    "link_loss": LinkAlive.hold_after_s, "rc_takeover": RcNotTakingOver.hold_after_s, "rc_loss": RcNotLost.hold_after_s,
    "ekf_loss": EkfOk.hold_after_s, "gps_glitch": GpsNotGlitching.hold_after_s, "heading_insane": HeadingSane.hold_after_s,
    "battery_low": BatteryAbove.hold_after_s, "geofence_breach": InsideGeofence.hold_after_s,
}  # fmt: skip


def _ekf_lost(bb: dict[str, Any]) -> bool:
    ekf = bb["/vehicle/ekf"]
    return ekf is not None and not (ekf.position_ok() and ekf.variances_ok(0.8))


def _outside(bb: dict[str, Any]) -> bool:
    p = bb["/vehicle/position"]
    return p is not None and Geofence((), FENCE_M).why_outside(p.lat, p.lon, HOME) is not None


@dataclass(frozen=True)
class Scenario:
    condition: str
    fault_file: str
    fact: Fact  # the condition, judged from the blackboard independently of the guards
    mode: str | None  # the reaction's mode; None: wait (nothing commanded)
    recovery: str
    changes: dict[str, Any] = field(default_factory=dict)  # to the mission
    fault_changes: dict[str, Any] = field(default_factory=dict)


SCENARIOS = [
    # downlink only: the vehicle hears the hold (both ways, it would keep driving in GUIDED, deaf)
    Scenario("link_loss", "link_loss.yaml", lambda bb: not bb["/link/up"], "HOLD", "resume", fault_changes={"direction": "downlink"}),
    Scenario("rc_takeover", "rc_takeover.yaml", lambda bb: len(bb["/rc/channels"]) >= 6 and bb["/rc/channels"][5] > 1700, None, "resume"),
    Scenario("rc_loss", "rc_loss.yaml", lambda bb: not bb["/rc/connected"], "HOLD", "resume"),
    Scenario("ekf_loss", "ekf_loss.yaml", _ekf_lost, "HOLD", "resume"),
    Scenario(
        "gps_glitch", "gps_glitch.yaml", lambda bb: bool(bb["/vehicle/ekf"] and bb["/vehicle/ekf"].flags & EkfFlags.GPS_GLITCHING), "HOLD", "resume"
    ),
    Scenario("heading_insane", "heading_insane.yaml", lambda bb: bb["/heading/ok"] is False, "HOLD", "resume"),
    Scenario(
        "battery_low", "battery_low.yaml", lambda bb: bool(bb["/vehicle/battery"] and bb["/vehicle/battery"].remaining_pct < 20), "RTL", "abort"
    ),
    Scenario("geofence_breach", "geofence_breach.yaml", _outside, "HOLD", "abort", {"geofence": {"max_distance_from_home_m": FENCE_M}}),
]


@dataclass
class Record:
    """What a run did, tick by tick (a tick's number is the runtime's count before it)."""

    facts: list[dict[str, Any]] = field(default_factory=list)  # the blackboard after each tick
    modes: list[tuple[int, str]] = field(default_factory=list)  # DO_SET_MODE sent: (tick, mode)
    warnings: list[tuple[int, str]] = field(default_factory=list)  # the executive's warnings: (tick, text)
    times: list[float] = field(default_factory=list)  # the vehicle time of each tick

    def first(self, fact: Fact, after: int = 0) -> int:
        return next(tick for tick, bb in enumerate(self.facts) if tick >= after and fact(bb))


class _Warnings(logging.Handler):
    def __init__(self, record: Record, runtime: Runtime) -> None:
        super().__init__(logging.WARNING)
        self.record, self.runtime = record, runtime

    def emit(self, r: logging.LogRecord) -> None:
        self.record.warnings.append((self.runtime.ticks, r.getMessage()))


def shifted_faults(name: str, **changes: Any) -> list[Any]:
    return [f.model_copy(update={"at_s": max(0.0, f.at_s - SHIFT_S), **changes}) for f in load_faults(FAULTS / name, "rover").faults]


@pytest.fixture
def run_scenario(tmp_path: Path, lockstep) -> Iterator[Callable[[Scenario], tuple[Any, Record, dict[str, Any], str]]]:
    """Runs a scenario's mission with its faults: the outcome, the record, the journal's report and the vehicle's final mode."""
    handlers: list[logging.Handler] = []

    def run(scenario: Scenario) -> tuple[Any, Record, dict[str, Any], str]:
        mission = failsafe_line(**scenario.changes)
        record = Record()
        journals: list[Journal] = []

        def journal_plug(clock: Clock) -> dict[str, Any]:
            journals.append(Journal(tmp_path / f"{scenario.condition}.db", clock))
            return {"plugs": [journal_recorder(journals[0])]}

        faults = shifted_faults(scenario.fault_file, **scenario.fault_changes)
        sim = lockstep(mission, home=(*HOME, 0.0), events=faults, options_for_clock=journal_plug)
        runtime, link, journal = sim.runtime, sim.link, journals[0]
        send = link.send

        def spy(msg: MAVLinkMessage) -> None:  # a command leaves in the flush at the end of tick runtime.ticks
            if msg.get_type() == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
                record.modes.append((runtime.ticks, runtime.link.commander.modes.decode(int(msg.param2))))
            send(msg)

        link.send = spy  # type: ignore[method-assign]
        bb = blackboard.reader("scenario", BB_KEYS)
        tick = runtime.tick

        def observed_tick() -> Any:
            status = tick()
            record.facts.append({key: bb.get(key) for key in BB_KEYS})
            record.times.append(sim.clock.now())
            return status

        runtime.tick = observed_tick  # type: ignore[method-assign]
        for handler in (_Warnings(record, runtime), JournalLogHandler(journal)):
            logging.getLogger("executive").addHandler(handler)
            handlers.append(handler)
        outcome = sim.run_to_end(limit_s=600)
        report = journal.report()
        journal.close()
        return outcome, record, report, sim.autopilot.mode

    yield run
    for handler in handlers:
        logging.getLogger("executive").removeHandler(handler)


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda s: s.condition)
def test_a_fault_gets_its_failsafe_within_one_tick_and_its_recovery(run_scenario, scenario: Scenario) -> None:
    outcome, record, report, final_mode = run_scenario(scenario)
    became_true = record.first(scenario.fact, after=int(10 / 0.1))  # after pre-flight; the faults start at 24 s
    prefix = f"failsafe {scenario.condition}: "
    reacted = next(tick for tick, text in record.warnings if text.startswith(prefix))
    if scenario.mode is not None:
        reacted = next(tick for tick, mode in record.modes if tick >= became_true and mode == scenario.mode)
        assert not [m for t, m in record.modes if became_true <= t < reacted], "something else was commanded first"
    # the guard's debounce: the tick in which the condition has been true for its hold time (a shorter bad spell is noise)
    hold_s, times = HOLD_AFTER_S[scenario.condition], record.times
    due = next(t for t in range(became_true, len(times)) if times[t] - times[became_true] >= hold_s - 1e-6)
    print(f"\n{scenario.condition}: true at tick {became_true}, due at tick {due} ({hold_s:g} s later), reaction at tick {reacted}")
    assert 0 <= reacted - due <= 1
    holds = [text for _, text in record.warnings if text.startswith(prefix) and re.search(r"resume when it recovers|abort the mission$", text)]
    resumes = [text for _, text in record.warnings if text.startswith(prefix) and "recovered after" in text]
    print(f"{scenario.condition}: {len(holds)} hold(s), {len(resumes)} resume(s)")
    assert len(holds) == 1 and len(resumes) <= 1, (holds, resumes)  # one fault episode: one hold/resume pair, no flapping
    leg = record.facts[became_true]["/mission/leg_index"]
    events = [e["text"] for e in report["events"] if e["kind"] == "failsafe"]
    assert any(e.startswith(prefix) for e in events), events
    if scenario.recovery == "resume":
        assert outcome.status is MissionStatus.COMPLETED, outcome.reason
        resumed = next(tick for tick, text in record.warnings if text.startswith(prefix) and "recovered" in text)
        assert f"-> resume leg {leg + 1}/4" in dict(record.warnings)[resumed]
        assert {bb["/mission/leg_index"] for bb in record.facts[became_true:resumed]} == {leg}  # held on that leg until it recovered
        assert (resumed, "GUIDED") in record.modes  # the leg again, in GUIDED
        if scenario.mode is None:
            assert not [m for t, m in record.modes if became_true <= t < resumed]  # hands off: nothing at all
    else:
        assert outcome.status is MissionStatus.ABORTED
        assert final_mode == scenario.mode  # the runtime left the vehicle in the reaction's mode, not its safe mode
        assert any(e.startswith(prefix) and e.endswith("abort the mission") for e in events), events
        assert report["outcome"] == "ABORTED"


def test_a_failsafe_abort_exits_1_and_the_report_has_the_event(tmp_path: Path, capsys, monkeypatch) -> None:
    """``executive run --faults --journal`` from the command line (in this process: its exit code and output are what is checked):
    battery_low, exit 1, the vehicle in RTL, the event in ``executive report --json``."""
    mission = tmp_path / "line.yaml"
    mission.write_text(yaml.safe_dump(failsafe_line().model_dump(mode="json", exclude_none=True)))
    faults = tmp_path / "battery_low.yaml"
    plan = {"version": 1, "faults": [f.model_dump(mode="json", exclude_none=True) for f in shifted_faults("battery_low.yaml")]}
    faults.write_text(yaml.safe_dump(plan))
    db = tmp_path / "journal.db"
    # at 10x: the safe mode is confirmed within its bound of vehicle time; at 50x, 0.1 s of wall time, too little beside busy processes
    run_in_lockstep(monkeypatch)
    code = main(["run", str(mission), "--faults", str(faults), "--speedup", "10", "--journal", str(db), "--socket", "none", "-v"])
    err = capsys.readouterr().err
    assert code == 1, err
    assert "ABORTED: Battery above floor?: battery" in err
    assert "executive: the vehicle made safe: RTL" in err  # the runtime saw the heartbeat confirm it, and said so in the last lines
    assert main(["report", str(db), "--json"]) == 0
    events = [e for e in json.loads(capsys.readouterr().out)["events"] if e["kind"] == "failsafe"]
    assert [e["text"].split(":")[0] for e in events] == ["failsafe battery_low"]
    assert events[0]["text"].endswith("-> rtl (RTL), abort the mission")


def test_the_policy_of_the_mission_file_is_the_one_played(run_scenario) -> None:
    """The same link loss with ``failsafe: {link_loss: {reaction: rtl, recovery: abort}}``: RTL at once, and the mission ends there."""
    changes = {"failsafe": {"link_loss": {"reaction": "rtl", "recovery": "abort"}}}
    scenario = Scenario("link_loss", "link_loss.yaml", lambda bb: not bb["/link/up"], "RTL", "abort", changes)
    outcome, record, _, _ = run_scenario(scenario)
    became_true = record.first(scenario.fact, after=100)
    assert (became_true, "RTL") in record.modes
    assert outcome.status is MissionStatus.ABORTED and outcome.reason == "Link alive?: no heartbeat from the autopilot"


def test_the_seeds_compass_bias_is_compensated_the_mission_completes_and_its_swings_still_hold(run_scenario) -> None:
    """missions/faults/compass_bias.yaml: 20° off from boot (measured, compensated, reported: the mission completes), and 45° swings
    when the motors start (held with the filter's reason, then resumed)."""
    scenario = Scenario("heading_insane", "compass_bias.yaml", lambda bb: bb["/heading/ok"] is False, "HOLD", "resume")
    outcome, record, _, _ = run_scenario(scenario)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    texts = [text for _, text in record.warnings]
    assert any(re.fullmatch(r"compass bias \+(1[7-9]|2[0-3])\.\d° measured against the course over ground: compensated", t) for t in texts), texts
    swings = [t for t in texts if t.startswith("failsafe heading_insane: compass rejected in ")]
    assert swings and swings[0].endswith("-> hold (HOLD), resume when it recovers (within 30 s)")  # the filter's reason
    assert any(t.startswith("failsafe heading_insane: recovered after ") for t in texts)


def test_a_reaction_the_simulated_firmware_cannot_take_now_is_replaced_by_the_next_at_once(run_scenario) -> None:
    """``ekf_loss: {reaction: rtl}`` on the simulated ArduRover, its position estimate lost at once: RTL needs one (Rover/mode.cpp
    Mode::enter; the simulator refuses it as the firmware does), so HOLD is asked in that tick instead, never RTL, and confirmed."""
    changes = {"failsafe": {"ekf_loss": {"reaction": "rtl"}}}
    scenario = Scenario("ekf_loss", "ekf_loss.yaml", _ekf_lost, "HOLD", "resume", changes, fault_changes={"lose_position": True})
    outcome, record, _, _ = run_scenario(scenario)
    assert outcome.status is MissionStatus.COMPLETED, outcome.reason
    became_true = record.first(scenario.fact, after=100)
    modes = [(t - became_true, m) for t, m in record.modes if t >= became_true]
    assert modes[0] == (0, "HOLD") and "RTL" not in [m for _, m in modes]
    texts = [text for _, text in record.warnings if text.startswith("failsafe ekf_loss: ")]
    print("\n" + "\n".join(texts))
    assert texts[1].startswith("failsafe ekf_loss: RTL cannot be entered: the EKF has no position estimate (flags ")
    assert texts[1].endswith(" -> HOLD instead")
    assert "refused" not in " ".join(texts)  # HOLD accepted and seen at the first ask
