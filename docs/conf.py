"""Sphinx configuration of the manual (``sphinx-build -W docs docs/_build``; .ci/run builds it with warnings as errors).

Sphinx, as the anchors py_trees and python-can use: autodoc reads our docstrings for the API pages, and a small
extension of ours (``_ext/executive_reference.py``) writes the reference from the code at each build. MyST-Parser
lets the pages be Markdown, as README is: a README section moved here stays the same text.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE / "_ext"), str(HERE.parent)]  # our extension; the package from a checkout (installed or not)

from executive import __version__  # noqa: E402

project = "executive"
author = "the executive's authors"
copyright = "the executive's authors"
release = version = __version__

extensions = ["myst_parser", "sphinx.ext.autodoc", "executive_reference"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]
myst_heading_anchors = 4  # README's `#section` links keep working as `page.md#section`
myst_enable_extensions = ["colon_fence"]
# README's sections keep their own heading levels here (### under a page's #), so that their later edits apply to the pages as they are
suppress_warnings = ["myst.header"]
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
html_theme = "alabaster"
html_title = f"executive {__version__}"
html_static_path: list[str] = []
