"""Hostile mission, fault and ground-station files: refused with exit 2 and FILE:LINE:COL, never a traceback.

Every case is written from the test to ``tmp_path`` (huge, deeply nested, non-UTF-8, BOM, NUL, CRLF...).
The property tests mutate valid files (bytes, and the YAML data) and hold the loaders to their contract:
a valid model back, or :class:`MissionError` with every error located at a line and column of the file.
"""

from __future__ import annotations

import copy
import datetime
import functools
import json
import math
import re
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.admission.checks import load_mission, load_mission_text  # the file, its tree and instrument: what run and validate read
from executive.cli import main
from executive.mission.errors import MissionError
from executive.mission.formats.plan_files import import_file
from executive.mission.model import Mission
from executive.sim.faults import FaultPlan, load_faults
from tests_support import executive_process

ROOT = Path(__file__).parents[2]
MINIMAL = (ROOT / "tests" / "data" / "minimal_mission.yaml").read_text(encoding="utf-8")
BROKEN = sorted((ROOT / "tests" / "data" / "broken_missions").glob("*.yaml"))
EXPECT = re.compile(r"# expect: (\d+):(\d+) (\S+)$")
MISSION_SEEDS = [MINIMAL.encode()] + [p.read_bytes() for p in sorted((ROOT / "missions").glob("*.yaml"))]
FAULT_SEEDS = [p.read_bytes() for p in sorted((ROOT / "missions" / "faults").glob("*.yaml"))]
PLAN_SEEDS = sorted((ROOT / "tests" / "data" / "plans").glob("*"))
WAYPOINT = "{lat: 47.397742, lon: 8.545594}"
LINE_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # what YAML counts as the end of a line
FUZZ = settings(derandomize=True, deadline=None, max_examples=80, suppress_health_check=[HealthCheck.too_slow])


def _waypoint(extra: str) -> bytes:
    return MINIMAL.replace(WAYPOINT, WAYPOINT[:-1] + ", " + extra + "}").encode()


def _lat(value: str) -> bytes:
    return MINIMAL.replace("47.397742", value).encode()


