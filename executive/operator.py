"""Operator requests - from ``executive ctl``, the ground station or RC switches - applied to the mission lifecycle.

Every request follows the lifecycle's transition table; a refused one changes nothing and says
why. The reply carries the resulting state so a client never has to ask twice.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

from executive.mission.errors import MissionError
from executive.mission.lifecycle import MissionState, Refused
from executive.mission.loader import load_mission_text
from executive.mission.model import Mission

REQUESTS = ("status", "start", "pause", "resume", "abort", "delete", "upload")


@dataclass(frozen=True)
class Reply:
    """What became of a request."""

    ok: bool
    reason: str
    state: str
    status: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        return {k: v for k, v in asdict(self).items() if v is not None}


class Operator:
    """Applies operator requests to a :class:`MissionState`.

    ``status`` supplies the status snapshot for ``status`` requests; ``vehicle`` is the kind of
    vehicle this executive drives (an uploaded mission for another kind is refused).
    """

    def __init__(self, mission_state: MissionState, vehicle: str, status: Callable[[], dict[str, Any]] | None = None) -> None:
        self.mission_state = mission_state
        self.vehicle = vehicle
        self._status = status

    def request(self, op: str, source: str = "operator", **args: Any) -> Reply:
        """Apply one request; ``source`` (ctl, gcs, rc) is recorded in the reasons."""
        state = self.mission_state
        try:
            if op == "status":
                return self._reply(True, state.reason, with_status=True)
            if op == "start":
                state.start()
            elif op == "pause":
                state.pause(f"{source}: pause")
            elif op == "resume":
                state.resume()
            elif op == "abort":
                state.abort(f"{source}: abort")
            elif op == "delete":
                state.delete()
            elif op == "upload":
                return self._upload(str(args.get("filename", "<upload>")), args.get("text"))
            else:
                return self._reply(False, f"unknown request {op!r} (known: {', '.join(REQUESTS)})")
        except Refused as refused:
            return self._reply(False, str(refused))
        return self._reply(True, state.reason)

    def _upload(self, filename: str, text: object) -> Reply:
        if not isinstance(text, str):
            return self._reply(False, "upload needs the mission file's text")
        try:
            mission: Mission = load_mission_text(text, filename)
        except MissionError as exc:
            return self._reply(False, "\n".join(str(e) for e in exc.errors))
        if mission.vehicle != self.vehicle:
            return self._reply(False, f"{filename}: vehicle: this executive drives a {self.vehicle}, not a {mission.vehicle}")
        self.mission_state.upload(mission)
        return self._reply(True, self.mission_state.reason)

    def _reply(self, ok: bool, reason: str, with_status: bool = False) -> Reply:
        status = self._status() if with_status and self._status else None
        return Reply(ok, reason, str(self.mission_state.status), status)
