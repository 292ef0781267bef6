"""The autopilot port: behaviours and trees depend on it, never on MAVLink; the back end follows the heartbeat."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from executive.autopilot.ardupilot import ArduPilotPort
from executive.autopilot.mavlink_port import SameAnswer
from executive.autopilot.port import AutopilotPort
from executive.autopilot.px4 import Px4Port
from executive.autopilot.selection import Autopilot
from executive.io.mavlink.mission_protocol import horizon_not_on_autopilot, route_items, route_not_on_autopilot
from executive.mission.model import Waypoint
from executive.world.dialect import mavlink
from executive.world.vehicles import PROFILES

ROOT = Path(__file__).resolve().parents[2]
FORBIDDEN = ("executive.io.mavlink", "pymavlink", "executive.io.mavlink.modes", "executive.autopilot.selection")


def _imports(path: Path) -> list[str]:
    names = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.append(node.module)
    return names


@pytest.mark.parametrize("path", sorted([*(ROOT / "executive" / "behaviours").glob("*.py"), *(ROOT / "trees").glob("*.py")]), ids=lambda p: p.name)
def test_behaviours_and_trees_import_nothing_from_mavlink(path: Path) -> None:
    bad = [name for name in _imports(path) if name.startswith(FORBIDDEN)]
    assert bad == [], f"{path.name} imports {bad}"


def test_route_keeper_does_not_import_behaviours() -> None:
    names = _imports(ROOT / "executive" / "autopilot_link" / "route_keeper.py")
    assert not [n for n in names if n.startswith("executive.behaviours")]


def test_the_heartbeat_picks_the_back_end(commander) -> None:
    port = Autopilot(commander, None, PROFILES["vtol"])
    assert port.capabilities.autopilot == "ardupilot"
    assert port.capabilities.safe_mode == "QLOITER"
    port.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_VTOL_QUADROTOR)
    assert port.capabilities.autopilot == "px4"
    assert (port.capabilities.safe_mode, port.capabilities.guided_mode, port.capabilities.route_mode) == ("AUTO.LOITER", "OFFBOARD", "AUTO.MISSION")
    assert port.mode_name("QLOITER") == "AUTO.LOITER"


def test_a_forced_back_end_stays_whatever_the_heartbeat_says(commander) -> None:
    port = Autopilot(commander, None, PROFILES["vtol"], forced="px4")
    assert port.mode_name("GUIDED") == "OFFBOARD"
    port.adopt(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, mavlink.MAV_TYPE_VTOL_QUADROTOR)
    assert port.capabilities.autopilot == "px4"
    assert port.mode_name("GUIDED") == "OFFBOARD"


def test_every_intent_of_the_port_is_the_back_end_s_before_and_after_the_heartbeat_swaps_it(commander) -> None:
    port = Autopilot(commander, None, PROFILES["vtol"])
    members = [name for name in vars(AutopilotPort) if not name.startswith("_")]
    for backend in ("ardupilot", "px4"):
        if backend == "px4":
            port.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_VTOL_QUADROTOR)
        assert port.backend.name == backend
        for name in members:
            assert getattr(port, name) == getattr(port.backend, name), name  # the back end's own bound method or value, not a copy
    with pytest.raises(AttributeError, match="'Autopilot' object has no attribute '_transfer_state'"):
        port._transfer_state  # noqa: B018  # a back end's own state is not reached through the selection


def test_a_back_end_set_directly_has_its_own_intents_called_none_of_the_one_before(commander) -> None:
    """The selection binds a back end's methods when it is set (by adopt, or assigned): a swapped one leaves none behind."""
    port = Autopilot(commander, None, PROFILES["vtol"])
    members = [name for name in vars(AutopilotPort) if not name.startswith("_")]
    for backend in (Px4Port(commander, None, PROFILES["vtol"]), ArduPilotPort(commander, None, PROFILES["vtol"])):
        port.backend = backend
        for name in members:
            assert getattr(port, name) == getattr(backend, name), name


ROUTE = (Waypoint(lat=44.0951, lon=9.8630), Waypoint(lat=44.0952, lon=9.8631))


def test_the_route_is_compared_again_only_when_the_waypoints_or_the_items_held_are_other_objects() -> None:
    """The same objects give the same answer without a comparison; other ones (an edited waypoint, items read back again,
    another leg) are compared; held items that may change (a list) are compared every time."""
    compared: list[int] = []

    def compare(waypoints, *args):
        compared.append(len(waypoints))
        return horizon_not_on_autopilot(waypoints, *args) if len(args) == 3 else route_not_on_autopilot(waypoints, *args)

    route_differs, horizon_differs = SameAnswer(compare), SameAnswer(compare)
    held = route_items(ROUTE)
    moved = (ROUTE[0], ROUTE[1].model_copy(update={"lat": 44.0953}))
    moved_away = "the autopilot's mission differs (item 2 x (latitude): sent 44.0953000, the vehicle holds 44.0952000)"
    assert route_differs(ROUTE, held) is None
    assert route_differs(list(ROUTE), held) is None  # the same waypoints in another sequence
    assert [route_differs(moved, held), route_differs(moved, held)] == [moved_away, moved_away]
    assert route_differs(moved, route_items(moved)) is None
    assert route_differs(moved, None) == "the autopilot's mission is not known yet"
    assert len(compared) == 4
    listed = list(held)
    assert route_differs(ROUTE, listed) is None
    listed.pop()
    assert route_differs(ROUTE, listed) == "the autopilot's mission differs (the vehicle holds 1 items, 2 were sent)"
    assert len(compared) == 6
    first = held[:1]
    assert [horizon_differs(ROUTE, leg, 0, first) for leg in (0, 0, 1)] == [None, None, "the vehicle holds 1 items, 2-2 are the horizon of leg 2"]
    assert len(compared) == 8
