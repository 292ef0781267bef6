"""``executive show``: the tree a mission would run, as text, dot, or a picture via Graphviz."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.cli import main

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
    monkeypatch.setenv("PATH", str(tmp_path))  # no 'dot' here
    assert main(["show", SQUARE, "--format", "svg", "-o", str(tmp_path / "t.svg")]) == 1
    err = capsys.readouterr().err
    assert "Graphviz" in err and "apt-get install graphviz" in err
    assert not (tmp_path / "t.svg").exists()


def test_pictures_with_graphviz_are_rendered(tmp_path, monkeypatch):
    fake_dot = tmp_path / "dot"  # stands in for Graphviz: proves we call it and write what it returns
    fake_dot.write_text("#!/bin/sh\ncat > /dev/null\necho '<svg>tree</svg>'\n")
    fake_dot.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}:/usr/bin:/bin")
    assert main(["show", SQUARE, "--format", "svg", "-o", str(tmp_path / "t.svg")]) == 0
    assert (tmp_path / "t.svg").read_text().strip() == "<svg>tree</svg>"


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