def _laughs() -> bytes:
    """The billion laughs: nine levels of ten aliases each."""
    levels = "".join(f"l{i}: &{chr(98 + i)} [" + ", ".join([f"*{chr(97 + i)}"] * 10) + "]\n" for i in range(8))
    return ("version: 1\nlol: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + levels).encode()


def _merge_bomb() -> bytes:
    """Merge keys that each pull in nine copies of the previous mapping."""
    merges = "".join(f"m{i}: &m{i} {{<<: [" + ", ".join([f"*{'a' if i == 0 else f'm{i - 1}'}"] * 9) + "]}\n" for i in range(12))
    return (MINIMAL + "a: &a {x: 1}\n" + merges).encode()


#: name -> (the file's bytes, where its first error must be: line, column, field).
HOSTILE: dict[str, tuple[Callable[[], bytes], tuple[int, int, str]]] = {
    "over_1_mib_of_comment": (lambda: (MINIMAL + "#" * (1 << 20) + "\n").encode(), (1, 1, "(file)")),
    "over_1_mib_of_route": (lambda: (MINIMAL + "  - " + WAYPOINT + "\n").encode() * 30_000, (1, 1, "(file)")),
    "deep_flow_nesting": (lambda: (MINIMAL + "x: " + "[" * 100_000 + "]" * 100_000 + "\n").encode(), (7, 67, "(yaml)")),
    "deep_block_nesting": (lambda: ("version: 1\n" + "".join(" " * i + f"k{i}:\n" for i in range(1_000))).encode(), (66, 65, "(yaml)")),
    "billion_laughs": (_laughs, (7, 37, "(yaml)")),
    "merge_key_bomb": (_merge_bomb, (13, 30, "(yaml)")),
    "latin1_byte": (lambda: MINIMAL.replace("square", "caf\u00e9").encode("latin-1"), (2, 10, "(file)")),
    "utf16_with_bom": (lambda: MINIMAL.encode("utf-16"), (1, 1, "(file)")),
    "utf8_bom_then_an_error": (lambda: b"\xef\xbb\xbf" + MINIMAL.replace("version: 1", "version: 2").encode(), (1, 10, "version")),
    "utf8_bom_then_a_latin1_byte": (lambda: b"\xef\xbb\xbf" + MINIMAL.replace("version: 1", "version: \u00e9").encode("latin-1"), (1, 10, "(file)")),
    "nul_in_a_value": (lambda: MINIMAL.replace("square", "sq\x00uare").encode(), (2, 9, "(yaml)")),
    "nul_first": (lambda: b"\x00" + MINIMAL.encode(), (1, 1, "(yaml)")),
    "crlf_with_an_error": (lambda: MINIMAL.replace("47.397742", "95.0").replace("\n", "\r\n").encode(), (6, 11, "waypoints[0].lat")),
    "cr_only_with_a_latin1_byte": (lambda: MINIMAL.replace("rover", "r\u00f6ver").replace("\n", "\r").encode("latin-1"), (3, 11, "(file)")),
    "500k_character_name": (lambda: MINIMAL.replace("square", "x" * 500_000).encode(), (2, 7, "name")),
    "500k_character_garbage_line": (lambda: (MINIMAL + "description: " + "x" * 500_000 + ": y\n").encode(), (7, 500_014, "(yaml)")),
    "2000_character_key": (lambda: (MINIMAL + "k" * 2_000 + ": 1\n").encode(), (7, 2_001, "(yaml)")),
    "1e400": (lambda: _lat("1.0e+400"), (6, 11, "waypoints[0].lat")),
    "1e400_without_dot": (lambda: _lat("1e400"), (6, 11, "waypoints[0].lat")),
    "nan_speed": (lambda: _waypoint("speed_m_s: .nan"), (6, 48, "waypoints[0].speed_m_s")),
    "inf_timeout": (lambda: (MINIMAL + "limits: {leg_timeout_s: .inf}\n").encode(), (7, 25, "limits.leg_timeout_s")),
    "minus_inf_home": (lambda: (MINIMAL + "home: {lat: -.Inf, lon: 8.0}\n").encode(), (7, 13, "home.lat")),
    "int64_max_channel": (lambda: (MINIMAL + "rc: {takeover_channel: 9223372036854775807}\n").encode(), (7, 24, "rc.takeover_channel")),
    "2_pow_64_lat": (lambda: _lat("18446744073709551616"), (6, 11, "waypoints[0].lat")),
    "5000_digit_integer": (lambda: _lat("9" * 5_000), (6, 11, "(yaml)")),
    "5000_digit_hex_integer": (lambda: _lat("0x" + "f" * 5_000), (6, 11, "waypoints[0].lat")),
    "sexagesimal_float_overflow": (lambda: _lat("1" + ":59" * 300 + ".5"), (6, 11, "(yaml)")),
    "duplicate_key_in_a_range": (
        lambda: (MINIMAL + "limits:\n  speed_m_s: {min: 0.1, max: 5.0, max: 4.0}\n").encode(),
        (8, 35, "limits.speed_m_s.max"),
    ),
    "duplicate_key_in_a_waypoint": (lambda: _waypoint("lon: 8.6"), (6, 37, "waypoints[0].lon")),
    "duplicate_key_two_levels_down": (
        lambda: (MINIMAL + "rc:\n  switch_channels:\n    swa: 5\n    swa: 7\n").encode(),
        (10, 5, "rc.switch_channels.swa"),
    ),
    "binary_tag_number": (lambda: _lat("!!binary aGVsbG8="), (6, 11, "waypoints[0].lat")),
    "set_tag_number": (lambda: _lat("!!set {a, b}"), (6, 11, "waypoints[0].lat")),
    "timestamp_tag_number": (lambda: _lat("!!timestamp 2001-12-14t21:59:43.10-05:00"), (6, 11, "waypoints[0].lat")),
    "date_number": (lambda: _lat("2001-12-14"), (6, 11, "waypoints[0].lat")),
    "int_tag_on_letters": (lambda: _lat("!!int abc"), (6, 11, "(yaml)")),
    "float_tag_on_letters": (lambda: _lat("!!float abc"), (6, 11, "(yaml)")),
    "bool_tag_on_letters": (lambda: _lat("!!bool abc"), (6, 11, "(yaml)")),
    "timestamp_tag_on_letters": (lambda: _lat("!!timestamp abc"), (6, 11, "(yaml)")),
    "binary_tag_string": (lambda: MINIMAL.replace("square", "!!binary aGVsbG8=").encode(), (2, 7, "name")),
    "null_key": (lambda: _waypoint("~: 1"), (6, 37, "waypoints[0].~")),
    "float_key": (lambda: _waypoint("1.5: 1"), (6, 37, "waypoints[0].1.5")),
    "date_key": (lambda: (MINIMAL + "2001-01-01: 1\n").encode(), (7, 1, "2001-01-01")),
}


def yaml_lines(text: str) -> list[str]:
    """The lines of ``text`` as YAML counts them (CR, LF, CRLF, NEL, LS, PS end a line)."""
    return LINE_BREAK.split(text)


#: How lines are counted: YAML's way (mission and fault files), JSON's ("\n" only) and Python's str.splitlines (.waypoints).
YAML_LINES: tuple[Callable[[str], list[str]], ...] = (yaml_lines,)
ANY_LINES: tuple[Callable[[str], list[str]], ...] = (yaml_lines, lambda text: text.split("\n"), lambda text: text.splitlines() or [""])


def assert_located(exc: MissionError, text: str, file: str, counts: tuple[Callable[[str], list[str]], ...] = YAML_LINES) -> None:
    """Every error names the file, a line of it and a column on (or just past the end of) that line, lines as one of ``counts`` has them."""
    assert exc.errors, "a refusal names at least one problem"
    for error in exc.errors:
        assert error.file == file
        assert error.field and error.message, str(error)
        for lines in (count(text) for count in counts):
            if 1 <= error.line <= len(lines) and 1 <= error.column <= len(lines[error.line - 1]) + 1:
                break
        else:
            lines = counts[0](text)
            assert 1 <= error.line <= len(lines), f"{error}: the file has {len(lines)} lines"
            raise AssertionError(f"{error}: line {error.line} has {len(lines[error.line - 1])} characters")


def assert_finite(value: Any, path: str = "") -> None:
    """No NaN or infinity anywhere in a validated model's data."""
    if isinstance(value, float):
        assert math.isfinite(value), f"{path} = {value}"
    elif isinstance(value, dict):
        for k, v in value.items():
            assert_finite(v, f"{path}.{k}")
    elif isinstance(value, list | tuple):
        for i, v in enumerate(value):
            assert_finite(v, f"{path}[{i}]")


def validate(path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, list[tuple[int, int, str]]]:
    """``executive validate PATH``: the exit code and every error printed, as (line, column, field)."""
    code = main(["validate", str(path)])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    printed = re.compile(re.escape(str(path)) + r":(\d+):(\d+): (\S+): \S")
    errors = []
    for line in err.splitlines():
        match = printed.match(line)
        assert match, f"not FILE:LINE:COL: FIELD: message: {line[:200]!r}"
        errors.append((int(match[1]), int(match[2]), match[3]))
    return code, errors


@pytest.mark.parametrize("name", HOSTILE)
def test_a_hostile_file_is_refused_with_its_location(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`executive validate` exits 2 and prints the first error exactly where the problem is; the loader locates every error."""
    make, where = HOSTILE[name]
    path = tmp_path / f"{name}.yaml"
    path.write_bytes(data := make())
    code, errors = validate(path, capsys)
    assert (code, errors[:1]) == (2, [where])
    with pytest.raises(MissionError) as info:
        load_mission(path)
    assert_located(info.value, data.decode("utf-8", "replace"), str(path))


@pytest.mark.parametrize("path", BROKEN, ids=lambda p: p.stem)
def test_the_broken_corpus_through_the_command_line(path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every file of the broken corpus: exit 2, its first error where its ``# expect:`` line says."""
    match = EXPECT.match(path.read_text(encoding="utf-8").splitlines()[0])
    assert match, f"{path.name}: the first line must be '# expect: LINE:COL FIELD'"
    code, errors = validate(path, capsys)
    assert (code, errors[:1]) == (2, [(int(match[1]), int(match[2]), match[3])])


@pytest.mark.parametrize("seed", [p for p in sorted((ROOT / "missions").glob("*.yaml"))], ids=lambda p: p.stem)
def test_crlf_and_a_bom_are_accepted(seed: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A valid mission saved with Windows line endings (and a UTF-8 BOM) validates, and loads to the same mission."""
    shutil.copytree(seed.parent / "events", tmp_path / "events")  # a simulator event file it names is checked as run checks it
    path = tmp_path / seed.name
    path.write_bytes(b"\xef\xbb\xbf" + seed.read_bytes().replace(b"\n", b"\r\n"))
    assert validate(path, capsys) == (0, [])
    assert load_mission(path) == load_mission(seed)


def test_the_real_command_exits_2_without_a_traceback(tmp_path: Path) -> None:
    """The installed entry point, in a process of its own, on a handful of the worst files at once."""
    names = ["over_1_mib_of_comment", "billion_laughs", "latin1_byte", "nul_first", "5000_digit_integer", "int_tag_on_letters", "null_key"]
    paths = []
    for name in names:
        paths.append(path := tmp_path / f"{name}.yaml")
        path.write_bytes(HOSTILE[name][0]())
    done = executive_process("validate", *map(str, paths))
    _, err = done.communicate(timeout=60)
    assert done.returncode == 2, err
    assert "Traceback" not in err
    firsts = [next(line for line in err.splitlines() if line.startswith(f"{path}:")) for path in paths]
    assert [line.split(": ")[0].removeprefix(f"{path}:") for line, path in zip(firsts, paths, strict=True)] == [
        f"{HOSTILE[n][1][0]}:{HOSTILE[n][1][1]}" for n in names
    ]


# -- property tests ----------------------------------------------------------------------------------------------

#: Byte strings a mutation likes to insert: YAML syntax, tags, special numbers, encodings, control characters.
TOKENS = [
    b"\x00", b"\xef\xbb\xbf", b"\r\n", b"\r", b"\n", b"\t", b"\x85", b"\xe2\x80\xa8", b"\xff", b"\xc3", b"\xed\xa0\x80",
    b"&a ", b"*a", b"<<: *a", b"<<: ", b"!!binary ", b"!!int ", b"!!float ", b"!!bool ", b"!!set ", b"!!timestamp ", b"!!python/object:os.system ",
    b"!x ", b"!!int x", b"!!float x ", b".nan", b".inf", b"-.inf", b"1e400", b"1.0e+400", b"9" * 40, b"9" * 4400, b"0x" + b"f" * 20,
    b"nan", b"inf", b"NaN", b"-Infinity", b"1e309", b"[" * 100, b"1:2:3", b"2001-12-14", b"~", b"yes", b"off",
    b"{", b"}", b"[", b"]", b"- ", b": ", b"? ", b", ", b"'", b'"', b"#", b"|", b">", b"%", b"@", b"---\n", b"...\n", b"%YAML 1.1\n", b"  ",
]  # fmt: skip


@st.composite
def mutated_bytes(draw: st.DrawFn, seeds: list[bytes]) -> bytes:
    """A seed with a few random byte flips, insertions, deletions and duplicated slices."""
    data = bytearray(draw(st.sampled_from(seeds)))
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["flip", "insert", "insert", "delete", "duplicate"]))
        at = draw(st.integers(0, len(data)))
        if op == "flip" and data:
            data[min(at, len(data) - 1)] ^= draw(st.integers(1, 255))
        elif op == "insert":
            data[at:at] = draw(st.sampled_from(TOKENS) | st.binary(min_size=1, max_size=6))
        elif op == "delete":
            del data[at : at + draw(st.integers(1, 12))]
        elif op == "duplicate":
            to = draw(st.integers(0, len(data)))
            data[to:to] = data[at : at + draw(st.integers(1, 40))]
    return bytes(data)


#: Values a mutation puts where a .plan had a value: wrong types, special numbers, huge integers, nesting.
JSON_VALUES = st.one_of(
    st.sampled_from(
        [math.nan, math.inf, -math.inf, 1e308, -0.0, 2**63, 2**64, -(2**63) - 1, 10**30, 10**400, True, False, None, "", "x" * 5000, [], {}]
    ),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(),
    st.text(max_size=20),
    st.recursive(st.none(), lambda inner: st.lists(inner, max_size=2) | st.dictionaries(st.text(max_size=5), inner, max_size=2), max_leaves=4),
)
#: Values a mutation puts where a seed had a value: wrong types, special numbers, YAML-only types.
HOSTILE_VALUES = st.one_of(
    st.sampled_from(
        [math.nan, math.inf, -math.inf, 1e308, -0.0, 2**63 - 1, 2**63, 2**64, -(2**63) - 1, 10**30, True, False, None, "", "yes", "1e3", "x" * 5000,
         b"\x00\xff", datetime.date(2001, 12, 14), datetime.datetime(2001, 12, 14, 21, 59), {"a", "b"}, [], {}, [1, 2], {"a": 1}, "\x07", "\ufeff"]
    ),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(),
    st.text(max_size=20),
)  # fmt: skip


def _places(data: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Paths of every value inside ``data`` (mapping keys and list indices)."""
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in items:
        yield (*path, key)
        yield from _places(value, (*path, key))


@functools.cache
def _seed_data(seed: bytes) -> Any:
    """A seed's YAML data, parsed once (the pure-Python parser took a sixth of the property tests' time)."""
    return yaml.safe_load(seed)


@st.composite
def mutated_yaml(draw: st.DrawFn, seeds: list[bytes]) -> str:
    """A seed's data with values replaced, removed or added, dumped as YAML in a random style (and line ending)."""
    data = copy.deepcopy(_seed_data(draw(st.sampled_from(seeds))))
    for _ in range(draw(st.integers(1, 4))):
        path = draw(st.sampled_from(list(_places(data)) or [()]))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        op = draw(st.sampled_from(["replace", "replace", "delete", "add"]))
        if not path:
            data = draw(HOSTILE_VALUES)
            break
        if op == "replace":
            parent[path[-1]] = draw(HOSTILE_VALUES)
        elif op == "delete":
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[draw(st.sampled_from(["x", "lat", "version", None, 1, 1.5, True]))] = draw(HOSTILE_VALUES)
        else:
            parent.append(draw(HOSTILE_VALUES))
    text = yaml.safe_dump(data, default_flow_style=draw(st.sampled_from([None, False, True])), allow_unicode=draw(st.booleans()), sort_keys=False)
    return draw(st.sampled_from(["", "\ufeff"])) + text.replace("\n", draw(st.sampled_from(["\n", "\r\n", "\r"])))


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("hostile") / "file.yaml"


def loaded_or_located(load: Callable[[], Any], text: str, file: str) -> Any:
    """What ``load()`` gives, every number of it finite; or None, every error it raised located in ``text`` of ``file``."""
    try:
        loaded = load()
    except MissionError as exc:
        assert_located(exc, text, file)
        return None
    assert_finite(loaded.model_dump())
    return loaded


def file_loaded_or_located(load: Callable[[Path], Any], path: Path, data: bytes) -> Any:
    """:func:`loaded_or_located` of ``load(path)``, ``data`` written there first."""
    path.write_bytes(data)
    return loaded_or_located(lambda: load(path), data.decode("utf-8", "replace"), str(path))


@FUZZ
@given(data=mutated_bytes(MISSION_SEEDS))
def test_mutated_mission_bytes_load_or_are_located(scratch: Path, data: bytes) -> None:
    """Random damage to a valid mission file: a Mission (every number finite) or located errors, never another exception."""
    file_loaded_or_located(load_mission, scratch, data)


@FUZZ
@given(text=mutated_yaml(MISSION_SEEDS))
def test_mutated_mission_data_loads_or_is_located(text: str) -> None:
    """Wrong types and special values anywhere in a valid mission: a Mission that re-validates, or located errors."""
    if (mission := loaded_or_located(lambda: load_mission_text(text, "m.yaml"), text, "m.yaml")) is not None:
        assert Mission.model_validate(mission.model_dump()) == mission


@FUZZ
@given(data=mutated_bytes(FAULT_SEEDS))
def test_mutated_fault_file_bytes_load_or_are_located(scratch: Path, data: bytes) -> None:
    """Fault files go through the same loader: a FaultPlan (every number finite) or located errors."""
    file_loaded_or_located(load_faults, scratch, data)


@FUZZ
@given(text=mutated_yaml(FAULT_SEEDS))
def test_mutated_fault_data_loads_or_is_located(scratch: Path, text: str) -> None:
    """Wrong types and special values anywhere in a valid fault file: a FaultPlan that re-validates, or located errors."""
    scratch.write_bytes(text.encode("utf-8", "surrogatepass"))
    if (plan := loaded_or_located(lambda: load_faults(scratch, vehicle="rover"), text, str(scratch))) is not None:
        assert FaultPlan.model_validate(plan.model_dump()) == plan


@st.composite
def mutated_json(draw: st.DrawFn, seeds: list[bytes]) -> bytes:
    """A JSON seed's data with values replaced, removed or added (NaN, infinities, huge integers, wrong types), dumped again."""
    data = json.loads(draw(st.sampled_from(seeds)))
    for _ in range(draw(st.integers(1, 4))):
        path = draw(st.sampled_from(list(_places(data))))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        op = draw(st.sampled_from(["replace", "replace", "delete"]))
        if op == "replace":
            parent[path[-1]] = draw(JSON_VALUES)
        else:
            del parent[path[-1]]
    return json.dumps(data, indent=draw(st.sampled_from([None, 4]))).encode()


def _plan_file_loads_or_is_located(path: Path, data: bytes, vehicle: str | None) -> None:
    path.write_bytes(data)
    try:
        imported = import_file(path, vehicle=vehicle)
    except MissionError as exc:
        assert_located(exc, data.decode("utf-8", "replace"), str(path), ANY_LINES)
    else:
        assert_finite(imported.mission.model_dump())
        assert load_mission_text(imported.yaml_text, "imported.yaml") == imported.mission


@FUZZ
@given(seed=st.sampled_from(PLAN_SEEDS), vehicle=st.sampled_from([None, "rover", "boat", "sub"]), data=st.data())
def test_mutated_ground_station_files_import_or_are_located(scratch: Path, seed: Path, vehicle: str | None, data: st.DataObject) -> None:
    """Damaged .plan and .waypoints files: an imported mission (finite, valid as YAML) or located errors, never another exception."""
    _plan_file_loads_or_is_located(scratch.with_suffix(seed.suffix), data.draw(mutated_bytes([seed.read_bytes()])), vehicle)


@FUZZ
@given(data=mutated_json([p.read_bytes() for p in PLAN_SEEDS if p.suffix == ".plan"]), vehicle=st.sampled_from([None, "rover", "boat"]))
def test_mutated_plan_data_imports_or_is_located(scratch: Path, data: bytes, vehicle: str | None) -> None:
    """Wrong types, NaN, infinities and huge integers anywhere in a valid .plan: an imported mission or located errors."""
    _plan_file_loads_or_is_located(scratch.with_suffix(".plan"), data, vehicle)


PLANS = ROOT / "tests" / "data" / "plans"
_PLAN = (PLANS / "rover_block.plan").read_bytes()
_WPL = (PLANS / "cmac_rover.waypoints").read_bytes()
_WPL_LAT = b"-35.36303667"  # the first waypoint's latitude

#: name -> (file name, its bytes): ground-station files that must be refused with located errors.
HOSTILE_PLANS: dict[str, tuple[str, Callable[[], bytes]]] = {
    "plan_5000_digit_integer": ("p.plan", lambda: _PLAN.replace(b'"version": 1', b'"version": ' + b"9" * 5_000, 1)),
    "plan_4000_digit_coordinate": ("p.plan", lambda: _PLAN.replace(b"-35.3633961993", b"-" + b"9" * 4_000, 1)),
    "plan_deep_nesting": ("p.plan", lambda: b'{"mission": ' + b"[" * 100_000 + b"]" * 100_000 + b"}"),
    "plan_nan": ("p.plan", lambda: _PLAN.replace(b"-35.3633961993", b"NaN", 1)),
    "plan_infinity": ("p.plan", lambda: _PLAN.replace(b"-35.3633961993", b"-Infinity", 1)),
    "plan_1e400": ("p.plan", lambda: _PLAN.replace(b"-35.3633961993", b"1e400", 1)),
    "plan_latin1": ("p.plan", lambda: _PLAN.replace(b'"Plan"', b'"Pl\xe4n"', 1)),
    "plan_nul": ("p.plan", lambda: _PLAN.replace(b'"Plan"', b'"Pl\x00n"', 1)),
    "plan_over_16_mib": ("p.plan", lambda: _PLAN + b" " * (16 << 20)),
    "waypoints_nan": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"nan", 1)),
    "waypoints_inf": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"-inf", 1)),
    "waypoints_1e400": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"1e400", 1)),
    "waypoints_5000_digits": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"9" * 5_000, 1)),
    "waypoints_latin1": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"-35.3\xb0", 1)),
    "waypoints_nul": ("w.waypoints", lambda: _WPL.replace(_WPL_LAT, b"-35.\x0036303667", 1)),
    "waypoints_no_header": ("w.waypoints", lambda: _WPL.split(b"\n", 1)[1]),
}


@pytest.mark.parametrize("name", HOSTILE_PLANS)
def test_a_hostile_ground_station_file_is_refused_with_locations(name: str, tmp_path: Path) -> None:
    """QGroundControl and Mission Planner files with NaN, infinities, 5000-digit numbers, deep nesting, bad bytes: located errors only."""
    filename, make = HOSTILE_PLANS[name]
    path = tmp_path / filename
    path.write_bytes(data := make())
    with pytest.raises(MissionError) as info:
        import_file(path, vehicle="rover")
    assert_located(info.value, data.decode("utf-8", "replace"), str(path), ANY_LINES)


@pytest.mark.parametrize("seed", PLAN_SEEDS, ids=lambda p: p.name)
def test_a_ground_station_file_with_crlf_and_a_bom_imports_as_it_is(seed: Path, tmp_path: Path) -> None:
    """Windows line endings and a UTF-8 BOM change nothing."""
    path = tmp_path / seed.name
    path.write_bytes(b"\xef\xbb\xbf" + seed.read_bytes().replace(b"\r\n", b"\n").replace(b"\n", b"\r\n"))
    assert import_file(path, vehicle="rover").mission == import_file(seed, vehicle="rover").mission
