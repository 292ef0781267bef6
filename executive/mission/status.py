"""The mission lifecycle's states (the transitions between them: :mod:`executive.mission.lifecycle`)."""

from enum import StrEnum


class MissionStatus(StrEnum):
    IDLE = "IDLE"
    READY = "READY"
    RUNNING = "RUNNING"
    PAUSED = "PAUSED"
    COMPLETED = "COMPLETED"
    ABORTED = "ABORTED"
