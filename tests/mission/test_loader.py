"""The mission loader: every problem in a mission file, located as FILE:LINE:COL: FIELD: message."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from executive import trees
from executive.admission import checks as admission
from executive.mission import loader
from executive.mission.errors import FieldError, MissionError, format_path
from executive.mission.loader import load_mission, load_mission_text
from executive.mission.model import Mission

BROKEN = sorted((Path(__file__).parents[1] / "data" / "broken_missions").glob("*.yaml"))
EXPECT = re.compile(r"# expect: (\d+):(\d+) (\S+)$")
WAYPOINT = "{lat: 47.397742, lon: 8.545594}"


def errors_of(text: str) -> list[str]:
    """Every error the loader reports for ``text`` (as file ``m.yaml``), as printed."""
    with pytest.raises(MissionError) as info:
        load_mission_text(text, "m.yaml")
    return [str(e) for e in info.value.errors]


def file_errors(path: Path) -> list[FieldError]:
    """Every error of a mission file as ``executive validate`` and ``run`` report them: the file, and whether its tree is found."""
    with pytest.raises(MissionError) as info:
        admission.load_mission(path)
    return info.value.errors


def test_minimal_mission_loads(minimal_yaml: str) -> None:
    mission = load_mission_text(minimal_yaml, "m.yaml")
    assert (mission.version, mission.name, mission.vehicle, mission.tree) == (1, "square", "rover", "waypoints")
    assert [(w.lat, w.lon) for w in mission.waypoints] == [(47.397742, 8.545594)]


def test_the_corpus_covers_the_known_problems() -> None:
    assert len(BROKEN) >= 25


@pytest.mark.parametrize("path", BROKEN, ids=lambda p: p.stem)
def test_broken_mission_reports_first_error_where_its_comment_says(path: Path) -> None:
    match = EXPECT.match(path.read_text(encoding="utf-8").splitlines()[0])
    assert match, f"{path.name}: the first line must be '# expect: LINE:COL FIELD'"
    first = file_errors(path)[0]
    assert (first.file, first.line, first.column, first.field) == (str(path), int(match[1]), int(match[2]), match[3])


def test_every_error_is_reported_in_file_order(minimal_yaml: str) -> None:
    text = minimal_yaml + "  - lat: 95.0\n    lon: yes\n    latt: 1\nrc: {takeover_channel: 6.0}\n"
    assert errors_of(text) == [
        "m.yaml:7:10: waypoints[1].lat: 95.0: Input should be less than or equal to 90 (waypoint 2)",
        "m.yaml:8:10: waypoints[1].lon: expected a number, got bool true (YAML 1.1 reads yes as a boolean) (waypoint 2)",
        "m.yaml:9:5: waypoints[1].latt: unknown field (did you mean lat? "
        "allowed: lat, lon, alt_m, name, speed_m_s, depth_m, altitude_m, control_mode, sample) (waypoint 2)",
        "m.yaml:10:24: rc.takeover_channel: expected an integer, got number 6.0",
    ]


def test_an_unknown_field_close_to_a_known_one_gets_a_suggestion(minimal_yaml: str) -> None:
    """Issue 28: `limits.recovery_timeout` (the _s left out) got the allowed fields and no suggestion."""
    (error,) = errors_of(minimal_yaml + "limits:\n  recovery_timeout: 30\n")
    assert error.startswith("m.yaml:8:3: limits.recovery_timeout: unknown field (did you mean recovery_timeout_s? allowed: acceptance_radius_m, ")


def test_a_duplicate_key_is_reported_with_the_errors_of_the_value_that_wins(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml + "vehicle: car\n") == [
        "m.yaml:7:1: vehicle: duplicate key (an earlier one is ignored)",
        "m.yaml:7:10: vehicle: 'car': Input should be 'rover', 'boat', 'sub' or 'vtol'",
    ]


def test_each_duplicate_is_located_at_its_own_key(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml + "name: b\nname: c\n") == [
        "m.yaml:7:1: name: duplicate key (an earlier one is ignored)",
        "m.yaml:8:1: name: duplicate key (an earlier one is ignored)",
    ]


@pytest.mark.parametrize(
    ("waypoint", "field", "message"),
    [
        ("{lat: 95.0, lon: 8.5}", "lat", "95.0: Input should be less than or equal to 90"),
        ("{lat: -90.5, lon: 8.5}", "lat", "-90.5: Input should be greater than or equal to -90"),
        ("{lat: yes, lon: 8.5}", "lat", "expected a number, got bool true (YAML 1.1 reads yes as a boolean)"),
        ("{lat: true, lon: 8.5}", "lat", "expected a number, got bool true"),
        (
            "{lat: 1e3, lon: 8.5}",
            "lat",
            "expected a number, got string '1e3' (YAML 1.1 reads 1e3 as a string: write a number with a dot and a signed exponent, e.g. 1.0e+3)",
        ),
        ("{lat: '1e3', lon: 8.5}", "lat", "expected a number, got string '1e3'"),
        ("{lat: .nan, lon: 8.5}", "lat", "nan: Input should be a finite number"),
        ("{lat: [1], lon: 8.5}", "lat", "expected a number, got a list"),
        ("{lat: ~, lon: 8.5}", "lat", "expected a number, got null"),
        ("{lat: 1.0, lon: 8.5, name: off}", "name", "expected a string, got bool false (YAML 1.1 reads off as a boolean)"),
        ("{lat: 1.0, lon: 8.5, name: 2024-05-01}", "name", "expected a string, got date 2024-05-01"),
        ("{lat: 1.0, lon: 8.5, name: " + "x" * 70 + "}", "name", "'" + "x" * 36 + "...: String should have at most 64 characters"),
        ("{lat: 1.0, lon: 8.5, control_mode: deep}", "control_mode", "'deep': Input should be 'depth' or 'altitude'"),
        ("{lon: 8.5}", "lat", "required field is missing"),
    ],
)
def test_waypoint_messages_say_what_is_wrong(minimal_yaml: str, waypoint: str, field: str, message: str) -> None:
    with pytest.raises(MissionError) as info:
        load_mission_text(minimal_yaml.replace(WAYPOINT, waypoint), "m.yaml")
    assert [(e.line, e.field, e.message) for e in info.value.errors] == [(6, f"waypoints[0].{field}", f"{message} (waypoint 1)")]


def test_a_waypoint_that_is_not_a_mapping(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml.replace(WAYPOINT, "[47.3, 8.5]")) == ["m.yaml:6:5: waypoints[0]: expected a mapping, got a list (waypoint 1)"]


def test_model_validator_message_has_no_pydantic_prefix(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml + "limits:\n  speed_m_s: {min: 5.0, max: 1.0}\n") == [
        "m.yaml:8:14: limits.speed_m_s: min (5.0) is greater than max (1.0)"
    ]


def test_values_merged_with_an_anchor_are_located_at_the_anchor(minimal_yaml: str) -> None:
    text = minimal_yaml + "  - &base {lat: 47.4, lon: 8.55, speed_m_s: 9.0}\n  - <<: *base\n    speed_m_s: 1.0\n  - <<: *base\n  - *base\n"
    outside = "9.0 m/s is outside limits.speed_m_s [0.1, 5.0]"
    assert errors_of(text) == [f"m.yaml:7:45: waypoints[{i}].speed_m_s: {outside} (waypoint {i + 1})" for i in (1, 3, 4)]


def test_anchors_and_merges_within_the_limits_load(minimal_yaml: str) -> None:
    mission = load_mission_text(minimal_yaml + "  - &p {lat: 47.4, lon: 8.55}\n  - *p\n  - {<<: *p, lat: 47.401}\n", "m.yaml")
    assert [(w.lat, w.lon) for w in mission.waypoints[1:]] == [(47.4, 8.55), (47.4, 8.55), (47.401, 8.55)]


def test_a_key_yaml_reads_as_a_bool_is_named_as_written(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml + "off: 1\n") == ["m.yaml:7:1: off: expected a string key, got bool false (YAML 1.1 reads off as a boolean)"]


def test_a_path_through_keys_that_are_not_text_is_named() -> None:
    paths = [(None,), (1.5, "x"), ("rc", True), ("waypoints", 0, None)]
    assert [format_path(path) for path in paths] == ["None", "1.5.x", "rc.True", "waypoints[0].None"]


def test_a_null_key_beside_a_refused_value_is_reported_with_it() -> None:
    # the rules between fields ran without both values and asked whether their message named the null key's path
    text = "version: 1\nname: square\nvehicle: rover\ntree: waypoints\nwaypoints: [.nan]\nnull: .nan\n"
    assert errors_of(text) == [
        "m.yaml:5:13: waypoints[0]: expected a mapping, got number nan (waypoint 1)",
        "m.yaml:6:1: null: expected a string key, got null",
    ]


def test_nesting_too_deep_through_aliases(minimal_yaml: str) -> None:
    text = minimal_yaml + "a: &a " + "[" * 40 + "]" * 40 + "\nb: " + "[" * 30 + "*a" + "]" * 30 + "\n"
    [error] = errors_of(text)
    assert error.startswith("m.yaml:7:") and error.endswith(": (yaml): nesting deeper than 64 levels (through aliases)")


def test_the_deepest_nesting_allowed_is_checked_by_the_model(minimal_yaml: str) -> None:
    text = minimal_yaml + "x: " + "[" * 63 + "]" * 63 + "\n"
    assert errors_of(text) == [f"m.yaml:7:1: x: unknown field (allowed: {', '.join(Mission.model_fields)})"]


def test_alias_count_limit_is_exactly_100(minimal_yaml: str) -> None:
    aliases = "x: &a 1\ny: [" + ", ".join(["*a"] * 100) + "]\n"
    assert [e.split(": ", 2)[1] for e in errors_of(minimal_yaml + aliases)] == ["x", "y"]  # unknown fields, but no alias error
    assert errors_of(minimal_yaml + aliases.replace("]", ", *a]")) == ["m.yaml:8:405: (yaml): more than 100 aliases (refusing a possible alias bomb)"]


def test_expansion_limit_counts_what_aliases_name(minimal_yaml: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(loader, "MAX_VALUES", 40)  # the first alias makes 39 (nodes, keys included)
    assert errors_of(minimal_yaml + "x: &a [1, 2, 3, 4, 5, 6, 7, 8, 9]\ny: [*a, *a]\n") == [
        "m.yaml:8:9: (yaml): aliases expand the document to more than 40 values (refusing a possible alias bomb)"
    ]


def test_a_mapping_key_that_is_a_list(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml + "? [a]\n: 1\n") == ["m.yaml:7:3: (yaml): while constructing a mapping, found unhashable key"]


def test_a_control_character_is_located(minimal_yaml: str) -> None:
    assert errors_of(minimal_yaml.replace("name: square", "name: sq\x07uare")) == [
        "m.yaml:2:9: (yaml): character #x0007: special characters are not allowed"
    ]


def test_a_byte_order_mark_is_accepted(tmp_path: Path, minimal_yaml: str) -> None:
    (tmp_path / "m.yaml").write_bytes(b"\xef\xbb\xbf" + minimal_yaml.encode())
    assert load_mission(tmp_path / "m.yaml").name == "square"


def test_a_file_that_is_not_utf8(tmp_path: Path, minimal_yaml: str) -> None:
    path = tmp_path / "m.yaml"
    path.write_bytes(minimal_yaml.replace("square", "caf\u00e9 \u00f1").encode("utf-8").replace(b"\xc3\xb1", b"\xf1"))
    offset = path.read_bytes().index(b"\xf1")
    assert file_errors(path) == [FieldError(str(path), 2, 12, "(file)", f"not UTF-8 text: byte 0xf1 at offset {offset}")]


def test_an_empty_file(tmp_path: Path) -> None:
    (tmp_path / "m.yaml").write_bytes(b"")
    assert file_errors(tmp_path / "m.yaml") == [
        FieldError(str(tmp_path / "m.yaml"), 1, 1, "(mission)", "the file holds no YAML document (it is empty or only comments)")
    ]


def test_a_missing_file(tmp_path: Path) -> None:
    assert file_errors(tmp_path / "none.yaml") == [FieldError(str(tmp_path / "none.yaml"), 1, 1, "(file)", "No such file or directory")]


def test_a_directory(tmp_path: Path) -> None:
    assert file_errors(tmp_path) == [FieldError(str(tmp_path), 1, 1, "(file)", "Is a directory")]


def test_a_file_over_the_size_limit_is_refused_before_parsing(tmp_path: Path, minimal_yaml: str, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(minimal_yaml, encoding="utf-8")
    monkeypatch.setattr(loader, "MAX_BYTES", len(minimal_yaml))
    assert load_mission(path).name == "square"
    path.write_text(minimal_yaml + "\n: [ not yaml", encoding="utf-8")
    message = f"file is {path.stat().st_size} bytes; a mission file may have at most {len(minimal_yaml)} (1 MiB)"
    assert [str(e) for e in file_errors(path)] == [f"{path}:1:1: (file): {message}"]


def test_the_size_limit_is_1_mib(tmp_path: Path) -> None:
    (tmp_path / "big.yaml").write_bytes(b"#" * (1024 * 1024 + 1))
    assert [e.message for e in file_errors(tmp_path / "big.yaml")] == ["file is 1048577 bytes; a mission file may have at most 1048576 (1 MiB)"]
    with pytest.raises(MissionError, match="file is 1048577 bytes"):
        load_mission_text("#" * (1024 * 1024 + 1), "m.yaml")


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("ab:-[]{}&*!<>|'\",?#%@ \n\t0.9e+yes~\x07\u00e9")), max_size=80))
def test_any_text_gives_a_mission_or_located_errors(text: str) -> None:
    try:
        load_mission_text(text, "m.yaml")
    except MissionError as exc:
        assert exc.errors
        assert all(1 <= e.line <= text.count("\n") + 1 and e.column >= 1 and e.field for e in exc.errors)


ONE_PASS = """\
version: 1
name: stages
vehicle: sub
bogus: 1
limits:
  speed_m_s: {min: 0.1, max: "fast"}
  link_timeout_s: -1
