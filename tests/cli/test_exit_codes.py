"""One table of exit codes and one message prefix for every subcommand: the manual's table is the code's, and a port in use is 3 for all."""

from __future__ import annotations

import re
import socket
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive import cli
from executive.cli import main

DOCS = Path(__file__).parents[2] / "docs"
RUNNING = DOCS / "running.md"  # README's "The command line", in the manual
sys.path.insert(0, str(DOCS / "_ext"))
import executive_reference as reference  # noqa: E402


def test_the_manuals_table_of_exit_codes_is_the_codes():
    """The running page's table is generated (``exit_codes``) at each build: it has every EXIT_ constant, each with its meaning."""
    assert "\n<!-- generated: exit_codes -->\n" in RUNNING.read_text(encoding="utf-8")
    page = reference.expand("<!-- generated: exit_codes -->")
    table = re.search(r"\| code \| meaning \|\n\|---\|---\|\n((?:\|.*\n)+)", page)
    assert table, "the generated page has no table of exit codes"
    rows = [row.split(" | ") for row in table.group(1).splitlines()]
    documented = [int(row[0].strip("| ")) for row in rows]
    constants = sorted(value for name, value in vars(cli).items() if name.startswith("EXIT_") and isinstance(value, int))
    assert documented == constants
    assert all(len(row[1].strip("| ")) > 10 for row in rows), "an exit code without its meaning"
    assert "exit codes, the same for every command: 0: success" in cli.build_parser().format_help().replace("\n", " ").replace("  ", " ")


@pytest.fixture
def port_in_use() -> Iterator[int]:
    """A TCP port another process (here: a socket of ours) listens on."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        yield taken.getsockname()[1]


def test_a_port_in_use_is_the_same_fault_for_sim_and_run_exit_3_said_alike(port_in_use, capsys, minimal_mission, tmp_path):
    """Issue 43: sim said `executive sim: cannot listen on ...` and exited 1; run said `executive: run: --mavlink ...` and exited 3."""
    url = f"tcpin:127.0.0.1:{port_in_use}"
    said = f"--mavlink {url}: cannot listen on 127.0.0.1:{port_in_use}: Address already in use"
    assert main(["sim", "--mavlink", url, "--duration", "1"]) == cli.EXIT_NO_VEHICLE
    assert capsys.readouterr().err == f"executive: sim: {said}\n"
    assert main(["run", str(minimal_mission), "--mavlink", url, "--socket", str(tmp_path / "s.sock")]) == cli.EXIT_NO_VEHICLE
    assert capsys.readouterr().err.splitlines()[-1] == f"executive: run: {said}"


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["sim", "--mavlink", "udp:127.0.0.1:1"], 2, "executive: sim: --mavlink expected tcpin:HOST:PORT or udpin:HOST:PORT, got 'udp:127.0.0.1:1'"),
        (["sim", "--vehicle", "rover", "--can", "virtual:x"], 2, "executive: sim: --can simulates the AgileX base of the tracked UGV"),
        (["sim", "--vehicle", "bunker", "--can", "nosuch:x"], 2, "executive: sim: --can: "),
    ],
)
def test_sims_refusals_carry_the_common_prefix_and_code(argv, code, message, capsys):
    assert main(argv) == code
    assert capsys.readouterr().err.startswith(message)


def test_the_manual_names_the_socket_a_second_executive_takes(monkeypatch):
    """Issue 43: README said `executive-PID.sock`; without $XDG_RUNTIME_DIR it is `executive-UID-PID.sock` (executive-0-PID.sock as root).

    The names are in `run --socket`'s help, which the manual's command line reference is generated from."""
    from executive.io.control import default_socket_path

    text = reference.cli_reference()
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    assert default_socket_path(1234).endswith("/executive-" + str(__import__("os").getuid()) + "-1234.sock")
    assert "`executive-UID-PID.sock`" in text
    monkeypatch.setenv("XDG_RUNTIME_DIR", "/run/user/1000")
    assert default_socket_path(1234) == "/run/user/1000/executive-1234.sock" and "`executive-PID.sock` under `$XDG_RUNTIME_DIR`" in text
