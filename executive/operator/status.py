"""The executive's status, as the operator sees it: one snapshot of the blackboard.

Shown on the progress line, returned by ``executive ctl status``, written as JSON lines and sent
to the ground station. Battery, position, yaw, pitch/roll, vehicle id and armed come from the
ASV node's 2 Hz status; mode, mission state, leg and distance/bearing from the executive; a sub's
depth and height above the seabed (its downward sonar), a vtol's height above home.
"""

from __future__ import annotations

from typing import Any

import py_trees

from executive.tree.waiting import waiting_text
from executive.world import blackboard, geo
from executive.world.clock import Clock
from executive.world.vehicles import profile_for_mav_type

KEYS = (
    "/mission/state", "/mission/reason", "/mission/leg_index", "/mission/leg_count", "/mission/target", "/mission/samples", "/vehicle/position",
    "/vehicle/attitude", "/vehicle/battery", "/vehicle/mode", "/vehicle/armed", "/link/system_id", "/link/up",
    "/runtime/late_ticks", "/mission/waiting", "/vehicle/mav_type", "/vehicle/altitude_above_bottom_m", "/vehicle/rangefinder",
    "/operator/command", "/link/device_lost", "/runtime/storage_lost", "/base/system", "/base/up", "/energy/estimate",
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
            "link_device_lost": bb.get("/link/device_lost"),
            "storage_lost": bb.get("/runtime/storage_lost"),
            "lat": None if position is None else round(position.lat, 7),
            "lon": None if position is None else round(position.lon, 7),
            "yaw_deg": None if attitude is None else round(attitude.yaw_deg, 1),
            "pitch_deg": None if attitude is None else round(attitude.pitch_deg, 1),
            "roll_deg": None if attitude is None else round(attitude.roll_deg, 1),
            "battery_v": None if battery is None else battery.voltage_v,
            "battery_pct": None if battery is None else battery.remaining_pct,
            **_heights(bb),
            "late_ticks": bb.get("/runtime/late_ticks"),
            "waiting": None if waiting is None else waiting.to_dict(self._clock.now() if self._clock else None),
            "command": bb.get("/operator/command"),  # a person's latest arm, disarm or mode, and the autopilot's answer
            "base": _base(bb),
            "energy": _energy(bb.get("/energy/estimate")),
        }


def _base(bb: py_trees.blackboard.Client) -> dict[str, Any] | None:
    """The AgileX base on CAN (``--can``), once heard: heard now, its state, who it obeys, its battery; None without one."""
    system = bb.get("/base/system")
    if system is None:
        return None
    return {"up": bool(bb.get("/base/up")), "state": system.vehicle_state, "mode": system.control_mode, "battery_v": round(system.battery_v, 1)}


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


def _heights(bb: py_trees.blackboard.Client) -> dict[str, Any]:
    """``depth_m`` and ``altitude_above_bottom_m`` (a sub: None without a good sonar reading, ``seabed_beyond_m`` when the
    seabed is farther than the sonar reaches), ``height_m`` (a vtol, above home): None where not this kind or not known."""
    position, mav_type = bb.get("/vehicle/position"), bb.get("/vehicle/mav_type")
    profile = profile_for_mav_type(mav_type) if mav_type is not None else None
    kind = profile.kind if profile is not None else None
    found: dict[str, Any] = {"depth_m": None, "altitude_above_bottom_m": None, "seabed_beyond_m": None, "height_m": None}
    if position is None:
        return found
    if kind == "sub":
        altitude, reading = bb.get("/vehicle/altitude_above_bottom_m"), bb.get("/vehicle/rangefinder")
        found["depth_m"] = round(max(0.0, -position.alt_rel_m), 2)
        found["altitude_above_bottom_m"] = None if altitude is None else round(altitude, 2)
        found["seabed_beyond_m"] = reading.max_m if reading is not None and reading.status == "too_far" else None
    elif kind == "vtol":
        found["height_m"] = round(position.alt_rel_m, 2)
    return found