waypoints:
  - {lat: 44.09, lon: 9.86, depth_m: 150, control_mode: depth, speed_m_s: 2.0}
  - {lat: 444.0, lon: 9.86, depth_m: 5}
  - {lat: 44.09, lon: 9.86, control_mode: altitude, altitude_m: 1, colour: red}
  - {lat: 44.09, lon: 9.86, control_mode: depth, depth_m: -2}
  - {lat: 44.09, lon: 9.86, speed_m_s: 0.5, sample: true}
"""


def test_every_error_comes_in_one_pass_cross_field_ones_included() -> None:
    """Issue 13: depth 150 and altitude 1 were reported only once the 6 other errors were fixed."""
    assert errors_of(ONE_PASS) == [
        "m.yaml:4:1: bogus: unknown field (allowed: version, name, vehicle, autopilot, tree, description, drive, auto_arm, home, geofence, "
        "rally_points, limits, rc, failsafe, sampling, vtol, rc_route, simulator, energy, waypoints)",
        "m.yaml:6:30: limits.speed_m_s.max: expected a number, got string 'fast'",
        "m.yaml:7:19: limits.link_timeout_s: -1: Input should be greater than 0",
        "m.yaml:9:38: waypoints[0].depth_m: 150.0 m is outside limits.depth_m [0.0, 100.0] (waypoint 1)",
        "m.yaml:10:11: waypoints[1].lat: 444.0: Input should be less than or equal to 90 (waypoint 2)",
        "m.yaml:11:65: waypoints[2].altitude_m: 1.0 m is outside limits.altitude_m [2.0, 100.0] (waypoint 3)",
        "m.yaml:11:68: waypoints[2].colour: unknown field (allowed: lat, lon, alt_m, name, speed_m_s, depth_m, altitude_m, control_mode, sample)"
        " (waypoint 3)",
        "m.yaml:12:59: waypoints[3].depth_m: -2: Input should be greater than or equal to 0 (waypoint 4)",
        "m.yaml:13:53: waypoints[4].sample: only goto_sample takes samples (waypoint 5)",
    ]


def test_a_rule_judged_by_a_value_left_out_is_not_reported() -> None:
    """The waypoint speeds are not checked against limits the file got wrong (that would judge them by the defaults)."""
    errors = errors_of(ONE_PASS)
    assert not any("].speed_m_s:" in e for e in errors)
    with_limits = errors_of(ONE_PASS.replace('"fast"', "1.0"))  # the file's own limits: judged by them
    assert "m.yaml:9:75: waypoints[0].speed_m_s: 2.0 m/s is outside limits.speed_m_s [0.1, 1.0] (waypoint 1)" in with_limits


def test_a_list_that_lost_an_item_is_not_judged_whole(monkeypatch: pytest.MonkeyPatch) -> None:
    """goto_sample's 'a waypoint with sample: true' is not claimed missing when the sample point itself was refused."""
    monkeypatch.setattr(trees, "available", lambda: ["goto_sample"])
    text = "version: 1\nname: s\nvehicle: boat\ntree: goto_sample\nwaypoints:\n  - {lat: 1.0, lon: 1.0}\n  - {lat: 100.0, lon: 1.0, sample: true}\n"
    assert errors_of(text) == ["m.yaml:7:11: waypoints[1].lat: 100.0: Input should be less than or equal to 90 (waypoint 2)"]


