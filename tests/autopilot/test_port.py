"""The autopilot port: behaviours and trees depend on it, never on MAVLink; the back end follows the heartbeat."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from executive.autopilot.port import AutopilotPort
from executive.autopilot.selection import Autopilot
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
