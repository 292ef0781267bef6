"""The shipped JSON schema: current with the model, and it accepts and refuses what the loader does."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from pydantic import ValidationError

from executive.cli import main
from executive.mission.model import Mission
from executive.mission.rules import cross_field_errors
from executive.tree.schema import SHIPPED, mission_json_schema, mission_json_schema_text

ROOT = Path(__file__).parents[2]
ANNOTATIONS = {"$defs", "$schema", "default", "description", "title"}
TYPES: dict[str, type | tuple[type, ...]] = {
    "object": dict,
    "array": list,
    "string": str,
    "integer": int,
    "number": (int, float),
    "boolean": bool,
    "null": type(None),
}
CHECKS: dict[str, Callable[[Any, Any], bool]] = {
    "minimum": lambda v, bound: v >= bound,
    "maximum": lambda v, bound: v <= bound,
    "exclusiveMinimum": lambda v, bound: v > bound,
    "exclusiveMaximum": lambda v, bound: v < bound,
    "minLength": lambda v, bound: len(v) >= bound,
    "maxLength": lambda v, bound: len(v) <= bound,
    "minItems": lambda v, bound: len(v) >= bound,
    "maxItems": lambda v, bound: len(v) <= bound,
    "pattern": lambda v, pattern: re.search(pattern, v) is not None,
    "const": lambda v, const: v == const,
    "enum": lambda v, values: v in values,
}
STRUCTURE = {"$ref", "anyOf", "type", "properties", "required", "additionalProperties", "items"}


def violations(value: Any, schema: dict[str, Any], root: dict[str, Any], where: str = "$") -> list[str]:
    """What ``value`` breaks of ``schema``: a tiny validator for the keywords the mission schema uses (jsonschema is not a dependency)."""
    if "$ref" in schema:
        schema = {**root["$defs"][schema["$ref"].removeprefix("#/$defs/")], **{k: v for k, v in schema.items() if k != "$ref"}}
    if "anyOf" in schema and all(violations(value, option, root, where) for option in schema["anyOf"]):
        return [f"{where}: anyOf"]
    kind = schema.get("type")
    if kind and (not isinstance(value, TYPES[kind]) or (isinstance(value, bool) and kind in ("integer", "number"))):
        return [f"{where}: type {kind}"]
    found = [f"{where}: {keyword}" for keyword, check in CHECKS.items() if keyword in schema and not check(value, schema[keyword])]
    if kind == "object":
        found += [f"{where}.{name}: required" for name in schema.get("required", []) if name not in value]
        for name, item in value.items():
            if name in schema.get("properties", {}):
                found += violations(item, schema["properties"][name], root, f"{where}.{name}")
            elif schema.get("additionalProperties") is False:
                found.append(f"{where}.{name}: additionalProperties")
    if kind == "array" and "items" in schema:
        for i, item in enumerate(value):
            found += violations(item, schema["items"], root, f"{where}[{i}]")
    return found


def keywords(schema: Any) -> set[str]:
    """Every keyword used anywhere in ``schema`` (property and definition names excluded)."""
    if isinstance(schema, list):
        return set().union(*map(keywords, schema))
    if not isinstance(schema, dict):
        return set()
    nested = [v for k, v in schema.items() if k not in ("properties", "$defs")]
    nested += [*schema.get("properties", {}).values(), *schema.get("$defs", {}).values()]
    return set(schema) | set().union(*map(keywords, nested))


@pytest.fixture
def good(minimal_yaml: str) -> dict[str, Any]:
    return yaml.safe_load(minimal_yaml)


@pytest.fixture(scope="module")
def schema() -> dict[str, Any]:
    """The mission schema, made once for the module's validations (the validator only reads it)."""
    return mission_json_schema()


@pytest.mark.parametrize("path", [SHIPPED, ROOT / "missions" / "mission.schema.json"], ids=["package", "missions"])
def test_shipped_schema_is_current(path: Path) -> None:
    assert path.read_text(encoding="utf-8") == mission_json_schema_text(), f"the model changed: run 'executive schema -o {path}'"


def test_schema_is_draft_2020_12_with_a_title() -> None:
    schema = mission_json_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["title"] == "executive mission file (version 1)"
    assert set(schema["required"]) == {"version", "name", "vehicle", "waypoints"}
    assert schema["additionalProperties"] is False


def test_schema_text_is_sorted_indented_json_with_a_final_newline() -> None:
    text = mission_json_schema_text()
    assert text.endswith("}\n")
    assert text == json.dumps(json.loads(text), indent=2, sort_keys=True) + "\n"


def test_the_tiny_validator_knows_every_keyword_of_the_schema() -> None:
    assert keywords(mission_json_schema()) <= ANNOTATIONS | STRUCTURE | set(CHECKS)


def test_schema_accepts_a_good_mission(good: dict[str, Any], schema: dict[str, Any]) -> None:
    Mission.model_validate(good)
    assert violations(good, schema, schema) == []


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (lambda m: m["waypoints"][0].update(lat=95.0), "$.waypoints[0].lat: maximum"),
        (lambda m: m["waypoints"][0].update(lat=True), "$.waypoints[0].lat: type number"),
        (lambda m: m["waypoints"][0].update(speed_m_s=0.0), "$.waypoints[0].speed_m_s: anyOf"),
        (lambda m: m["waypoints"][0].update(latt=1.0), "$.waypoints[0].latt: additionalProperties"),
        (lambda m: m.update(waypoints=[]), "$: anyOf"),  # an empty route only for ugv_rc_route
        (lambda m: m.pop("waypoints"), "$.waypoints: required"),
        (lambda m: m.update(version=2), "$.version: const"),
        (lambda m: m.update(vehicle="car"), "$.vehicle: enum"),
        (lambda m: m.update(tree="Bad-Tree"), "$.tree: anyOf"),  # neither a name nor a composed tree
        (lambda m: m.update(home={"lat": 1.0, "lon": 2.0, "heading_deg": 360.0}), "$.home: anyOf"),
        (lambda m: m.update(limits={"link_timeout_s": 0.0}), "$.limits.link_timeout_s: exclusiveMinimum"),
    ],
)
def test_schema_refuses_what_the_model_refuses(
    good: dict[str, Any], schema: dict[str, Any], change: Callable[[dict[str, Any]], Any], expected: str
) -> None:
    change(good)
    try:
        refusals = cross_field_errors(Mission.model_validate(good))
    except ValidationError as exc:
        refusals = exc.errors()
    assert refusals
    assert violations(good, schema, schema) == [expected]


def test_schema_command_prints_the_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    assert capsys.readouterr().out == mission_json_schema_text()


def test_schema_command_writes_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "-o", str(tmp_path / "out.json")]) == 0
    assert (tmp_path / "out.json").read_text(encoding="utf-8") == mission_json_schema_text()
    assert capsys.readouterr().out == ""


def test_schema_command_reports_an_unwritable_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "-o", str(tmp_path / "no" / "such" / "dir.json")]) == 2
    assert capsys.readouterr().err == f"executive: schema: cannot write {tmp_path / 'no' / 'such' / 'dir.json'}: No such file or directory\n"