def test_an_error_in_a_waypoint_says_the_persons_number_and_its_name_after_the_path(minimal_yaml: str) -> None:
    """Issue 43: `waypoints[6]` (the file's path, 0-based) beside status, `ctl route` and `report`'s `waypoint 7 of 8`."""
    text = minimal_yaml + "".join(f"  - {{lat: 47.3977{n}, lon: 8.5456}}\n" for n in range(5)) + "  - {lat: 95.0, lon: 8.5, name: far}\n"
    assert errors_of(text) == ["m.yaml:12:11: waypoints[6].lat: 95.0: Input should be less than or equal to 90 (waypoint 7, 'far')"]


@pytest.fixture
def parses(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The file names the YAML is parsed for (from now on, none kept from before)."""
    monkeypatch.setattr(loader, "_read_lately", {}, raising=False)
    parsed: list[str] = []
    parse = loader._parse

    def counted(text: str, filename: str, what: str) -> Any:
        parsed.append(filename)
        return parse(text, filename, what)

    monkeypatch.setattr(loader, "_parse", counted)
    return parsed


def test_a_file_read_again_is_parsed_once_and_loads_an_equal_mission_of_its_own(minimal_yaml: str, parses: list[str]) -> None:
    first, second = load_mission_text(minimal_yaml, "m.yaml"), load_mission_text(minimal_yaml, "m.yaml")
    assert parses == ["m.yaml"]
    assert first == second and first is not second and first.waypoints is not second.waypoints
    load_mission_text(minimal_yaml, "other.yaml")  # another file's errors would name it
    assert parses == ["m.yaml", "other.yaml"]


def test_a_file_that_cannot_be_read_is_refused_alike_each_time(minimal_yaml: str, parses: list[str], monkeypatch: pytest.MonkeyPatch) -> None:
    broken = minimal_yaml + "x: [1\n"
    assert errors_of(broken) == errors_of(broken) != []
    assert parses == ["m.yaml", "m.yaml"]
    expanding = minimal_yaml + "x: &a [1, 2, 3, 4, 5, 6, 7, 8, 9]\ny: [*a, *a]\n"
    assert [e.split(": ")[1] for e in errors_of(expanding)] == ["x", "y"]  # unknown fields: read
    monkeypatch.setattr(loader, "MAX_VALUES", 40)  # the same text read under other limits is read again
    assert errors_of(expanding) == ["m.yaml:8:9: (yaml): aliases expand the document to more than 40 values (refusing a possible alias bomb)"]


def test_only_a_few_small_files_are_kept(minimal_yaml: str, parses: list[str]) -> None:
    for n in range(loader.READ_KEPT + 3):
        load_mission_text(minimal_yaml, f"m{n}.yaml")
    assert len(loader._read_lately) == loader.READ_KEPT
    big = minimal_yaml + "#" * loader.READ_KEPT_MAX_CHARS + "\n"
    load_mission_text(big, "big.yaml")
    load_mission_text(big, "big.yaml")
    assert parses[-2:] == ["big.yaml", "big.yaml"] and len(loader._read_lately) == loader.READ_KEPT
    large = minimal_yaml + "#" * (loader.READ_KEPT_MAX_CHARS - len(minimal_yaml) - 1) + "\n"  # as large as one kept may be
    for n in range(loader.READ_KEPT):
        load_mission_text(large, f"large{n}.yaml")
    assert sum(len(text) for text, *_ in loader._read_lately) <= loader.READ_KEPT_CHARS
    assert len(loader._read_lately) == loader.READ_KEPT_CHARS // len(large)
