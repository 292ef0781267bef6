"""The JSON schema of the mission file, for editors and other tools: the model's, and for a composed ``tree:`` the node catalogue's.

The shipped copies (``executive/mission/mission.schema.json`` and ``missions/mission.schema.json``)
are written by ``executive schema -o FILE``; a test fails when they fall behind the model.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from executive.mission.declaration import BUILT_IN_KINDS, plugin_kinds, trees_with
from executive.mission.model import Mission, mission_model
from executive.tree.composition import tree_json_schema

DIALECT = "https://json-schema.org/draft/2020-12/schema"
SHIPPED = Path(__file__).parent.parent / "mission" / "mission.schema.json"


def mission_json_schema() -> dict[str, Any]:
    """The JSON schema (draft 2020-12) of a mission file, generated from :class:`Mission` and, for a composed ``tree:``, the node catalogue.

    With plugins installed: their trees' own options sections, and their vehicle kinds in ``vehicle``'s enum.
    """
    schema = mission_model(base=Mission).model_json_schema()
    if kinds := plugin_kinds():
        schema["properties"]["vehicle"]["enum"] = [*BUILT_IN_KINDS, *kinds]
    composed, defs = tree_json_schema()
    tree = schema["properties"]["tree"]
    tree["anyOf"] = [option if option.get("type") != "object" else {**composed, "description": option["description"]} for option in tree["anyOf"]]
    schema["$defs"] |= defs
    # for editors: an empty route only for a tree that declares one (its operator records it; cross_field_errors says so too)
    empty = [{"type": "object", "required": ["tree"], "properties": {"tree": {"const": name}}} for name in trees_with(lambda d: d.empty_route)]
    schema["anyOf"] = [*empty, {"type": "object", "properties": {"waypoints": {"minItems": 1}}}]
    return {**schema, "$schema": DIALECT, "title": "executive mission file (version 1)"}


def mission_json_schema_text() -> str:
    """:func:`mission_json_schema` as the shipped files hold it: indented, sorted keys, a final newline."""
    return json.dumps(mission_json_schema(), indent=2, sort_keys=True) + "\n"
