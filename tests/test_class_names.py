"""One name for one thing: no two classes of the package (its trees included) share a name (issue 41).

Two things named alike were ``Outcome`` (a run's end, a command's ask), ``Sample`` (the action, the record it
makes), ``MissionState`` (ours, the simulator's AP_Mission), ``Limits``, ``Source``, ``Step`` and ``Transition``;
each renamed one keeps its old name for one release (``executive.RENAMED``).
"""

from __future__ import annotations

import re
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLASS = re.compile(r"^[ \t]*class (\w+)[(:[]", re.MULTILINE)  # a class statement (and one in a docstring's example; ast is 4x slower)


def classes() -> dict[str, list[str]]:
    """Each class name of ``executive/`` and ``trees/`` -> where it is defined (FILE:LINE)."""
    found: dict[str, list[str]] = defaultdict(list)
    for path in sorted([*(ROOT / "executive").rglob("*.py"), *(ROOT / "trees").rglob("*.py")]):
        text = path.read_text(encoding="utf-8")
        for match in CLASS.finditer(text):
            found[match[1]].append(f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, match.start()) + 1}")
    return found


def test_no_two_classes_share_a_name() -> None:
    assert {name: where for name, where in classes().items() if len(where) > 1} == {}
