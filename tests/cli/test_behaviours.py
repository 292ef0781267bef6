"""``executive behaviours [--json] [--kind K] [NAME...]``: the node catalogue on the command line."""

from __future__ import annotations

import json

from executive.cli import main
from executive.tree.catalogue import catalogue


def test_json_lists_the_whole_catalogue(capsys):
    assert main(["behaviours", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert [n["name"] for n in listed] == catalogue().names()
    go_to = next(n for n in listed if n["name"] == "go_to")
    radius = next(p for p in go_to["params"] if p["name"] == "acceptance_radius_m")
    assert radius == {
        "name": "acceptance_radius_m", "type": "float", "unit": "m", "required": False,
        "doc": "the target counts as reached within this distance", "from_mission": "limits.acceptance_radius_m",
    }  # fmt: skip


def test_text_names_each_parameter_with_type_unit_and_default(capsys):
    assert main(["behaviours", "set_mode", "timeout"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("set_mode (action): Put the autopilot in a flight mode (by name); confirmed by the heartbeat.\n")
    assert "    mode: str, required: flight mode name" in out
    assert "    confirm_timeout_s: float [s], default: 5.0: " in out
    assert "timeout (decorator): " in out and "    timeout_s: float [s], required: " in out


def test_kind_filters(capsys):
    assert main(["behaviours", "--kind", "composite", "--json"]) == 0
    assert [n["name"] for n in json.loads(capsys.readouterr().out)] == ["parallel", "selector", "sequence"]


def test_an_unknown_node_is_bad_input(capsys):
    assert main(["behaviours", "go_to", "fly_away"]) == 2
    assert "no node 'fly_away'" in capsys.readouterr().err


def test_a_misspelt_node_gets_the_suggestion_validate_gives(capsys):
    """Issue 28: `validate` says "did you mean go_to?" of `goto`; `behaviours goto` did not."""
    assert main(["behaviours", "goto", "fly_away"]) == 2
    assert (
        capsys.readouterr().err
        == "executive: behaviours: no node 'goto' (did you mean go_to?), no node 'fly_away'; executive behaviours lists them\n"
    )


def test_a_plugin_that_cannot_be_loaded_is_named_with_exit_2_and_the_rest_still_listed(capsys, monkeypatch):
    from executive.cli import behaviours
    from executive.registry import PluginError

    def broken(found: list[PluginError]) -> list[type]:
        found.append(PluginError("'sea' (executive.behaviours = mypkg.sea:Sea, from mypkg 1.0)", ModuleNotFoundError("No module named 'mypkg.sea'")))
        return []

    monkeypatch.setattr(behaviours, "load_behaviours", broken)
    assert main(["behaviours"]) == 2
    out, err = capsys.readouterr()
    assert err == (
        "executive: behaviours: plugin 'sea' (executive.behaviours = mypkg.sea:Sea, from mypkg 1.0): "
        "ModuleNotFoundError: No module named 'mypkg.sea'\n"
    )
    assert "go_to (action)" in out  # the others, listed all the same
