"""The ``failsafe:`` section of a mission file: its defaults per vehicle kind and tree, overrides, and the errors it refuses."""

from __future__ import annotations

import re

import pytest

from executive.mission import failsafes
from executive.mission.errors import MissionError
from executive.mission.failsafes import FAILSAFE_CONDITIONS, FailsafePolicy
from executive.mission.loader import load_mission_text
from executive.mission.model import Mission
from executive.mission.rules import failsafe_policy

HEAD = "version: 1\nname: m\nvehicle: {vehicle}\ntree: {tree}\n"  # the body starts on line 5
WP = "waypoints:\n  - {lat: 47.3978, lon: 8.5456}\n"


def load(body: str, vehicle: str = "rover", tree: str = "waypoints") -> Mission:
    return load_mission_text(HEAD.format(vehicle=vehicle, tree=tree) + body + WP, "m.yaml")


def errors_of(body: str, vehicle: str = "rover", tree: str = "waypoints") -> list[str]:
    try:
        load(body, vehicle, tree)
    except MissionError as exc:
        return [str(e) for e in exc.errors]
    return []


def pairs(mission: Mission) -> dict[str, tuple[str, str]]:
    return {c: (p.reaction, p.recovery) for c, p in failsafe_policy(mission).items()}


# the table of the model's docstring, read back: what the documentation says is what the code does
_ROW = re.compile(r"^(\w+)\s+(\w+), (\w+)\s+(\w+), (\w+)\s+(\w+), (\w+)\s+(\w+), (\w+)\s*$")


def documented_defaults() -> dict[str, dict[str, tuple[str, str]]]:
    table: dict[str, dict[str, tuple[str, str]]] = {kind: {} for kind in ("rover", "boat", "sub", "vtol")}
    for line in (failsafes.__doc__ or "").splitlines():
        if m := _ROW.match(line):
            condition, *cells = m.groups()
            for kind, reaction, recovery in zip(table, cells[0::2], cells[1::2], strict=True):
                table[kind][condition] = (reaction, recovery)
    return table


@pytest.mark.parametrize("vehicle", ["rover", "boat", "sub", "vtol"])
def test_the_defaults_are_the_documented_table(vehicle: str) -> None:
    mission = load("limits: {acceptance_radius_m: 80}\n" if vehicle == "vtol" else "", vehicle)
    documented = documented_defaults()[vehicle]
    assert set(documented) == set(FAILSAFE_CONDITIONS)
    assert pairs(mission) == documented
    assert {p.timeout_s for p in failsafe_policy(mission).values()} == {mission.limits.recovery_timeout_s}


def test_the_documented_rover_boat_sub_vtol_defaults() -> None:
    """The safe defaults, spelled out: a rover holds, a boat loiters, a sub surfaces on link loss; low battery goes home and ends."""
    d = failsafes.VEHICLE_FAILSAFES
    assert [d[k]["link_loss"] for k in ("rover", "boat", "sub", "vtol")] == [
        ("hold", "resume"),
        ("loiter", "resume"),
        ("surface", "resume"),
        ("hold", "resume"),
    ]
    assert [d[k]["battery_low"] for k in ("rover", "boat", "sub", "vtol")] == [("rtl", "abort")] * 2 + [("surface", "abort"), ("rtl", "abort")]
    assert {d[k]["rc_takeover"] for k in d} == {("wait", "resume")}
    assert {d[k]["geofence_breach"][1] for k in d} == {"abort"}


