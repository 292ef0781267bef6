"""Missions: the YAML file format, its validation and the mission lifecycle."""

from executive.mission.errors import FieldError, MissionError
from executive.mission.model import Limits, Mission, Waypoint

__all__ = ["FieldError", "Limits", "Mission", "MissionError", "Waypoint"]
