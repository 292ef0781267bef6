"""Errors a person can act on: ``FILE:LINE:COL: FIELD: message``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

Path = tuple[str | int, ...]


def format_path(path: Path) -> str:
    """``("waypoints", 2, "lat")`` -> ``waypoints[2].lat``; the empty path is ``(mission)``.

    A mapping key YAML does not read as text (``null: 1``, ``1.5: 1``) is shown as Python prints it.
    """
    out = ""
    for part in path:
        if isinstance(part, int) and not isinstance(part, bool):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out or "(mission)"


@dataclass(frozen=True)
class FieldError:
    """One problem in a mission file, located as precisely as the file allows."""

    file: str
    line: int  # 1-based
    column: int  # 1-based
    field: str
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}: {self.field}: {self.message}"


class MissionError(Exception):
    """A mission file was refused; carries every error found, in file order."""

    def __init__(self, errors: Sequence[FieldError]) -> None:
        self.errors = sorted(errors, key=lambda e: (e.file, e.line, e.column, e.field))
        super().__init__("\n".join(str(e) for e in self.errors))
