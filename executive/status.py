"""The executive's status, as the operator sees it: one snapshot of the blackboard.

Shown on the progress line, returned by ``executive ctl status``, written as JSON lines and sent
to the ground station. Battery, position, yaw, pitch/roll, vehicle id and armed come from the
ASV node's 2 Hz status; mode, mission state, leg and distance/bearing from the executive.
"""

from __future__ import annotations

from typing import Any

import py_trees

from executive import blackboard, geo
from executive.clock import Clock
from executive.waiting import waiting_text

KEYS = (
    "/mission/state", "/mission/reason", "/mission/leg_index", "/mission/leg_count", "/mission/target", "/mission/samples", "/vehicle/position",
    "/vehicle/attitude", "/vehicle/battery", "/vehicle/mode", "/vehicle/armed", "/link/system_id", "/link/up",
    "/runtime/late_ticks", "/mission/waiting", "/energy/estimate",
)  # fmt: skip


class StatusSource:
    """Reads the status keys (a read-only blackboard client); with ``clock``, says for how long the tree has been waiting."""

    def __init__(self, name: str = "status", clock: Clock | None = None) -> None:
        self._bb: py_trees.blackboard.Client = blackboard.reader(name, KEYS)
        self._clock = clock

    def headline(self) -> tuple[object, ...]:
        """State, leg, mode and armed, as :meth:`snapshot` has them: cheap to read every tick (no distance worked out)."""
        bb = self._bb
        return bb.get("/mission/state"), _leg(bb), bb.get("/vehicle/mode"), bool(bb.get("/vehicle/armed"))

    def snapshot(self) -> dict[str, Any]:
        """Plain values, ready for JSON: None where not known yet; ``t``: the clock's time (the vehicle's), with a clock."""
        bb = self._bb
        position, attitude, battery, target = (bb.get(k) for k in ("/vehicle/position", "/vehicle/attitude", "/vehicle/battery", "/mission/target"))
        waiting = bb.get("/mission/waiting")
        distance = bearing = None
        if target is not None and position is not None:
            distance, bearing = geo.distance_bearing(position.lat, position.lon, target.lat, target.lon)
        return {
            "t": None if self._clock is None else round(self._clock.now(), 2),
            "state": bb.get("/mission/state"),
            "reason": bb.get("/mission/reason"),
            "leg": _leg(bb),
            "legs": bb.get("/mission/leg_count"),
            "distance_m": None if distance is None else round(distance, 2),
            "bearing_deg": None if bearing is None else round(bearing, 1),
            "samples": len(bb.get("/mission/samples")),
            "mode": bb.get("/vehicle/mode"),
            "armed": bool(bb.get("/vehicle/armed")),
            "vehicle_id": bb.get("/link/system_id"),
            "link_up": bool(bb.get("/link/up")),
            "lat": None if position is None else round(position.lat, 7),
            "lon": None if position is None else round(position.lon, 7),
            "yaw_deg": None if attitude is None else round(attitude.yaw_deg, 1),
            "pitch_deg": None if attitude is None else round(attitude.pitch_deg, 1),
            "roll_deg": None if attitude is None else round(attitude.roll_deg, 1),
            "battery_v": None if battery is None else battery.voltage_v,
            "battery_pct": None if battery is None else battery.remaining_pct,
            "late_ticks": bb.get("/runtime/late_ticks"),
            "waiting": None if waiting is None else waiting.to_dict(self._clock.now() if self._clock else None),
            "energy": _energy(bb.get("/energy/estimate")),
        }


def _energy(estimate: Any) -> dict[str, float] | None:
    """The energy left above the reserve, the estimate to finish and return (and its 1 sigma), the margin, Wh; None: no estimate."""
    if estimate is None:
        return None
    return {
        "has_wh": round(estimate.has_wh, 2),
        "need_wh": round(estimate.route_wh + estimate.home_wh, 2),
        "home_wh": round(estimate.home_wh, 2),
        "sigma_wh": round(estimate.sigma_wh, 2),
        "margin_wh": round(estimate.margin_wh, 2),
    }


def _leg(bb: py_trees.blackboard.Client) -> int:
    return min(bb.get("/mission/leg_index") + 1, bb.get("/mission/leg_count"))


def status_line(status: dict[str, Any]) -> str:
    """``RUNNING   leg 2/4    12.3 m at 090°  GUIDED armed  batt 87%  waiting: Go to waypoint (14 s): leg 2/4: 12.3 m at 090°``"""
    to_go = "" if status["distance_m"] is None else f"  {status['distance_m']:7.1f} m at {status['bearing_deg']:03.0f}°"
    battery = "" if status["battery_pct"] is None else f"  batt {status['battery_pct']}%"
    samples = f"  samples {status['samples']}" if status["samples"] else ""
    energy = status.get("energy")
    if energy is not None:  # left above the reserve; to finish and return, +/- 1 sigma
        battery += f"  energy {energy['has_wh']:.1f}/{energy['need_wh']:.1f}±{energy['sigma_wh']:.1f} Wh"
    armed = "armed" if status["armed"] else "disarmed"
    why = f"  ({status['reason']})" if status["state"] == "PAUSED" and status.get("reason") else ""
    waiting = f"  {waiting_text(status['waiting'])}" if status.get("waiting") and status["state"] == "RUNNING" else ""
    return f"{status['state']:<9} leg {status['leg']}/{status['legs']}{to_go}  {status['mode'] or '-'} {armed}{battery}{samples}{why}{waiting}"
