"""A recorded .tlog played back through the executive's MAVLink reader, the autopilot port and the intervention watch.

What the autopilot sent goes into the reader at its recorded time (the clock follows the tlog's
timestamps); what the executive sent is asked again of the autopilot port (a mode, a take-off, a
reposition), so that the port and the commander know what "we" asked, as in the recorded run. The
port's own queued commands go nowhere. Nothing here needs the firmware: CI keeps our reading of the
real firmware honest with the recording alone.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from executive.autopilot.port import Target
from executive.autopilot.selection import Autopilot
from executive.io.mavlink.commander import Commander
from executive.io.mavlink.mission_protocol import MissionTransfer
from executive.io.mavlink.reader import MavlinkReader
from executive.mission.lifecycle import MissionState
from executive.mission.model import Mission, RcConfig
from executive.operator.intervention import InterventionWatch
from executive.testing import FakeLink
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.dialect import EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink
from executive.world.state import HomePosition
from executive.world.vehicles import PROFILES, AutopilotName

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

DATA = Path(__file__).resolve().parent / "data"
PX4 = DATA / "px4"
AUTOPILOT_COMPONENT = 1


def records(path: Path) -> Iterator[tuple[float, MAVLinkMessage]]:
    """(recorded time in s, message) for each message of a .tlog, both directions, in order."""
    yield from _parsed(Path(path).resolve())


@functools.lru_cache(maxsize=8)
def _parsed(path: Path) -> tuple[tuple[float, MAVLinkMessage], ...]:
    """A .tlog's messages, parsed once for the tests of a process that play it (pymavlink's parser took ~4 CPU-s of the recorded
    tests' for ~200 reads of ~60 files; a file's messages are ~1 kB each). Nothing that reads them changes a message."""
    conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega", robust_parsing=True)
    try:
        return tuple((msg._timestamp, msg) for msg in iter(conn.recv_msg, None) if msg.get_type() != "BAD_DATA")
    finally:
        conn.close()


def through_reader(path: Path, vehicle: str) -> Iterator[MAVLinkMessage]:
    """The recording's vehicle side fed to a fresh reader and mission transfer at its recorded times: each autopilot message is
    yielded once the reader has put it on the blackboard (reset it before)."""
    clock, link = ManualClock(), FakeLink()
    reader = MavlinkReader(link, clock, Commander(link, clock, PROFILES[vehicle]), mission=MissionTransfer(link, clock), link_timeout_s=5.0)
    t0: float | None = None
    for t, msg in records(path):
        if msg.get_srcComponent() != AUTOPILOT_COMPONENT:
            continue
        t0 = t if t0 is None else t0
        if t - t0 > clock.now():
            clock.advance(t - t0 - clock.now())
        link.incoming.append(msg)
        reader.drain()
        yield msg


@dataclass
class Replay:
    """The executive's reading side (its mission transfer too: MISSION_CURRENT, MISSION_ITEM_REACHED), fed a recording;
    ``seen`` keeps each change of a watched blackboard key, with its time."""

    vehicle: str = "vtol"
    clock: ManualClock = field(default_factory=ManualClock)
    link: FakeLink = field(default_factory=FakeLink)
    watch: tuple[str, ...] = (
        "/vehicle/mode", "/vehicle/mode_set_by", "/vehicle/armed", "/vehicle/landed_state", "/vehicle/vtol_state", "/vehicle/statustext",
    )  # fmt: skip
    seen: list[tuple[float, str, object]] = field(default_factory=list)
    #: Commands of ours not asked again (to see what the autopilot does by itself): MAV_CMD numbers.
    unasked: frozenset[int] = frozenset()
    #: Judge mode changes as this firmware's whatever the heartbeat says (a control: another firmware's rules); None: the heartbeat's.
    judged_as: AutopilotName | None = None

    def __post_init__(self) -> None:
        blackboard.reset()
        profile = PROFILES[self.vehicle]
        self.commander = Commander(self.link, self.clock, profile)
        self.port = Autopilot(self.commander, None, profile)
        self.reader = MavlinkReader(self.link, self.clock, self.commander, mission=MissionTransfer(self.link, self.clock), link_timeout_s=5.0)
        self.reader.on_autopilot = self.port.adopt
        self.state = MissionState()
        fields = {
            "version": 1,
            "name": "replay",
            "vehicle": self.vehicle,
            "waypoints": [{"lat": 0.0, "lon": 0.0}],
            "limits": {"acceptance_radius_m": 100},
        }
        mission = Mission.model_validate(fields)  # a mission running, so that a person's change would pause it
        self.state.upload(mission)
        self.state.start()
        self.intervention = InterventionWatch(self.clock, self.port, self.state, profile, RcConfig(), firmware=self._firmware)
        self.bb = blackboard.reader("tlog replay", [*self.watch, "/vehicle/home", "/vehicle/position", "/vehicle/ekf"])
        self._last: dict[str, object] = {}
        self._t0: float | None = None

    def _firmware(self) -> AutopilotName:
        return self.judged_as or self.port.backend.name  # type: ignore[return-value]

    def play(self, path: Path, until_s: float | None = None) -> Replay:
        """Feed the recording (up to ``until_s`` after its first record); the clock starts at its first record."""
        self._recorded_home = next((home for _, home in records(path) if home.get_type() == "HOME_POSITION"), None)
        for t, msg in records(path):
            if self._t0 is None:
                self._t0 = t
            now = t - self._t0
            if until_s is not None and now > until_s:
                break
            if now > self.clock.now():
                self.clock.advance(now - self.clock.now())
            if msg.get_srcComponent() == EXECUTIVE_COMPONENT:
                self._ours(msg)
            elif msg.get_srcComponent() == AUTOPILOT_COMPONENT:
                self.link.incoming.append(msg)
                self.reader.drain()
                self.intervention.service()
                self._note()
        return self

    def _ours(self, msg: MAVLinkMessage) -> None:
        """What the executive asked, asked again of the port (its notes of the modes we asked for are what matter)."""
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT") and msg.command in self.unasked:
            return
        home: HomePosition | None = self.bb.get("/vehicle/home")
        if home is None and self._recorded_home is not None:  # a cut recording may start before PX4's next HOME_POSITION
            recorded = self._recorded_home
            home = HomePosition(recorded.latitude * 1e-7, recorded.longitude * 1e-7, recorded.altitude * 1e-3, 0.0)
        if kind == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            main, sub = int(msg.param2), int(msg.param3)
            self.port.set_mode(self.commander.modes.decode((main << 16) | (sub << 24) if self.port.backend.name == "px4" else main))
        elif kind == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_NAV_TAKEOFF:
            height = msg.param7 - home.alt_m if home is not None and self.port.backend.name == "px4" else msg.param7
            self.port.take_off(height, home=home, position=self.bb.get("/vehicle/position"), airborne=False)
        elif kind == "COMMAND_INT" and msg.command == mavlink.MAV_CMD_DO_REPOSITION:
            self.port.reposition(msg.x * 1e-7, msg.y * 1e-7, msg.z - (home.alt_m if home is not None else 0.0))
        elif kind == "SET_POSITION_TARGET_GLOBAL_INT":
            self.port.go_to(Target(msg.lat_int * 1e-7, msg.lon_int * 1e-7, msg.alt))
        self.link.take()  # the port's commands go nowhere

    def _note(self) -> None:
        for key in self.watch:
            value = self.bb.get(key)
            if key not in self._last or self._last[key] != value:
                self._last[key] = value
                self.seen.append((self.clock.now(), key, value))

    def values(self, key: str) -> list[object]:
        """Each value ``key`` took, in order."""
        return [value for _, k, value in self.seen if k == key]

    def when(self, key: str, value: object) -> float:
        """The replay time ``key`` first took ``value``."""
        return next(t for t, k, v in self.seen if k == key and v == value)

    def last_when(self, key: str, value: object) -> float:
        """The replay time ``key`` last took ``value``."""
        return max(t for t, k, v in self.seen if k == key and v == value)
