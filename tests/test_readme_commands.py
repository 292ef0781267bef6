"""Every command README and the manual's pages show is run here, or checked against the command line it names, so they cannot drift.

The commands are read from README.md and every page of ``docs/`` (the generated reference holds none): each line of a
``sh`` (or unlabelled) code block, and each inline code span, that starts with a command (``executive``, ``python``,
``pytest``, ``pip``, ``sudo``, ``systemctl``, ``journalctl``, ``mavproxy.py``, ``sphinx-build``); ``&&`` chains are split,
``$ `` prompts, ``sudo`` and trailing ``# comments`` dropped. Each is then one of:

- a usage line (placeholders: ``MISSION``, ``[--rate HZ]``, ``a|b``, ``...``, ``<x>``), or a mention
  of a command alone: its command and subcommands exist and every option it names is one of theirs;
- an ``executive`` example that needs nothing else: run in-process in a scratch directory (with
  ``missions/``, a ``mission.yaml`` and the ``rover_square.yaml`` getting started copies out), exit 0 (``service install``
  with ``--unit-dir`` there, ``examples --copy`` with ``--to`` a directory of its own);
- an ``executive run`` of a shipped mission (a file, or an example by name): its options parsed and checked by the very function
  ``run`` calls before it opens anything; README's first command, the rover's square, also run to
  COMPLETED, lock-step with its simulator (seconds, not the minute README's pace takes, and the same on a busy machine);
- in :data:`NOT_RUN_HERE`, with the reason (hardware, systemd, a live executive, minutes); its
  ``executive`` part still parsed by the real command line. An entry no page shows any more fails.
"""

from __future__ import annotations

import argparse
import re
import shlex
import shutil
from pathlib import Path

import pytest

from executive.cli import COMMANDS, build_parser, main
from executive.cli.run_checks import check_run
from executive.mission.loader import load_mission
from tests_support import run_in_lockstep

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts)]
README = (ROOT / "README.md").read_text(encoding="utf-8")
COMMAND_WORDS = ("executive", "python", "python3", "pytest", "pip", "sudo", "systemctl", "journalctl", "mavproxy.py", "sphinx-build", ".")

#: Commands README shows that are not run here: exact text (after a ``$ ``, ``sudo`` and a comment are taken off) -> why.
NOT_RUN_HERE: dict[str, str] = {
    "python3 -m venv .venv": "makes a virtual environment (this suite runs in one)",
    "pip install 'executive[foxglove]'": "installs the Foxglove SDK (the test extra, this suite's, has it)",
    ". .venv/bin/activate": "a shell's own command",
    "pip install .": "installs the package from the network or a cache (this suite runs installed)",
    "pip install '.[test]'": "installs the package from the network or a cache (this suite runs installed)",
    "pytest -q -n auto": "the whole suite, of which this test is part",
    "pip install uxv-executive": "installs the released package from the package index (tests/test_wheel.py installs the wheel it builds)",
    "pip install dist/uxv_executive-*.whl": "installs the wheel python -m build makes (tests/test_wheel.py does, in a fresh virtualenv)",
    "python -m build": "tests/test_wheel.py runs it (an sdist and a wheel, twine check, the wheel run in a fresh virtualenv)",
    "sphinx-build -W -b html docs docs/_build/html": ".ci/run builds the manual so, warnings as errors (tests/docs/ checks its generated reference)",
    "systemctl daemon-reload": "systemd, as root",
    "systemctl enable --now executive-boat_survey": "systemd, as root",
    "systemctl status executive-boat_survey": "systemd (tests/cli/test_service.py runs the unit's ExecStart under a fake service manager)",
    "journalctl -u executive-boat_survey -f": "systemd's journal",
    "systemctl stop": "systemd",
    "systemctl enable --now mavlink-router": "systemd and mavlink-router",
    "executive ctl --socket /run/executive-boat_survey/control.sock status": "needs the service running (tests/cli/test_ctl.py)",
    "executive ctl pause": "needs a running executive (tests/cli/test_ctl.py)",
    "executive ctl upload survey-v2.yaml": "needs a paused executive and the operator's new file (tests/cli/test_ctl.py, tests/operator/)",
    "executive ctl resume": "needs a running executive (tests/cli/test_ctl.py)",
    "executive ctl status": "needs a running executive (tests/cli/test_ctl.py)",
    "executive report j.db | head": "needs the journal of a run (tests/cli/test_console.py: a reader that goes away)",
    "executive replay run.snap --web 8080": "needs a recorded run, and serves a browser until Ctrl-C (tests/observers/web/test_replay_web.py)",
    "executive replay run.jsonl --groot2 1667 --speed 10": "served to Groot2 until Ctrl-C (tests/observers/groot2/test_groot2_clients.py)",
    "executive sim --vehicle boat --mavlink tcpin:0.0.0.0:5760": "serves a ground station until Ctrl-C (tests/sim/test_server.py)",
    "executive sim": "serves a simulated vehicle until Ctrl-C (tests/sim/test_server.py)",
    "executive import cmac.waypoints --vehicle rover --zones fence.waypoints --zones points.rally -o m.yaml": "needs Mission Planner's "
    "files (tests/mission/test_mp_zone_files.py imports the same kinds, and runs `executive import --zones`)",
    "python -m benchmarks": "about 4 minutes on 2 cores (tests/test_benchmarks_smoke.py runs each benchmark once, small)",
    "python -m benchmarks --json bench.json": "about 4 minutes on 2 cores (tests/test_benchmarks_smoke.py)",
    "python -m benchmarks --only tick ingest": "a minute (tests/test_benchmarks_smoke.py)",
    "python -m benchmarks --only efficiency": "a minute (tests/test_benchmarks_smoke.py)",
    "python -m benchmarks --only route": "seconds (tests/test_benchmarks_smoke.py)",
    "python -m benchmarks --only tick": "minutes (tests/test_benchmarks_smoke.py runs it small)",
}
#: Commands that need nothing but files: run in-process, in a scratch directory.
IN_PROCESS = frozenset({"validate", "show", "schema", "behaviours", "export", "import", "service", "examples", "foxglove-layout"})
#: README's first command: run for real, as shown, its simulator lock-step with it (its pace is the reader's, not the suite's).
RUN_FOR_REAL = {"executive run missions/rover_square.yaml --speedup 20": []}
_PLACEHOLDER = re.compile(r"^\[|[|<>\[\]]|\.\.\.|^[A-Z][A-Z0-9_]*(\.[a-z]+)?$|^[A-Z]+:|:[A-Z]+$|^\d+\.\d+\.\d+\.\d+:[A-Z]+$")


