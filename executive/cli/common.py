"""Helpers shared by subcommands: loading a mission the CLI way, logging set-up."""

from __future__ import annotations

import logging
import sys

from executive.mission.errors import MissionError
from executive.mission.loader import load_mission
from executive.mission.model import Mission


def load_or_report(path: str) -> Mission | None:
    """The mission in ``path``, or ``None`` after printing every error to stderr."""
    try:
        return load_mission(path)
    except MissionError as exc:
        for error in exc.errors:
            print(error, file=sys.stderr)
        return None


def setup_logging(verbose: int = 0) -> None:
    """Log to stderr: warnings by default, info with -v, debug with -vv."""
    level = (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    logging.basicConfig(level=level, format="executive: %(levelname)s: %(name)s: %(message)s", stream=sys.stderr, force=True)
