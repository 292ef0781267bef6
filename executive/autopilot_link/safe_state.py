"""Where making the vehicle safe leaves it, by its kind and what it is doing, and when it is there.

- A sub surfaces: an AUV waiting under water is out of everyone's reach. SURFACE climbs and, at the
  surface, the firmware holds the depth there in ALT_HOLD itself (``ArduSub/mode_surface.cpp``,
  ModeReason::SURFACE_COMPLETE); then POSHOLD keeps it where it came up: ``surfaced, holding position,
  armed``. A sub at the surface already is held there in POSHOLD.
- A VTOL below the height its firmware flies the last metres of a landing from (ArduPlane's
  Q_LAND_FINAL_ALT, 6 m, ``ArduPlane/quadplane.cpp``; PX4's MPC_LAND_ALT2, 5 m,
  ``src/modules/mc_pos_control/multicopter_takeoff_land_params.c``), landing, or armed on the ground,
  lands rather than hover there: QLAND (AUTO.LAND on PX4), until landed and disarmed (ArduPlane
  disarms once QuadPlane::check_land_complete's land detector is sure, 4 s; PX4's commander after
  COM_DISARM_LAND, 2 s, ``commander/Commander.cpp`` handleAutoDisarm).
- Rovers, boats, a VTOL higher up, and a disarmed sub or VTOL (the executive never arms a vehicle to
  make it safe): the safe mode as before (HOLD, LOITER, QLOITER or AUTO.LOITER), made once the
  heartbeat shows it.

A failsafe of the mission that left the vehicle in a mode of its own (RTL, QRTL, SURFACE) is not undone;
only a hold is replaced by the phase's plan. Waiting for the safe state is bounded (:meth:`SafePlan.bound_s`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

from executive.autopilot.mode_cause import SUB_AT_SURFACE_M
from executive.world.state import GlobalPosition

Read = Callable[[str], object]

#: The height (m above home) below which a VTOL lands rather than hover, per firmware: where its own landing slows for the
#: last metres (ArduPlane Q_LAND_FINAL_ALT 6 m, ArduPlane/quadplane.cpp; PX4 MPC_LAND_ALT2 5 m, multicopter_takeoff_land_params.c).
LAND_BELOW_M = {"ardupilot": 6.0, "px4": 5.0}
#: The slowest the firmware climbs to the surface or descends to land, m/s: the bound on the wait (ArduSub's SURFACE climbs at
#: WPNAV_SPEED_UP, at most PILOT_SPEED_UP; ArduPlane's final descent is Q_LAND_FINAL_SPD, 0.5 m/s; PX4's MPC_LAND_SPEED, 0.7 m/s).
SLOWEST_M_S = 0.5
#: Added to the wait: the land detector (ArduPlane 4 s, PX4 ~2 s and COM_DISARM_LAND 2 s), the heartbeat, a round trip, a wave.
SETTLE_MARGIN_S = 30.0
#: The mode ArduSub goes on to by itself once SURFACE reaches the surface (ArduSub/mode_surface.cpp, ModeReason::SURFACE_COMPLETE).
SURFACE_COMPLETE_MODE = "ALT_HOLD"
#: The modes that only hold the vehicle where it is, per kind (the trees' names): replaced by the phase's plan.
_HOLDS = {"sub": frozenset({"POSHOLD", "ALT_HOLD"}), "vtol": frozenset({"QLOITER", "LOITER"})}


class Until(StrEnum):
    """What the make-safe waits for once the heartbeat shows the mode asked."""

    SHOWN = "shown"  # nothing more
    SURFACED = "surfaced"
    LANDED = "landed and disarmed"


@dataclass(frozen=True)
class SafePlan:
    """The reaction to ask first, what to wait for after it, and why (None: the vehicle's usual safe mode)."""

    mode: str
    until: Until = Until.SHOWN
    why: str | None = None
    then: str | None = None  # the mode asked once the safe state is reached (POSHOLD at the surface)
    distance_m: float = 0.0  # how far it has to go (depth, height), for the bound

    def bound_s(self) -> float:
        """How long the wait for the safe state may take: the distance at the firmware's slowest rate, and a margin."""
        return SETTLE_MARGIN_S + self.distance_m / SLOWEST_M_S


def plan(kind: str, firmware: str, asked: str | None, safe_mode: str, read: Read) -> SafePlan:
    """Where to leave a ``kind`` vehicle on ``firmware``, now: ``asked`` is a failsafe's mode (None: none), ``safe_mode`` the usual one."""
    mode = asked or safe_mode
    if asked is not None and asked not in _HOLDS.get(kind, ()) and not (kind == "sub" and asked == "SURFACE"):
        return SafePlan(mode)  # RTL, QRTL, QLAND...: the mission's failsafe chose it
    if not read("/vehicle/armed"):
        return SafePlan(mode)  # nothing moves it (a disarmed sub floats up at its buoyancy); the executive never arms it to make it safe
    position: GlobalPosition | None = read("/vehicle/position")  # type: ignore[assignment]
    height = position.alt_rel_m if position is not None else None
    if kind == "sub":
        if height is not None and height >= SUB_AT_SURFACE_M:
            return SafePlan("POSHOLD", why=f"at the surface (depth {-height:.1f} m): held there")
        depth = f"depth {-height:.1f} m" if height is not None else "depth unknown"
        why = f"an AUV is made safe at the surface ({depth}): SURFACE, then POSHOLD there (ArduSub/mode_surface.cpp)"
        return SafePlan("SURFACE", Until.SURFACED, why, then="POSHOLD", distance_m=-height if height is not None else 100.0)
    if kind == "vtol":
        low = LAND_BELOW_M.get(firmware, 6.0)
        landed_state = read("/vehicle/landed_state")
        if landed_state == "LANDING":
            why = "landing: it lands rather than hover"
        elif landed_state == "ON_GROUND":
            why = "armed on the ground: it lands (and disarms) rather than take off to hover"
        elif height is not None and height < low:
            why = f"at {height:.1f} m, below the {low:g} m its firmware lands the last metres from: it lands rather than hover"
        else:
            return SafePlan(mode)
        return SafePlan("QLAND", Until.LANDED, why, distance_m=max(height or 0.0, 0.0))
    return SafePlan(mode)


def settled(plan: SafePlan, read: Read) -> bool:
    """The vehicle is in the safe state ``plan`` waits for (once the heartbeat has shown its mode)."""
    if plan.until is Until.SURFACED:  # ArduSub's own word (SURFACE_COMPLETE: ALT_HOLD, at SURFACE_DEPTH -10 cm), and the depth agrees
        position: GlobalPosition | None = read("/vehicle/position")  # type: ignore[assignment]
        return read("/vehicle/mode") == SURFACE_COMPLETE_MODE and position is not None and position.alt_rel_m >= SUB_AT_SURFACE_M
    if plan.until is Until.LANDED:
        return not read("/vehicle/armed") and read("/vehicle/landed_state") in (None, "ON_GROUND")
    return True


def progress(plan: SafePlan, read: Read) -> str:
    """How far the vehicle is from the safe state: ``depth 12.3 m``, ``height 1.2 m, armed``."""
    position: GlobalPosition | None = read("/vehicle/position")  # type: ignore[assignment]
    if position is None:
        return "no position report"
    if plan.until is Until.SURFACED:
        return f"depth {max(-position.alt_rel_m, 0.0):.1f} m, in {read('/vehicle/mode')}"
    landed = read("/vehicle/landed_state")
    return (
        f"height {position.alt_rel_m:.1f} m"
        + (f", {str(landed).lower().replace('_', ' ')}" if landed else "")
        + (", armed" if read("/vehicle/armed") else ", disarmed")
    )


def where(kind: str, mode: str | None, read: Read) -> str:
    """Where the vehicle is left, for a person: ``surfaced, holding position, armed``; ``landed, disarmed``."""
    armed = "armed" if read("/vehicle/armed") else "disarmed"
    position: GlobalPosition | None = read("/vehicle/position")  # type: ignore[assignment]
    if kind == "sub":
        depth = None if position is None else -position.alt_rel_m
        place = (
            "surfaced" if depth is not None and depth <= -SUB_AT_SURFACE_M else (f"at {depth:.1f} m depth" if depth is not None else "depth unknown")
        )
        hold = {"POSHOLD": "holding position", "ALT_HOLD": "holding depth", "SURFACE": "surfacing"}.get(mode or "", f"in {mode}")
        return f"{place}, {hold}, {armed}"
    if kind == "vtol" and read("/vehicle/landed_state") == "ON_GROUND":
        return f"landed, {armed}"
    if kind == "vtol" and position is not None:
        return f"at {position.alt_rel_m:.1f} m, in {mode}, {armed}"
    return f"in {mode}, {armed}"