def _commands() -> list[str]:
    """Every command README and the pages show, in order, each once."""
    found: list[str] = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for lang, body in re.findall(r"```(\w*)\n(.*?)```", text, re.S):
            if lang in ("sh", "bash", ""):
                found += [line for line in body.splitlines() if _is_command(line)]
        prose = re.sub(r"```.*?```", "", text, flags=re.S).replace("\\|", "|")
        found += [span for span in re.findall(r"`([^`\n]+)`", prose) if _is_command(span)]
    commands: list[str] = []
    for line in found:
        for part in line.split("&&"):
            text = _clean(part)
            if text and text not in commands:
                commands.append(text)
    return commands


def _is_command(text: str) -> bool:
    words = text.strip().removeprefix("$ ").split()
    return bool(words) and words[0] in COMMAND_WORDS and not (words[0] == "." and words[1:2] != [".venv/bin/activate"])


def _clean(text: str) -> str:
    text = re.sub(r"\s+#.*$", "", text.strip()).removeprefix("$ ").strip()
    return text.removeprefix("sudo ").strip()


COMMANDS_SHOWN = _commands()


def test_readme_shows_commands_and_every_one_is_accounted_for():
    assert len(COMMANDS_SHOWN) > 40
    kinds = {c: _kind(c) for c in COMMANDS_SHOWN}
    assert [c for c, kind in kinds.items() if kind is None] == []
    assert sorted(set(NOT_RUN_HERE) - set(COMMANDS_SHOWN)) == []  # a command no page shows any more is not excused here
    assert set(RUN_FOR_REAL) <= set(COMMANDS_SHOWN)
    assert README.split("```sh\n")[1].split("```")[0].splitlines()[0].endswith(next(iter(RUN_FOR_REAL)))  # README's first command


def _kind(command: str) -> str | None:
    """How a command is accounted for: listed (not run here), usage, run, in-process; None: not at all (the test fails)."""
    words = command.split()
    if command in NOT_RUN_HERE:
        return "listed"
    if words[0] != "executive" or (len(words) > 1 and words[1] not in COMMANDS and not _top_level(words[1])):
        return None
    if len(words) == 1 or _top_level(words[1]) or any(_PLACEHOLDER.search(w) for w in words[2:]) or not _parses(words[1:]):
        return "usage"  # a usage line, or a command named without what it needs (`executive run`, `ctl upload`)
    if words[1] == "run":
        return "run"
    return "in-process" if words[1] in IN_PROCESS else None


def _top_level(word: str) -> bool:
    """An option of ``executive`` itself, or any command (``COMMAND``)."""
    return word.startswith("-") or word == "COMMAND"


def _parses(argv: list[str]) -> bool:
    try:
        build_parser(argv[0]).parse_args(argv)
    except SystemExit:
        return False
    return True


