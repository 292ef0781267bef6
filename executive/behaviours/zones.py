"""Pre-flight: the mission's zones and rally points on the autopilot (its fence and rally items, read back), its own fence switched on.

``geofence.autopilot: upload`` (the default) sends the fence (``polygon``, ``inclusion`` and
``keep_out`` shapes) and the rally points with the MAVLink mission protocol and reads each back item
by item before it counts, so a ground station shows them and the firmware's own RTL knows the rally
points; the autopilot's fence parameters are read and said, not changed. ``enforce`` also sets them
(:meth:`~executive.autopilot.port.AutopilotPort.fence_settings`), read back, and leaves them set after
the mission: the vehicle stays protected when the executive is gone. A refusal (the firmware's NAK, a
read-back that differs, a parameter it will not take) fails the pre-flight naming the zone, before
anything is armed.
"""

from __future__ import annotations

import logging
import math
import re

from py_trees.common import Status

from executive.autopilot.fence import ZoneItems, fence_items, inclusion_shapes, rally_items
from executive.behaviours.auto_route import MissionTransferFollower
from executive.behaviours.base import FAILURE, RUNNING, SUCCESS
from executive.mission.model import GeofenceConfig, Mission, RallyPoint
from executive.world.clock import Clock
from executive.world.dialect import mavlink
from executive.world.state import MissionTransferStatus

log = logging.getLogger(__name__)

_ITEM = re.compile(r"\bitem (\d+)\b")
#: A parameter read back within this of the value set holds it (FENCE_RADIUS is a float32).
_PARAM_TOLERANCE = 1e-3


def _same(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=_PARAM_TOLERANCE, abs_tol=_PARAM_TOLERANCE)


def puts_zones_on_autopilot(mission: Mission) -> bool:
    """Whether the mission's pre-flight puts zones or rally points on the autopilot (``geofence.autopilot`` not ``off``, and it has some)."""
    geofence = mission.geofence
    shapes = geofence is not None and (geofence.polygon is not None or bool(geofence.inclusion) or bool(geofence.keep_out))
    enforce = geofence is not None and geofence.autopilot == "enforce"  # max_distance_from_home_m alone is the fence's circle
    return not (geofence is not None and geofence.autopilot == "off") and (shapes or bool(mission.rally_points) or enforce)


