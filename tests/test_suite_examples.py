"""The suite's property tests draw the same examples in every run, whatever the tests before them imported."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st


def _examples() -> list[int]:
    drawn: list[int] = []

    @settings(max_examples=200, derandomize=True, database=None)
    @given(st.integers())
    def draw(value: int) -> None:
        drawn.append(value)

    draw()
    return drawn


def test_a_module_imported_between_two_runs_of_a_property_test_changes_none_of_its_examples(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    before = _examples()
    # a module of the project's own (not a test file, not site-packages) that a test before this one might have imported: hypothesis
    # 6.170 draws some examples from the literals of the local modules loaded (providers._get_local_constants)
    (tmp_path / "bait_constants.py").write_text("BAIT = [" + ", ".join(str(123_456_700 + i) for i in range(64)) + "]\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "bait_constants", raising=False)
    importlib.import_module("bait_constants")
    after = _examples()
    assert after == before
    assert not {v for v in after if 123_456_700 <= v < 123_456_764}