@pytest.mark.parametrize(
    ("vehicle", "tree", "seed"),
    [
        (
            "boat",
            "goto_sample",
            {"ekf_loss": ("disarm", "resume"), "rc_takeover": ("wait", "abort")},
        ),  # the ASV: MANUAL, disarmed; RC out of auto: leave
        ("rover", "goto_sample", {"ekf_loss": ("disarm", "resume"), "rc_takeover": ("wait", "abort")}),
        ("sub", "auv_survey", {"link_loss": ("hold", "resume")}),  # the survey holds in POSHOLD, as its tests say
    ],
)
def test_a_seed_systems_rules_are_its_trees_defaults(vehicle: str, tree: str, seed: dict[str, tuple[str, str]]) -> None:
    body = "sampling: {duration_s: 2}\n" if tree == "goto_sample" else ""
    waypoint = "waypoints:\n  - {lat: 47.3978, lon: 8.5456, sample: true}\n" if tree == "goto_sample" else WP
    mission = load_mission_text(HEAD.format(vehicle=vehicle, tree=tree) + body + waypoint, "m.yaml")
    assert pairs(mission) == failsafes.VEHICLE_FAILSAFES[vehicle] | seed


def test_an_entry_overrides_only_what_it_says() -> None:
    mission = load(
        "limits: {recovery_timeout_s: 45}\nfailsafe:\n  link_loss: {reaction: rtl}\n  gps_glitch: {timeout_s: 5}\n  ekf_loss: {recovery: abort}\n"
    )
    policy = failsafe_policy(mission)
    assert policy["link_loss"] == FailsafePolicy("link_loss", "rtl", "resume", 45.0)  # the rover's recovery, the mission's limit
    assert policy["gps_glitch"] == FailsafePolicy("gps_glitch", "hold", "resume", 5.0)
    assert policy["ekf_loss"] == FailsafePolicy("ekf_loss", "hold", "abort", 45.0)
    assert policy["battery_low"] == FailsafePolicy("battery_low", "rtl", "abort", 45.0)


ALLOWED = "link_loss, rc_takeover, disarmed, rc_loss, ekf_loss, gps_glitch, heading_insane, battery_low, geofence_breach, energy, keep_out"


@pytest.mark.parametrize(
    ("vehicle", "body", "error"),
    [
        ("sub", "failsafe:\n  battery_low: {reaction: rtl}\n",
         "6:27: failsafe.battery_low.reaction: rtl: not for a sub (a sub has no RTL: use surface)"),
        ("rover", "failsafe:\n  link_loss: {reaction: surface}\n",
         "6:25: failsafe.link_loss.reaction: surface: not for a rover (only a sub can surface)"),
        ("vtol", "limits: {acceptance_radius_m: 80}\nfailsafe:\n  ekf_loss: {reaction: disarm}\n",
         "7:24: failsafe.ekf_loss.reaction: disarm: not for a vtol (disarming a vtol would drop it)"),
        ("rover", "failsafe:\n  battery_low: {timeout_s: 30}\n",
         "6:28: failsafe.battery_low.timeout_s: recovery abort ends the mission at once: a time limit is only for resume"),
        ("rover", "failsafe:\n  geofence_breach: {recovery: resume}\n",  # held outside, the vehicle never comes back in
         "6:31: failsafe.geofence_breach.recovery: resume after hold: a vehicle held outside the fence never comes back in; "
         "use reaction rtl, or recovery abort"),
        ("rover", "failsafe:\n  link_los: {reaction: hold}\n", f"6:3: failsafe.link_los: unknown field (did you mean link_loss? allowed: {ALLOWED})"),
        ("rover", "failsafe:\n  link_loss: {reaction: land}\n",
         "6:25: failsafe.link_loss.reaction: 'land': Input should be 'hold', 'loiter', 'rtl', 'surface', 'disarm' or 'wait'"),
        ("rover", "failsafe:\n  link_loss: {timeout_s: 0}\n", "6:26: failsafe.link_loss.timeout_s: 0: Input should be greater than 0"),
    ],
)  # fmt: skip
def test_a_policy_the_vehicle_cannot_follow_is_refused_where_it_is_written(vehicle: str, body: str, error: str) -> None:
    assert errors_of(body, vehicle, "waypoints") == [f"m.yaml:{error}"]