# -- usage lines and mentions: the commands, subcommands and options exist -------------------------------------------------------------


def _parser_chain(words: list[str]) -> list[argparse.ArgumentParser]:
    """The parsers a usage line goes through: the command's, then each subcommand's it names (every alternative of ``a|b``)."""
    if len(words) == 1 or _top_level(words[1]):
        return [build_parser()]  # `executive` alone, `executive --version`, `executive COMMAND --help`
    command = words[1]
    root = build_parser(command)
    sub = next(a for a in root._actions if isinstance(a, argparse._SubParsersAction))
    chain = [sub.choices[command]]
    level = [chain[0]]
    for word in words[2:]:
        subs = [a for p in level for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        names = [n for n in word.strip("[]").split("|") if n and not n.startswith("-")]
        known = [n for n in names if any(n in s.choices for s in subs)]
        if not known:
            continue  # an argument (a placeholder, a file), not a subcommand
        assert known == names, f"{' '.join(words)}: {sorted(set(names) - set(known))} are not subcommands of `executive {command}`"
        level = [s.choices[n] for n in names for s in subs if n in s.choices]
        chain += level
    return chain


@pytest.mark.parametrize("command", [c for c in COMMANDS_SHOWN if _kind(c) == "usage"])
def test_a_usage_line_names_commands_and_options_that_exist(command):
    words = command.split()
    chain = _parser_chain(words)
    options = {o for p in chain for a in p._actions for o in a.option_strings}
    named = {m.split("=")[0] for w in words[2:] for m in re.findall(r"(?<![\w-])(--?[a-z][\w-]*)", w)}
    assert named <= options, f"{command}: {sorted(named - options)} are not options of `executive {words[1]}`"


# -- examples run in-process ------------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    """A directory with the pages' files: missions/ (a copy), mission.yaml (the rover's square), its tree.xml, rover_square.yaml.

    The tree.xml README's `export` writes is made here too: pytest-xdist may run the `import` examples in another
    worker than the `export` one, each with a directory of its own.
    """
    where = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "missions", where / "missions")
    shutil.copy(ROOT / "missions" / "rover_square.yaml", where / "mission.yaml")
    assert main(["export", str(where / "mission.yaml"), "--format", "btcpp", "-o", str(where / "tree.xml")]) == 0
    assert main(["examples", "--copy", "rover_square", "--to", str(where)]) == 0  # as getting started does, before it validates
    return where


@pytest.mark.parametrize("command", [c for c in COMMANDS_SHOWN if _kind(c) == "in-process"])
def test_an_example_runs_and_exits_0(command, scratch, tmp_path, monkeypatch, capsys):
    """Each in a scratch directory with the pages' files."""
    monkeypatch.chdir(scratch)
    argv = shlex.split(command)[1:]
    if argv[:2] == ["service", "install"]:
        argv += ["--unit-dir", str(scratch)]  # not /etc/systemd/system: no root here
    if argv[:2] == ["examples", "--copy"]:
        argv += ["--to", str(tmp_path)]  # the scratch has its copy already
    code = main(argv)
    assert code == 0, f"{command}: exit {code}: {capsys.readouterr().err}"


@pytest.mark.parametrize("command", [c for c in COMMANDS_SHOWN if _kind(c) == "run"])
def test_a_run_example_passes_runs_own_checks(command, scratch, monkeypatch):
    monkeypatch.chdir(scratch)
    argv = shlex.split(command)[1:]
    args = build_parser("run").parse_args(argv)
    check_run(args, load_mission(args.mission))  # BadInput (exit 2) if run would refuse it


@pytest.mark.parametrize("command", list(RUN_FOR_REAL))
def test_readmes_first_command_drives_the_square_to_completed(command, monkeypatch, capsys):
    """Lock-step (it was run at 150x on the wall clock: beside CPU hogs the loop kept 0.3 of its 10 ticks a vehicle second;
    a copy ran it at 20x in a process of its own: an executive's exit code as a process is tests/cli/test_run.py's)."""
    monkeypatch.chdir(ROOT)
    run_in_lockstep(monkeypatch)
    argv = [*shlex.split(command)[1:], *RUN_FOR_REAL[command], "--socket", "none"]
    code, err = main(argv), capsys.readouterr().err
    assert code == 0, err
    assert "COMPLETED: every waypoint reached" in err


@pytest.mark.parametrize("command", [c for c in NOT_RUN_HERE if c.startswith("executive ")])
def test_an_example_not_run_here_is_still_a_command_line_the_executive_takes(command):
    words = shlex.split(command.split(" | ")[0])[1:]
    build_parser(words[0]).parse_args(words)  # SystemExit (exit 2) on an option or a subcommand that does not exist
