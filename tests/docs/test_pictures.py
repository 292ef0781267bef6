"""The manual's pictures are the program's own output, made by tests, so that none shows what the program no longer does.

- ``docs/tree-rover_square.svg`` (the trees page): ``executive show rover_square -o tree.svg``, checked here node by node
  against what ``show`` draws now; ``EXECUTIVE_DOCS_PICTURES=1`` writes it again.
- ``docs/live-view.png`` (README, the live view page): the screenshot tests/web/test_live_view_browser.py takes in headless
  Chromium during a real run; ``EXECUTIVE_LIVE_VIEW_PNG=docs/live-view.png`` keeps it.
"""

from __future__ import annotations

import html
import os
import re
import shutil
from pathlib import Path

import pytest

from executive.cli import main

DOCS = Path(__file__).parents[2] / "docs"
TREE = DOCS / "tree-rover_square.svg"


def labels(svg: str) -> list[str]:
    """The text of the drawing, node by node in Graphviz's order (its layout's numbers vary between Graphviz versions)."""
    return [html.unescape(text) for text in re.findall(r"<text[^>]*>([^<]*)</text>", svg)]


def test_the_tree_picture_is_what_executive_show_draws_now(tmp_path):
    if not shutil.which("dot") and not os.environ.get("CI"):
        pytest.skip("no Graphviz dot (apt-get install graphviz; .ci/run does)")
    drawn = tmp_path / "tree.svg"
    assert main(["show", "rover_square", "-o", str(drawn)]) == 0
    if os.environ.get("EXECUTIVE_DOCS_PICTURES"):
        shutil.copy(drawn, TREE)
    now = labels(drawn.read_text(encoding="utf-8"))
    assert {"Mission", "Pre-flight", "For each leg"} <= set(now)
    assert labels(TREE.read_text(encoding="utf-8")) == now, "docs/tree-rover_square.svg is out of date: EXECUTIVE_DOCS_PICTURES=1 makes it again"


def test_the_pages_show_the_pictures_the_tests_make():
    assert "](tree-rover_square.svg)" in (DOCS / "trees.md").read_text(encoding="utf-8")
    assert "](live-view.png)" in (DOCS / "live-view.md").read_text(encoding="utf-8")
    assert "](docs/live-view.png)" in (DOCS.parent / "README.md").read_text(encoding="utf-8")
