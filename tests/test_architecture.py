"""The import contract: the layers README's "Architecture" draws, kept true.

Every module of ``executive`` (``executive.trees``, the top-level ``trees/`` folder, included) is read with ``ast`` (imports inside
functions count). The checks: no import cycle between modules; an import runs down the layers, or is
one of the few listed upward ones; nothing in ``behaviours`` imports ``io``; no module over 600 lines.
"""

from __future__ import annotations

import ast
import copy
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "executive"

#: Top first: each layer is folders (packages) of ``executive/``, and the few modules at its top. A module belongs to the
#: layer of its top-level package; ``executive`` itself (its ``__init__``) is the bottom.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("entry points", ("cli", "__main__", "sim", "testing")),
    ("observers", ("observers",)),
    ("runtime", ("runtime", "autopilot_link")),
    ("operator", ("operator",)),
    ("admission", ("admission",)),
    ("tree", ("tree", "trees")),
    ("behaviours", ("behaviours",)),
    ("autopilot", ("autopilot", "instruments", "sensing")),
    ("io", ("io",)),
    ("mission", ("mission",)),
    ("world", ("world", "registry", "")),
)  # fmt: skip

#: The imports allowed to run up a layer, and why (at most 3).
UPWARD: dict[tuple[str, str], str] = {}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[0] == "trees":  # the top-level trees/ folder is the package's executive.trees (pyproject's package-dir)
        parts = ["executive", *parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


SOURCES = [*sorted(PACKAGE.rglob("*.py")), *sorted((PACKAGE.parent / "trees").rglob("*.py"))]
MODULES = {module_name(p): p for p in SOURCES if "__pycache__" not in p.parts}


@functools.cache
def import_statements(path: Path) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement of ``path``, at its top or inside functions: parsed once in a worker for all the checks below (parsing
    the package is 0.8 s of CPU). Only the statements are kept: the whole trees, kept, slowed every later garbage collection."""
    return [node for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))) if isinstance(node, ast.Import | ast.ImportFrom)]


def imports_of(name: str, modules: dict[str, Path] = MODULES) -> set[str]:
    """The modules of ours (of ``modules``) ``name`` imports (``from a import b`` names module ``a.b`` when there is one)."""
    path = modules[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in import_statements(path):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
            targets = [f"{base}.{alias.name}" for alias in node.names] + [base]
        for target in targets:
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target != name:
                found.add(target)
    return found


@functools.cache
def graph_of_ours() -> dict[str, set[str]]:
    """Each module of ours and the modules of ours it imports: read when a test first asks (not at collection, in every worker)."""
    return {name: imports_of(name) for name in MODULES}


#: The tests that read every module: on one xdist worker (``--dist loadgroup``), which parses the package once for all of them.
reads_the_package = pytest.mark.xdist_group("import_graph")


def top_level(name: str) -> str:
    """The folder (or module) of ``executive/`` that ``name`` is in: ``executive.world.geo`` -> ``world``; ``executive`` -> ``""``."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def layer(name: str) -> int:
    return next(i for i, (_, tops) in enumerate(LAYERS) if top_level(name) in tops)


def cycles(graph: dict[str, set[str]] | None = None) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), of ``graph`` (ours when None)."""
    graph = graph_of_ours() if graph is None else graph
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return groups


@reads_the_package
def test_the_tests_that_read_the_package_go_to_one_worker(request: pytest.FixtureRequest) -> None:
    """xdist's loadgroup scheduler groups by the ``@GROUP`` end of a node id (tests/conftest.py writes it where pytest 9.2 reads it)."""
    if getattr(request.config.option, "loadgroup", False):  # an xdist worker under --dist loadgroup (README's `pytest -n auto`)
        assert request.node.nodeid.endswith("@import_graph")
    else:  # one process: the conftest's marking, on a copy of this test's item
        conftest = next(p for p in request.config.pluginmanager.get_plugins() if str(getattr(p, "__file__", "")).endswith("tests/conftest.py"))
        item = copy.copy(request.node)
        conftest._groups_in_node_ids([item])
        assert item.nodeid == f"{request.node.nodeid}@import_graph"


@reads_the_package
def test_no_import_cycle() -> None:
    assert cycles() == []


#: The repository's other Python, read the same way: the benchmarks, and any module in tools/ (its scripts import none of ours).
OTHERS = {
    module_name(p): p for folder in ("benchmarks", "tools") for p in sorted((PACKAGE.parent / folder).rglob("*.py")) if "__pycache__" not in p.parts
}


def test_no_import_cycle_in_the_benchmarks_or_tools() -> None:
    graph = {name: imports_of(name, OTHERS) for name in OTHERS}
    assert "benchmarks.recorded" in graph["benchmarks.efficiency"] and "benchmarks.common" in graph["benchmarks.tick"]  # read as the package is
    assert cycles(graph) == []


@reads_the_package
def test_imports_run_down_the_layers() -> None:
    upward = {(a, b) for a, targets in graph_of_ours().items() for b in targets if layer(b) < layer(a)}
    assert upward == set(UPWARD), "imports running up a layer (README: Architecture)"
    assert len(UPWARD) <= 3


@reads_the_package
def test_behaviours_import_no_io() -> None:
    behaviours = {a: targets for a, targets in graph_of_ours().items() if a.startswith("executive.behaviours")}
    assert {(a, b) for a, targets in behaviours.items() for b in targets if b.startswith("executive.io")} == set()


@reads_the_package
def test_the_package_imports_no_test_only_library() -> None:
    """matplotlib draws the manual's pictures in tests (the [test] extra): an installed executive never needs it."""
    found = set()
    for name, path in MODULES.items():
        for node in import_statements(path):
            if isinstance(node, ast.Import):
                found |= {(name, alias.name.split(".")[0]) for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                found.add((name, node.module.split(".")[0]))
    assert {(name, lib) for name, lib in found if lib in ("matplotlib", "playwright")} == set()


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_over_600_lines(name: str) -> None:
    assert len(MODULES[name].read_text(encoding="utf-8").splitlines()) <= 600


@reads_the_package
def test_the_contract_reads_the_package_it_guards() -> None:
    """Imports are found at the top and inside functions; every module has a layer."""
    assert "executive.autopilot" in graph_of_ours()["executive.behaviours.commands"]  # the package: its __init__ imports the port
    assert "executive.world.dialect" in graph_of_ours()["executive.io.mavlink.link"]
    assert "executive.tree.select" in graph_of_ours()["executive.runtime.loop"]
    assert "executive.trees.parts" in graph_of_ours()["executive.trees.waypoints"]  # the trees/ folder read as executive.trees
    assert {layer(name) for name in MODULES} == set(range(len(LAYERS)))


def test_the_folders_are_the_layers() -> None:
    """Every folder of ``executive/`` is in exactly one layer, and no module lies loose beside them but the entry, the registry and the package."""
    named = [top for _, tops in LAYERS for top in tops]
    assert len(named) == len(set(named))
    on_disk = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file()} | {"trees"}
    loose = {p.stem for p in PACKAGE.glob("*.py")} - {"__init__"}
    assert on_disk <= set(named), "a new folder of executive/ must be placed in a layer"
    assert loose == {"__main__", "registry"}, "a module at executive/'s top belongs in a folder of its layer"
    assert all(layer(name) is not None for name in MODULES)
