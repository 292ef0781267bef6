"""Fixtures for the mission file tests: a known set of trees and the minimal valid mission."""

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
def minimal_yaml() -> str:
    """The smallest valid mission: one waypoint, rover, tree waypoints."""
    return (DATA / "minimal_mission.yaml").read_text(encoding="utf-8")