class ZonesOnAutopilot(MissionTransferFollower):
    """SUCCESS once the fence and the rally points are on the autopilot, read back (and, with ``enforce``, its fence switched on).

    ``clear_fence``, ``clear_rally``: an empty fence or rally list is sent too (a replacing mission without
    what the mission before it put there, :mod:`executive.autopilot_link.replaced_zones`).

    FAILURE, nothing armed, when the autopilot refuses an item (naming the zone it belongs to, and
    what the autopilot said), reads back something else, will not take a parameter, or it is not all
    done within ``timeout_s``.
    """

    reads = ("/link/mission_transfer", "/vehicle/fence_items", "/vehicle/rally_items", "/vehicle/params", "/vehicle/statustext")
    clock: Clock

    def __init__(
        self,
        geofence: GeofenceConfig | None,
        rally_points: list[RallyPoint],
        *,
        clear_fence: bool = False,
        clear_rally: bool = False,
        timeout_s: float = 60.0,
        ask_every_s: float = 1.0,
        name: str = "Zones and rally points on the autopilot",
    ) -> None:
        super().__init__(name, retry_s=ask_every_s)
        self.enforce = geofence is not None and geofence.autopilot == "enforce"
        self.radius_m = geofence.max_distance_from_home_m if geofence is not None else None
        self.inclusions = inclusion_shapes(geofence)
        self.uploads: list[tuple[str, int, ZoneItems]] = [
            (what, mission_type, zone_items)
            for what, mission_type, zone_items, clear in (
                ("fence", mavlink.MAV_MISSION_TYPE_FENCE, fence_items(geofence), clear_fence),
                ("rally points", mavlink.MAV_MISSION_TYPE_RALLY, rally_items(rally_points), clear_rally),
            )
            if zone_items.items or clear
        ]
        self.timeout_s, self.ask_every_s = timeout_s, ask_every_s

    def initialise(self) -> None:
        super().initialise()
        self._began = self.clock.now()
        self._asked_at = self._set_at = float("-inf")
        self._told = False
        self._set_told: set[str] = set()

    def update(self) -> Status:
        refused = self.autopilot.fence_settings(radius_m=self.radius_m, inclusion_shapes=self.inclusions, held={}).refused
        if refused and (self.enforce or self.autopilot.capabilities.autopilot == "px4"):  # PX4 acts on any fence it holds
            self.feedback_message = f"not sent to the autopilot: {refused}"
            return FAILURE
        if self.clock.now() - self._began > self.timeout_s:
            self.feedback_message = f"not done within {self.timeout_s:g} s: {self.feedback_message}"
            return FAILURE
        if self._settle():
            status: MissionTransferStatus = self.get("/link/mission_transfer")
            step = "reading back" if status.verifying else "sending"
            self.feedback_message = f"{step} {status.progress}/{status.total} items"
            return RUNNING
        for what, mission_type, zone_items in self.uploads:
            key = "/vehicle/fence_items" if mission_type == mavlink.MAV_MISSION_TYPE_FENCE else "/vehicle/rally_items"
            if self._holds(zone_items, self.get(key)):
                continue
            if self.failure:
                self.feedback_message = self._refusal(what, zone_items, self.failure)
                return FAILURE
            if not self.autopilot.route_transfer_idle:
                self.feedback_message = "waiting for another mission transfer to end"
                return RUNNING
            self._started(self.autopilot.upload_zones(zone_items.items, mission_type))
            self.feedback_message = f"sending the {what}: {len(zone_items.items)} items ({', '.join(zone_items.shapes())})"
            return RUNNING
        return self._fence_parameters()

    def _holds(self, zone_items: ZoneItems, held: object) -> bool:
        return held is not None and self.autopilot.zones_differ(zone_items.items, held) is None

    def _refusal(self, what: str, zone_items: ZoneItems, reason: str) -> str:
        found = _ITEM.search(reason)
        where = f" ({zone_items.source_of(int(found.group(1)))})" if found else f" ({', '.join(zone_items.shapes())})"
        text = self.get("/vehicle/statustext")  # its last warning explains a refusal ("Fence validation failed", "Only 84 items ...")
        said = f"; the autopilot said '{text[1]}'" if text and text[0] <= mavlink.MAV_SEVERITY_WARNING else ""
        return f"the autopilot did not take the {what}{where}: {reason}{said}"

    def _fence_parameters(self) -> Status:
        """The fence parameters read (and with ``enforce`` set and read back): SUCCESS once they are."""
        names = self.autopilot.capabilities.fence_params
        held = {name: value for name, value in (self.get("/vehicle/params") or {}).items() if name in names}
        missing = [name for name in names if name not in held]
        wanted = self.autopilot.fence_settings(radius_m=self.radius_m, inclusion_shapes=self.inclusions, held=held) if self.enforce else None
        if wanted is not None and wanted.refused:
            self.feedback_message = f"not enforced: {wanted.refused}"
            return FAILURE
        to_set = {} if wanted is None else {n: v for n, v in wanted.params.items() if n not in held or not _same(held[n], v[0])}
        if not missing and not to_set:
            done = ", ".join(f"{n} {held[n]:g}" for n in names)
            self.feedback_message = f"on the autopilot, read back: {self._sent()}; its fence: {done}" + ("" if self.enforce else " (not changed)")
            if not self._told:
                log.info("%s", self.feedback_message)
                self._told = True
            return SUCCESS
        now = self.clock.now()
        if missing and now - self._asked_at >= self.ask_every_s:
            self._asked_at = now
            for name in missing:
                self.autopilot.read_parameter(name)
        settable = {n: v for n, v in to_set.items() if n in held}  # what it holds is said before it is changed
        if settable and now - self._set_at >= self.ask_every_s:
            self._set_at = now
            for name, (value, param_type) in settable.items():
                if name not in self._set_told:
                    self._set_told.add(name)
                    log.info("geofence.autopilot enforce: %s %g -> %g", name, held[name], value)
                self.autopilot.set_parameter(name, value, param_type)
        if missing:
            self.feedback_message = f"reading the autopilot's fence parameters: {', '.join(missing)}"
        else:
            self.feedback_message = "setting " + ", ".join(f"{n} {held[n]:g} -> {v:g}" for n, (v, _) in to_set.items())
        return RUNNING

    def _sent(self) -> str:
        return ", ".join(f"{what} {len(z.items)} items" for what, _, z in self.uploads) or "nothing"
