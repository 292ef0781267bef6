"""The manual's reference is made from the code at each build (docs/_ext/executive_reference.py): what the code has, it shows."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import pytest
from pydantic import Field

from executive.cli import build_parser
from executive.mission.model import Mission
from executive.tree import schema as mission_schema
from executive.world import blackboard

DOCS = Path(__file__).parents[2] / "docs"
sys.path.insert(0, str(DOCS / "_ext"))
import executive_reference as reference  # noqa: E402


def test_a_field_added_to_the_model_appears_in_the_mission_reference_with_its_type_unit_default_and_description(monkeypatch):
    class Extended(Mission):
        sonar_gain_db: float = Field(3.5, ge=0, le=40, description="the echo sounder's gain")
        max_wave_height_m: float = Field(0.8, description="no leg starts above these waves")

    monkeypatch.setattr(mission_schema, "Mission", Extended)  # what `executive schema` is made from
    page = reference.mission_reference()
    rows = {row.split(" | ")[0].strip("| `"): row for row in page.splitlines() if row.startswith("| `")}
    assert "the echo sounder's gain (\\>= 0, \\<= 40)" in rows["sonar_gain_db"] and "`3.5`" in rows["sonar_gain_db"]
    assert "| number | m | `0.8` | no leg starts above these waves |" in rows["max_wave_height_m"]


def test_every_field_of_every_model_of_the_schema_is_in_the_mission_reference():
    schema = mission_schema.mission_json_schema()
    page = reference.mission_reference(schema)
    models = {"": schema} | {n: m for n, m in schema["$defs"].items() if not n.startswith("TreeNode") and "properties" in m}
    for name, model in models.items():
        assert not name or f"## {name}\n" in page
        for field in model["properties"]:
            assert f"| `{field}` |" in page, (name, field)


def _parsers(parser: argparse.ArgumentParser, words: list[str]):
    yield words, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, [*words, name])


def test_every_command_and_option_of_the_command_line_is_in_its_reference():
    page = reference.cli_reference()
    for words, parser in _parsers(build_parser(), ["executive"]):
        assert re.search(rf"^#+ `{' '.join(words)}`$", page, re.M), words
        for action in parser._actions:
            for option in [] if isinstance(action, argparse._HelpAction) else action.option_strings:
                assert option in page, (words, option)


def test_every_node_of_the_catalogue_and_its_parameters_are_in_the_node_reference():
    nodes = reference.catalogue()
    page = reference.nodes_reference(nodes)
    assert len(nodes) > 50
    for node in nodes:
        section = page.split(f"### {node['name']}\n")[1].split("\n### ")[0]
        assert all(f"| `{p['name']}` |" in section for p in node["params"]), node["name"]


def test_every_documented_blackboard_key_is_in_the_blackboard_reference():
    page = reference.blackboard_reference()
    assert all(f"| `{key}` |" in page for key in blackboard.KEYS)
    assert "## `/vehicle`\n\nthe vehicle's state as the autopilot reports it" in page


@pytest.mark.parametrize("page", ["cli", "mission", "nodes", "blackboard"])
def test_each_reference_page_holds_its_marker_and_the_build_replaces_it(page):
    text = (DOCS / "reference" / f"{page}.md").read_text(encoding="utf-8")
    assert f"<!-- generated: {page} -->" in text
    assert reference.MARKER.search(text) and not reference.MARKER.search(reference.expand(text))


def test_the_running_pages_list_of_commands_is_generated_each_linked_to_its_reference():
    """Issue 36: the command tables were written by hand in docs/running.md beside the generated reference; now made from the parsers."""
    commands = {name for action in build_parser()._actions if isinstance(action, argparse._SubParsersAction) for name in action.choices}
    table = reference.commands_table()
    anchors = dict(re.findall(r"\[`executive ([\w-]+)`\]\(reference/cli\.md#([\w-]+)\)", table))
    assert set(anchors) == commands
    headings = {re.sub(r"[^\w-]", "", h.replace(" ", "-")) for h in re.findall(r"^#+ `(executive[^`]*)`$", reference.cli_reference(), re.M)}
    assert set(anchors.values()) <= headings, "a command links to no heading of the command line reference"
    assert "\n<!-- generated: commands -->\n" in (DOCS / "running.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("page", sorted(p.name for p in DOCS.glob("*.md")))
def test_no_page_lists_commands_or_options_by_hand(page):
    """A table of commands or options outside the generated reference would be a second copy to keep up to date."""
    text = (DOCS / page).read_text(encoding="utf-8")
    assert not re.search(r"^\| (command|option) \| what it does \|", text, re.M)


def test_the_guards_figures_on_the_failsafes_page_are_the_catalogues():
    """Issue 36: the failsafes page wrote each guard's hold/resume figures and its unknown-or-stale rule by hand; now generated."""
    nodes = reference.catalogue()
    page = reference.guards_table(nodes)
    rows = {re.search(r"`(\w+)`", row)[1]: row for row in page.splitlines()[2:]}
    for node in (n for n in nodes if n["kind"] == "guard"):
        defaults = {p["name"]: p.get("default") for p in node["params"]}
        assert f"| {defaults['hold_after_s']:g} s | {defaults['resume_after_s']:g} s |" in rows[node["name"]]
        assert node["unknown_or_stale"] and node["unknown_or_stale"].split(":")[0].replace("_", "\\_") in rows[node["name"]]
    text = (DOCS / "failsafes.md").read_text(encoding="utf-8")
    assert "\n<!-- generated: guards -->\n" in text and not re.search(r"^\| guard\b", text, re.M)
