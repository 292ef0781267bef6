"""The package as a user gets it: built as ``python -m build`` builds it (an sdist, then the wheel from the extracted sdist,
each in an isolated environment holding only what pyproject's ``build-system`` asks for), ``twine check``, the wheel in a
fresh virtualenv outside the checkout, and an example run by name there.

Slow (two isolated builds, a run): marked ``slow``, so ``pytest -m 'not slow'`` leaves it out while working; README's test
command runs it. The two builds run build's own steps through its API (``ProjectBuilder`` in a ``DefaultIsolatedEnv``) in one
isolated environment: ``python -m build`` makes one per build, and installing setuptools into it was 2.4 of the test's 10 s of
CPU. No network beyond the suite's own install: the build's isolated environment takes setuptools from pip's cache.

What it does NOT prove: that pip resolves the wheel's dependencies from the index. The fresh virtualenv gets the wheel alone
(``--no-deps``) and borrows this environment's packages through a ``.pth`` file, behind its own site-packages (``executive``
itself comes from the wheel, never from the checkout): installing the dependencies into it took 58 s on the 2-core machine, too
much for the suite. What stands in for it: ``pip check`` in the fresh virtualenv (every requirement the wheel declares is there,
at a version it accepts), and every third-party package the wheel's modules import is one its Requires-Dist names (read from the
wheel's own files), so a dependency the wheel forgets to declare fails here.
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest
from build import ProjectBuilder
from build.env import DefaultIsolatedEnv

ROOT = Path(__file__).parents[1]
#: What the sdist is made of (the rest of the repository is not the package's).
SOURCES = ("executive", "trees", "missions", "pyproject.toml", "README.md", "CHANGELOG.md")


def _key(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _undeclared_imports(wheel: Path) -> dict[str, str]:
    """Each module of the wheel's ``executive`` that imports a third-party package no Requires-Dist of the wheel names (an extra's
    counts): {module's path: the package}. The packages' owners are looked up in this environment."""
    from importlib import metadata

    owners = metadata.packages_distributions()
    with zipfile.ZipFile(wheel) as archive:
        meta = next(n for n in archive.namelist() if n.endswith(".dist-info/METADATA"))
        requires = [line.split(":", 1)[1] for line in archive.read(meta).decode().splitlines() if line.startswith("Requires-Dist:")]
        declared = {_key(re.match(r"\s*([\w.-]+)", line)[1]) for line in requires}
        undeclared = {}
        for name in (n for n in archive.namelist() if n.startswith("executive/") and n.endswith(".py")):
            for node in ast.walk(ast.parse(archive.read(name), name)):
                if isinstance(node, ast.Import):
                    tops = {alias.name.split(".")[0] for alias in node.names}
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    tops = {node.module.split(".")[0]}
                else:
                    continue
                for top in tops - set(sys.stdlib_module_names) - {"executive", "__future__"}:
                    if not {_key(d) for d in owners.get(top, [top])} & declared:
                        undeclared[name] = top
    return undeclared


def _run(command: list[str], **kwargs) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, **kwargs)
    assert done.returncode == 0, f"{' '.join(command)}: exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done


def _build_sdist_then_wheel(source: Path, dist: Path) -> tuple[Path, Path]:
    """``python -m build``'s steps: the sdist of ``source``, then the wheel from the extracted sdist, each with the backend's own
    build requirements installed first; one isolated environment (only setuptools, as pyproject asks) for both."""
    with DefaultIsolatedEnv() as env:
        builder = ProjectBuilder.from_isolated_env(env, source)
        env.install(builder.build_system_requires)
        env.install(builder.get_requires_for_build("sdist"))
        sdist = Path(builder.build("sdist", dist))
        with tarfile.open(sdist) as archive:
            archive.extractall(dist.with_name("unpacked"), filter="data")
        (unpacked,) = dist.with_name("unpacked").iterdir()  # one top-level directory, as build requires of an sdist
        assert (unpacked / "PKG-INFO").is_file()
        from_sdist = ProjectBuilder.from_isolated_env(env, unpacked)
        assert from_sdist.build_system_requires == builder.build_system_requires  # installed already (pip again: 1 s for nothing)
        env.install(from_sdist.get_requires_for_build("wheel"))
        wheel = Path(from_sdist.build("wheel", dist))
    return sdist, wheel


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::pyproject_hooks.BuildBackendWarning")  # setuptools' advice, which `python -m build` prints and we never read
def test_the_wheel_alone_in_a_fresh_virtualenv_lists_and_runs_the_examples_by_name_with_only_the_packages_it_declares(tmp_path: Path) -> None:
    source = tmp_path / "source"  # a copy: the build's egg-info and build/ stay out of the checkout
    for name in SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy(ROOT / name, source / name)
    sdist, wheel = _build_sdist_then_wheel(source, tmp_path / "dist")
    _run([sys.executable, "-m", "twine", "check", "--strict", str(wheel), str(sdist)])
    names = zipfile.ZipFile(wheel).namelist()
    examples = {"rover_square.yaml", "faults/rc_loss.yaml", "events/ugv_operator.yaml", "mission.schema.json"}
    assert {f"executive/examples/{name}" for name in examples} <= set(names)
    assert [n for n in names if n.split("/")[0] != "executive" and ".dist-info/" not in n] == []  # nothing at the top but executive

    fresh = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(fresh)
    python = fresh / "bin" / "python"
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index", "-q", str(wheel)])
    purelib = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).stdout.strip())
    (purelib / "zz_dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")  # after the venv's own: its executive first
    home = tmp_path / "home"  # outside the checkout, nothing of it on the path
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")} | {"HOME": str(home)}
    where = _run([str(python), "-c", "import executive; print(executive.__file__)"], cwd=home, env=env).stdout.strip()
    assert Path(where).is_relative_to(purelib), where
    executive = str(fresh / "bin" / "executive")

    listed = json.loads(_run([executive, "examples", "--json"], cwd=home, env=env).stdout)
    assert {m["name"] for m in listed["missions"]} >= {"rover_square", "boat_survey", "auv_survey", "vtol_transit", "ugv_rc_route"}
    assert all(Path(m["file"]).is_relative_to(purelib) for m in listed["missions"])
    assert "rc_loss" in listed["faults"]

    _run([str(python), "-m", "pip", "check"], env=env)  # every declared requirement is there (pip through the .pth: one start, not two)
    assert _undeclared_imports(wheel) == {}, "the wheel's code imports packages it does not declare"

    ran = subprocess.run([executive, "run", "rover_square", "--speedup", "50", "--socket", str(home / "ctl.sock")], cwd=home, env=env,
                         capture_output=True, text=True, timeout=600)  # fmt: skip
    assert ran.returncode == 0, ran.stderr[-3000:]
    assert "executive: mission 'rover-square' COMPLETED: every waypoint reached" in ran.stderr
