"""What ``pip install .`` puts in site-packages: the package ``executive`` whole, its trees as ``executive.trees``, no top-level ``trees``."""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).parents[1]
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def test_the_trees_folder_installs_as_executive_trees_and_nothing_installs_at_the_top_but_executive() -> None:
    assert SETUPTOOLS["package-dir"] == {"executive.trees": "trees", "executive.examples": "missions"}
    assert all(name == "executive" or name.startswith("executive.") for name in SETUPTOOLS["packages"])


def test_every_package_of_the_repository_is_listed() -> None:
    """A mapped package is not found by packages.find, so the list is written out: a package left out of it would not be installed."""
    found = {".".join(init.parent.relative_to(ROOT).parts) for init in (ROOT / "executive").rglob("__init__.py")}
    assert sorted(SETUPTOOLS["packages"]) == sorted(found | {"executive.trees", "executive.examples"})  # examples: missions/, data
    assert (ROOT / "trees" / "__init__.py").is_file()


def test_no_code_imports_a_top_level_trees_module() -> None:
    """``import trees`` works only from a checkout, never once installed: the trees are ``executive.trees``."""
    wrong = []
    bare = re.compile(r"(?<![.\w])trees\b")  # in every import of `trees` or `trees.x`: only a file with it is parsed (466 -> ~50)
    for folder in ("executive", "trees", "tests", "examples", "benchmarks"):
        for path in (ROOT / folder).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            if not bare.search(text):
                continue
            for node in ast.walk(ast.parse(text)):
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and not node.level:
                    names = [node.module or ""]
                else:
                    continue
                wrong += [f"{path.relative_to(ROOT)}:{node.lineno}: {name}" for name in names if name == "trees" or name.startswith("trees.")]
    assert wrong == []


def test_from_a_checkout_executive_trees_is_the_top_level_trees_folder(tmp_path: Path) -> None:
    """Not installed (``python -m executive`` in a checkout, the suite with pytest's pythonpath), the trees are found all the same."""
    import os
    import subprocess
    import sys

    code = "import executive.trees.parts, executive.trees; print(executive.__file__); print(executive.trees.__file__)"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    package, trees = (Path(line) for line in done.stdout.split())
    assert (package, trees) == (ROOT / "executive" / "__init__.py", ROOT / "trees" / "__init__.py")
