"""``executive examples [--json] [--copy NAME [--to DIR]]``: the example missions installed with the package, run by name.

Installed, the examples are package data (``executive/examples/``: pyproject maps the repository's ``missions/`` folder
there); run from a checkout they are ``missions/`` itself. A command that takes a mission file takes an example's name
too (:func:`mission_file`: ``executive run rover_square``), and ``--faults`` the name of an example's fault or event
file (:func:`fault_file`); a file of that name in the current directory comes first.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

from executive.cli import EXIT_BAD_INPUT, EXIT_OK

_PACKAGE = Path(__file__).resolve().parents[1]
#: Event and fault files, in the folders beside the missions that ``simulator.events`` and ``--faults`` name.
EVENT_FOLDERS = ("events", "faults")


def folder() -> Path:
    """Where the example missions are: the installed package's ``examples/``, else the checkout's ``missions/``."""
    installed = _PACKAGE / "examples"
    return installed if installed.is_dir() else _PACKAGE.parent / "missions"


def names() -> list[str]:
    """The examples' names (their file names without ``.yaml``)."""
    return sorted(p.stem for p in folder().glob("*.yaml"))


def mission_file(text: str) -> str:
    """An argparse ``type=`` for a mission: a file as given, or the example of that name when no such file is here."""
    if Path(text).exists() or not (folder() / f"{text}.yaml").is_file():
        return text
    return str(folder() / f"{text}.yaml")


def fault_file(text: str) -> str:
    """An argparse ``type=`` for ``--faults``: a file as given, or an example's fault or event file of that name."""
    if Path(text).exists():
        return text
    found = [folder() / sub / f"{text}.yaml" for sub in EVENT_FOLDERS if (folder() / sub / f"{text}.yaml").is_file()]
    return str(found[0]) if found else text


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``examples`` subcommand."""
    parser = subparsers.add_parser(
        "examples",
        help="list the example missions installed with the package (run one by name: executive run rover_square)",
        description="List the example missions installed with the package, with their event and fault files; any command that "
        "takes a mission takes an example's name (executive run rover_square --speedup 20), and --faults a fault file's (rc_loss).",
    )
    parser.add_argument("--json", action="store_true", help="a JSON list of the examples on stdout")
    parser.add_argument("--copy", metavar="NAME", help="write example NAME (and the event and fault files beside it) to a directory, to edit")
    parser.add_argument("--to", metavar="DIR", default=".", help="the directory --copy writes to (default: the current one)")
    parser.set_defaults(func=run)


def _described(path: Path) -> dict[str, str]:
    import yaml

    data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    return {"name": path.stem, "vehicle": str(data.get("vehicle", "")), "description": str(data.get("description") or ""), "file": str(path)}


def run(args: argparse.Namespace) -> int:
    """List the examples, or copy one out."""
    where = folder()
    if args.copy is not None:
        return _copy(args.copy, Path(args.to))
    examples = [_described(where / f"{name}.yaml") for name in names()]
    files = {sub: sorted(p.stem for p in (where / sub).glob("*.yaml")) for sub in EVENT_FOLDERS}
    if args.json:
        json.dump({"missions": examples, **files}, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return EXIT_OK
    width = max(len(e["name"]) for e in examples)
    for example in examples:
        print(f"{example['name']:<{width}}  {example['vehicle']:<7} {example['description']}")
    for sub, found in files.items():
        print(f"\n{sub} (--faults NAME): {', '.join(found)}")
    print(f"\nrun one: executive run {examples[0]['name']} --speedup 20   (the files are in {where})")
    return EXIT_OK


def _copy(name: str, to: Path) -> int:
    source = folder() / f"{name}.yaml"
    if not source.is_file():
        print(f"executive: examples: no example {name!r}; there are {', '.join(names())}", file=sys.stderr)
        return EXIT_BAD_INPUT
    target = to / source.name
    if target.exists():
        print(f"executive: examples: {target} exists; not overwritten", file=sys.stderr)
        return EXIT_BAD_INPUT
    to.mkdir(parents=True, exist_ok=True)
    shutil.copy(source, target)
    for sub in EVENT_FOLDERS:
        shutil.copytree(folder() / sub, to / sub, dirs_exist_ok=True)
    for extra in folder().glob("*.json"):  # the schema the examples name for editors (yaml-language-server)
        if not (to / extra.name).exists():
            shutil.copy(extra, to / extra.name)
    print(f"executive: examples: wrote {target} (and {', '.join(f'{s}/' for s in EVENT_FOLDERS)} beside it)", file=sys.stderr)
    return EXIT_OK
