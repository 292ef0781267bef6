"""The operator side: a person's requests (``executive ctl``, a ground station, the RC switches) applied to the mission
lifecycle (:mod:`executive.operator.requests`), and the ground-station endpoint that takes MAVLink commands to them and
reports the mission back (:mod:`executive.operator.ground_station`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from executive import lazy_exports

if TYPE_CHECKING:
    from executive.operator.requests import REQUESTS, VEHICLE_REQUESTS, Operator, Reply

__all__ = ["REQUESTS", "VEHICLE_REQUESTS", "Operator", "Reply"]

# imported on first use: ``executive ctl`` needs only this package's status line, not the requests' whole mission (~0.8 s of CPU)
__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "requests"))
