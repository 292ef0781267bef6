"""``executive show``: the tree a mission would run, as text, dot, or a picture via Graphviz."""

from __future__ import annotations

from pathlib import Path

import pydot
import pytest

from executive.cli import main
from executive.mission.loader import load_mission
from executive.tree import select as mission_tree

MISSIONS = Path(__file__).parents[2] / "missions"
SQUARE = str(MISSIONS / "rover_square.yaml")


@pytest.mark.parametrize("fmt", ["ascii", "unicode"])
def test_text_formats_show_every_guard_and_action(capsys, fmt):
    assert main(["show", SQUARE, "--format", fmt]) == 0
    out = capsys.readouterr().out
    for name in ("Pre-flight", "Link alive?", "EKF ok?", "Armed?", "RC not taking over?", "Set GUIDED", "Go to waypoint", "Hold at the end"):
        assert name in out


def test_dot_is_a_graph_with_every_node(capsys, tmp_path):
    out_file = tmp_path / "tree.dot"
    assert main(["show", SQUARE, "--format", "dot", "-o", str(out_file)]) == 0
    dot = out_file.read_text()
    assert dot.lstrip().startswith("digraph")
    assert '"Go to waypoint"' in dot and '"Wait for guards"' in dot
    assert "->" in dot


def test_pictures_without_graphviz_say_how_to_install_it(capsys, tmp_path, monkeypatch):
    """Exit 2, README's code for a usage this machine cannot serve (issue 28: it was 1, which says a mission aborted)."""
    monkeypatch.setenv("PATH", str(tmp_path))  # no 'dot' here
    assert main(["show", SQUARE, "--format", "svg", "-o", str(tmp_path / "t.svg")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("executive: show: --format svg: Graphviz's 'dot' program is needed for svg/png and was not found on PATH")
    assert "apt-get install graphviz" in err
    assert not (tmp_path / "t.svg").exists()
    assert main(["show", SQUARE, "-o", str(tmp_path / "x.svg")]) == 2  # the format from the file's suffix: said so
    assert capsys.readouterr().err.startswith(f"executive: show: -o {tmp_path / 'x.svg'} (svg, from its suffix): Graphviz's 'dot' program")


def test_pictures_with_graphviz_are_rendered(tmp_path, monkeypatch):
    fake_dot = tmp_path / "dot"  # stands in for Graphviz: proves we call it and write what it returns
    fake_dot.write_text("#!/bin/sh\ncat > /dev/null\necho '<svg>tree</svg>'\n")
    fake_dot.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}:/usr/bin:/bin")
    assert main(["show", SQUARE, "--format", "svg", "-o", str(tmp_path / "t.svg")]) == 0
    assert (tmp_path / "t.svg").read_text().strip() == "<svg>tree</svg>"


@pytest.fixture
def fake_graphviz(tmp_path, monkeypatch):
    """A 'dot' on PATH that answers with the format it was asked for, so a test sees which one was."""
    fake_dot = tmp_path / "dot"
    fake_dot.write_text('#!/bin/sh\ncat > /dev/null\necho "picture $1"\n')
    fake_dot.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}:/usr/bin:/bin")


@pytest.mark.parametrize(("name", "expected"), [("tree.svg", "picture -Tsvg"), ("tree.PNG", "picture -Tpng")])
def test_a_picture_format_is_taken_from_the_output_suffix(tmp_path, fake_graphviz, name, expected):
    assert main(["show", SQUARE, "-o", str(tmp_path / name)]) == 0
    assert (tmp_path / name).read_text().strip() == expected


@pytest.mark.parametrize(("name", "start"), [("tree.dot", "digraph"), ("tree.gv", "digraph"), ("tree.txt", "◇ Mission")])
def test_a_text_format_is_taken_from_the_output_suffix(tmp_path, name, start):
    assert main(["show", SQUARE, "-o", str(tmp_path / name)]) == 0
    assert (tmp_path / name).read_text(encoding="utf-8").startswith(start)


@pytest.mark.parametrize("name", ["tree.jpeg", "tree"])
def test_an_output_suffix_naming_no_format_is_refused(capsys, tmp_path, name):
    assert main(["show", SQUARE, "-o", str(tmp_path / name)]) == 2
    assert "cannot tell the format" in capsys.readouterr().err
    assert not (tmp_path / name).exists()


def test_an_explicit_format_wins_over_the_suffix(tmp_path):
    assert main(["show", SQUARE, "--format", "dot", "-o", str(tmp_path / "tree.txt")]) == 0
    assert (tmp_path / "tree.txt").read_text().startswith("digraph")


def test_unicode_draws_lines_and_kinds_where_ascii_does_not(capsys):
    main(["show", SQUARE, "--format", "unicode"])
    unicode = capsys.readouterr().out
    main(["show", SQUARE, "--format", "ascii"])
    ascii_text = capsys.readouterr().out
    assert unicode != ascii_text
    assert "├─ → Pre-flight" in unicode and "└─ • EKF ok?" in unicode and "? Guarded route or hold" in unicode
    assert ascii_text.isascii()


# names with ':' ("Switch A: edit the route"), repeated names ("EKF ok?" twice in the square)
@pytest.mark.parametrize("path", [MISSIONS / "ugv_rc_route.yaml", MISSIONS / "rover_square.yaml"])
def test_dot_keeps_every_node_apart_and_is_named_after_the_mission(capsys, path):
    assert main(["show", str(path), "--format", "dot"]) == 0
    (graph,) = pydot.graph_from_dot_data(capsys.readouterr().out)
    tree = list(mission_tree.build(load_mission(path)).iterate())
    nodes = [n for n in graph.get_nodes() if n.get_name() not in ("graph", "node", "edge")]
    assert len(nodes) == len(tree) and len(graph.get_edges()) == len(tree) - 1
    assert sorted(n.get("label").strip('"') for n in nodes) == sorted(n.name for n in tree)
    assert any(":" in n.name for n in tree) or len({n.name for n in tree}) < len(tree)
    assert graph.get_name().strip('"') == load_mission(path).name


def test_picture_needs_an_output_file(capsys):
    assert main(["show", SQUARE, "--format", "png"]) == 2
    assert "needs -o FILE" in capsys.readouterr().err


def test_a_broken_mission_is_reported_not_drawn(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nname: x\nvehicle: tank\nwaypoints: []\n")
    assert main(["show", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:3:10: vehicle:" in err
    assert capsys.readouterr().out == ""