def _leg(bb: py_trees.blackboard.Client) -> int:
    return min(bb.get("/mission/leg_index") + 1, bb.get("/mission/leg_count"))


def status_fields(status: dict[str, Any]) -> list[str]:
    """The status line's fields, most important first: a narrow terminal drops them from the end (:func:`fit`).

    A field added to the status goes in at its rank here; nothing else changes for it to fit.
    """
    fields = [f"{status['state']:<9} leg {status['leg']}/{status['legs']}"]
    if status["distance_m"] is not None:
        fields.append(f"{status['distance_m']:7.1f} m at {status['bearing_deg']:03.0f}°")
    if vertical := _vertical(status):
        fields.append(vertical)
    fields.append(f"{status['mode'] or '-'} {'armed' if status['armed'] else 'disarmed'}")
    if status.get("link_device_lost"):
        fields.append(f"LINK: {status['link_device_lost']}")
    if status.get("storage_lost"):
        fields.append(f"DISK: {status['storage_lost']}")
    if status["state"] == "PAUSED" and status.get("reason"):
        fields.append(f"({status['reason']})")
    if refused := _refused(status):
        fields.append(refused)
    if status["battery_pct"] is not None:
        fields.append(f"batt {status['battery_pct']}%")
    if energy := status.get("energy"):  # left above the reserve / to finish and return, +/- 1 sigma
        fields.append(f"energy {energy['has_wh']:.1f}/{energy['need_wh']:.1f}±{energy['sigma_wh']:.1f} Wh")
    if base := status.get("base"):
        fields.append(f"base {base['state']} {base['mode']} {base['battery_v']:.1f}V" + ("" if base["up"] else " (not heard)"))
    if status.get("waiting") and status["state"] == "RUNNING":
        fields.append(waiting_text(status["waiting"]))
    if status["samples"]:
        fields.append(f"samples {status['samples']}")
    return fields


def fit(fields: list[str], width: int | None = None, separator: str = "  ") -> str:
    """``fields`` joined, as many as fit in ``width`` columns from the first (None: all); the first alone is cut to fit."""
    line = fields[0] if width is None or len(fields[0]) <= width else fields[0][: max(width, 0)]
    for field in fields[1:]:
        if width is not None and len(line) + len(separator) + len(field) > width:
            break
        line += separator + field
    return line


def status_line(status: dict[str, Any], width: int | None = None) -> str:
    """``RUNNING   leg 2/4    12.3 m at 090°  GUIDED armed  batt 87%  waiting: Go to waypoint (14 s): leg 2/4: 12.3 m at 090°``

    With ``width``, at most that many characters: the least important fields left out (:func:`status_fields`).
    """
    return fit(status_fields(status), width)


def _vertical(status: dict[str, Any]) -> str:
    """``depth 26.0 m, seabed 24.0 m below`` (a sub), ``height 30.0 m`` (a vtol, above home); empty for others."""
    if status.get("depth_m") is not None:
        if status.get("altitude_above_bottom_m") is not None:
            seabed = f"{status['altitude_above_bottom_m']:.1f} m below"
        elif status.get("seabed_beyond_m") is not None:
            seabed = f"beyond {status['seabed_beyond_m']:g} m"
        else:
            seabed = "no sonar reading"
        return f"depth {status['depth_m']:.1f} m, seabed {seabed}"
    if status.get("height_m") is not None:
        return f"height {status['height_m']:.1f} m"
    return ""


#: How long (vehicle time) the status line says that the autopilot refused a person's command.
REFUSAL_SHOWN_S = 30.0


def _refused(status: dict[str, Any]) -> str:
    """``ctl: mode POSCTL refused by the autopilot (TEMPORARILY_REJECTED)`` for :data:`REFUSAL_SHOWN_S` after the answer."""
    command = status.get("command")
    if not command or not command.get("refused"):
        return ""
    if status.get("t") is not None and status["t"] - command["t"] > REFUSAL_SHOWN_S:
        return ""
    return f"{command['by']}: {command['what']} {command['answer']}"
