"""Fixtures for the mission file tests."""

from __future__ import annotations

import pytest

from executive import trees


@pytest.fixture(autouse=True)
def waypoints_tree_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Missions may name exactly one tree here, whatever trees/ holds today, so messages stay stable."""
    monkeypatch.setattr(trees, "available", lambda: ["waypoints"])
