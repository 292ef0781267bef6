"""drive: auto on a sub: its waypoints given to ArduSub's AUTO at their depths, never deeper than the seabed floor.

ArduSub's AUTO flies a NAV_WAYPOINT in the relative-altitude frame at that altitude above home, negative
below the surface (ArduSub/commands_logic.cpp start_command refuses a positive one: "Alt above home must
be negative"), straight to the point in 3-D, and counts it reached within WPNAV_RADIUS (default 2 m) in
3-D, position and depth (libraries/AC_WPNav/AC_WPNav.cpp advance_wp_target_along_track; ArduSub gives
its waypoint navigation no next waypoint, so every waypoint is a stop). It does not guard the seabed
under a depth item: so the executive bounds every depth it gives by the seabed floor
(:func:`executive.world.seabed.depth_floor`), as GUIDED bounds its depth targets.

ArduSub has no mission change detection (ArduRover's AP_Mission_ChangeDetector is not used): an item
rewritten while AUTO flies it is flown as it was read when it started (AP_Mission::update runs the
cached ``_nav_cmd``). A current leg whose depth the floor raised is therefore started again at its new
item, by MISSION_SET_CURRENT (AP_Mission::set_current_cmd, running: advance_current_nav_cmd starts it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

from py_trees.common import Status

from executive.behaviours.auto_legs import HorizonOnAutopilot
from executive.behaviours.auto_route import AUTO
from executive.behaviours.base import FAILURE, SUCCESS
from executive.behaviours.motion import seabed_log
from executive.mission.model import Waypoint
from executive.world.seabed import Floor, depth_floor
from executive.world.state import GlobalPosition

#: A depth given is kept while it is no deeper than the floor and at most this much shallower than the floor now allows:
#: the floor moves with every sonar reading, a mission write does not.
FLOOR_SLACK_M = 1.0
#: Two item depths this close are the same (ArduPilot keeps an altitude to the centimetre).
DEPTH_SAME_M = 0.011


class DepthsOnAutopilot(HorizonOnAutopilot):
    """:class:`HorizonOnAutopilot` for a sub: each waypoint given at its depth, no deeper than the seabed floor.

    A waypoint's depth is given as the floor allows when it is put on the autopilot (a warning, a
    journal event ``seabed``, the first time the floor holds one) and kept while it is no deeper than the
    floor and not more than :data:`FLOOR_SLACK_M` shallower than the floor now allows: the horizon is
    written again when it must (raised half the slack above the floor). The current leg, so changed while
    AUTO flies it, is started again at its new item: a dive toward a seabed beyond the sonar's reach goes
    down in steps of about the slack, as GUIDED's ChangeDepth does, until the sonar reads it. With
    ``too_deep: fail`` (``limits.seabed_floor``), a leg the measured seabed holds shallower than its depth
    fails, as GUIDED's ChangeDepth does.
    """

    reads = (*HorizonOnAutopilot.reads, "/vehicle/position", "/vehicle/rangefinder", "/vehicle/mode")
    from_mission = {**HorizonOnAutopilot.from_mission, "clearance_m": "limits.altitude_m.min", "too_deep": "limits.seabed_floor"}
    param_docs = {
        **HorizonOnAutopilot.param_docs,
        "clearance_m": "never closer to the seabed than this, as the sonar reads it",
        "too_deep": "a depth the water cannot hold: hold (at the floor) or fail",
    }

    def __init__(
        self, horizon_legs: int = 2, clearance_m: float = 2.0, too_deep: Literal["hold", "fail"] = "hold", name: str = "Horizon on the autopilot"
    ) -> None:
        super().__init__(horizon_legs, name)
        self.clearance_m = clearance_m
        self.too_deep = too_deep
        self._given: dict[int, tuple[float, float]] = {}  # waypoint index -> (its depth, the depth given)
        self._flown: tuple[int, float] | None = None  # in AUTO: (the leg, the depth of the item AUTO began it with)
        self._told: set[int] = set()
        self._floor: Floor | None = None

    def given_route(self) -> Sequence[Waypoint]:
        route = self.mission_state.route.waypoints
        position: GlobalPosition | None = self.get("/vehicle/position")
        floor = None if position is None else depth_floor(-position.alt_rel_m, self.get("/vehicle/rangefinder"), self.clearance_m, self.clock.now())
        self._floor = floor
        given = []
        for i, wp in enumerate(route):
            wanted = wp.depth_m or 0.0
            allowed = wanted if floor is None else min(wanted, math.floor(floor.depth_m * 10) / 10)
            kept = self._given.get(i)
            if kept is not None and kept[0] == wanted and i < self.mission_state.leg_index:  # a leg done: its item stays as flown
                given.append(wp.model_copy(update={"depth_m": kept[1], "control_mode": "depth"}))
                continue
            held = allowed < wanted and kept is not None and kept[0] == wanted and allowed - FLOOR_SLACK_M <= kept[1] <= allowed
            depth = kept[1] if held and kept is not None else allowed
            # the floor rose above it: half the slack above the floor, not rewritten at each reading
            if kept is not None and kept[0] == wanted and depth < kept[1]:
                depth = max(0.0, round(allowed - FLOOR_SLACK_M / 2, 1))
            self._given[i] = (wanted, depth)
            if depth < wanted and i not in self._told and floor is not None:
                self._told.add(i)
                seabed_log.warning(
                    "%s: waypoint %d's depth %g m given at %.1f m: %s, %g m above it (limits.altitude_m.min)",
                    self.name, i + 1, wanted, depth, floor.why, self.clearance_m,
                )  # fmt: skip
            given.append(wp.model_copy(update={"depth_m": depth, "control_mode": "depth"}))
        return given

    def update(self) -> Status:
        leg = self.mission_state.leg_index
        held = self._held_depth(leg)
        if self.get("/vehicle/mode") != self.autopilot.mode_name(AUTO) or held is None:
            self._flown = None  # AUTO (re)starts the leg at the item it then holds
        elif self._flown is None or self._flown[0] != leg:
            self._flown = (leg, held)
        elif abs(held - self._flown[1]) > DEPTH_SAME_M and not self._settle() and self._may_start():
            # its item rewritten (the floor moved) since AUTO began it: before anything else is written, flown as it now is
            self._flown = (leg, held)
            self._started(self.autopilot.set_route_leg(leg))
            self.feedback_message = f"leg {leg + 1} started again at {held:g} m (the seabed floor moved)"
            return SUCCESS
        status = super().update()
        wanted = self._given.get(leg, (0.0, 0.0))[0]
        floor = self._floor
        if self.too_deep == "fail" and floor is not None and floor.kind == "seabed" and floor.depth_m < wanted:
            self.feedback_message = f"depth {wanted:g} m deeper than the water holds: {floor.why} (limits.seabed_floor: fail)"
            seabed_log.warning("%s: %s", self.name, self.feedback_message)
            return FAILURE
        return status

    def _held_depth(self, leg: int) -> float | None:
        """The depth of the item the autopilot holds (read back) for leg ``leg``; None when it holds none."""
        held = self.get("/vehicle/mission_items")
        return -held[leg].z if held is not None and leg < len(held) else None
