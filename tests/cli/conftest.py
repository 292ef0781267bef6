"""Fixtures for the command-line tests."""

from __future__ import annotations

from pathlib import Path

import pytest

import trees

DATA = Path(__file__).parent.parent / "data"


@pytest.fixture(autouse=True)
def waypoints_tree_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Missions may name exactly one tree, whatever trees/ holds today."""
    monkeypatch.setattr(trees, "available", lambda: ["waypoints"])


@pytest.fixture
def minimal_mission() -> Path:
    """A valid mission file: one waypoint, rover, tree waypoints."""
    return DATA / "minimal_mission.yaml"
