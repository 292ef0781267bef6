"""Missions: the YAML file format, its validation and the mission lifecycle."""

from __future__ import annotations

from typing import TYPE_CHECKING

from executive import lazy_exports

if TYPE_CHECKING:
    from executive.mission.errors import FieldError, MissionError
    from executive.mission.model import Limits, Mission, Waypoint

__all__ = ["FieldError", "Limits", "Mission", "MissionError", "Waypoint"]

# imported on first use: a module of this package (its errors, a command's table) does not cost the model's pydantic classes
__getattr__, __dir__ = lazy_exports(
    __name__, {"FieldError": "errors", "MissionError": "errors", "Limits": "model", "Mission": "model", "Waypoint": "model"}
)
