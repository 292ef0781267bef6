"""Mission files in tests: every error a text has."""

from __future__ import annotations


def mission_errors(text: str, filename: str = "m.yaml") -> list[str]:
    """Every located error of a mission text (``FILE:LINE:COL: field: why``; none when it is valid)."""
    from executive.admission.checks import load_mission_text
    from executive.mission.errors import MissionError

    try:
        load_mission_text(text, filename)
    except MissionError as exc:
        return [str(e) for e in exc.errors]
    return []
