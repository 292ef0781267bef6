"""The operator side: a person's requests (``executive ctl``, a ground station, the RC switches) applied to the mission
lifecycle (:mod:`executive.operator.requests`), and the ground-station endpoint that takes MAVLink commands to them and
reports the mission back (:mod:`executive.operator.ground_station`)."""

from executive.operator.requests import REQUESTS, VEHICLE_REQUESTS, Operator, Reply

__all__ = ["REQUESTS", "VEHICLE_REQUESTS", "Operator", "Reply"]