@pytest.mark.parametrize("reaction", ["hold", "loiter", "rtl", "disarm"])
@pytest.mark.parametrize("condition", ["rc_takeover", "disarmed"])
def test_a_persons_precedence_is_not_a_policy(condition: str, reaction: str) -> None:
    """A take-over or a disarm is a person's act (or the autopilot's own failsafe's): the only reaction is hands off, refused at load."""
    column = len(f"  {condition}: {{reaction: ") + 1  # where the reaction is written
    why = {
        "rc_takeover": "a person who takes over always wins: the executive keeps its hands off (reaction wait), "
        "it never commands against the take-over switch",
        "disarmed": "a vehicle disarmed mid-mission was disarmed by a person (or by the autopilot's own failsafe), who always wins: "
        "the executive keeps its hands off (reaction wait)",
    }[condition]
    body = f"failsafe:\n  {condition}: {{reaction: {reaction}}}\n"
    assert errors_of(body) == [f"m.yaml:6:{column}: failsafe.{condition}.reaction: {reaction}: {why}"]


@pytest.mark.parametrize("condition", ["rc_takeover", "disarmed"])
def test_waiting_hands_off_is_a_persons_only_reaction_and_its_recovery_is_the_missions(condition: str) -> None:
    mission = load(f"failsafe:\n  {condition}: {{reaction: wait, recovery: abort}}\n")
    assert failsafe_policy(mission)[condition] == FailsafePolicy(condition, "wait", "abort", mission.limits.recovery_timeout_s)


def test_disarm_is_refused_on_the_rc_route_tree() -> None:
    body = "failsafe:\n  link_loss: {reaction: disarm}\n"
    text = HEAD.format(vehicle="rover", tree="ugv_rc_route") + body + "waypoints: []\n"
    with pytest.raises(MissionError) as refused:
        load_mission_text(text, "m.yaml")
    assert [str(e) for e in refused.value.errors] == [
        "m.yaml:6:25: failsafe.link_loss.reaction: disarm: not in tree ugv_rc_route (the operator arms and disarms with switch D)"
    ]


def test_the_readmes_table_of_next_reactions_is_the_code_s() -> None:
    """README's failsafe table (firmware, reaction, needs, next) is executive/autopilot/fallbacks.py's FALLBACKS, row for row."""
    from pathlib import Path

    from executive.autopilot.fallbacks import DISARM, FALLBACKS
    from executive.io.mavlink.modes import PX4_EQUIVALENTS

    labels = {
        ("ardupilot", "rover"): "ArduRover (rover, boat)", ("ardupilot", "boat"): "ArduRover (rover, boat)", ("ardupilot", "sub"): "ArduSub",
        ("ardupilot", "vtol"): "ArduPlane QuadPlane (vtol)", ("px4", "rover"): "PX4 rover", ("px4", "vtol"): "PX4 VTOL",
    }  # fmt: skip

    def shown(firmware: str, step: str) -> str:
        return "disarm" if step == DISARM else PX4_EQUIVALENTS.get(step, step) if firmware == "px4" else step

    code = {
        (labels[firmware, kind], shown(firmware, step), "position" if rule.needs_position else "-", shown(firmware, rule.then))
        for (firmware, kind), table in FALLBACKS.items()
        for step, rule in table.items()
        if rule.then is not None
    }
    readme = (Path(__file__).parents[2] / "docs" / "failsafes.md").read_text(encoding="utf-8")  # README's section, in the manual
    section = readme[readme.index("### Failsafes (`failsafe:`)") : readme.index("### When a person intervenes")]
    rows = re.findall(r"^\| ((?:Ardu|PX4)[^|]*) \| ([^|]+) \| ([^|]+) \| ([^|]+) \|", section, re.MULTILINE)
    assert {tuple(cell.strip() for cell in row) for row in rows} == code
    assert len(rows) == len(code)  # one row each
