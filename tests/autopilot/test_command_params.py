"""Every COMMAND_LONG / COMMAND_INT the executive sends, per firmware, param by param (issue 23).

Each row is what goes on the wire for one intent of the autopilot port (or the stream set-up), checked
against MAVLink's common.xml and the firmware's handler (cited in executive/io/mavlink/commander.py and
the back ends). NaN where the definition says "NaN: unchanged / default / here": never 0, which PX4
takes as a value (NAV_TAKEOFF's latitude/longitude 0, 0 is a take-off point in the Gulf of Guinea;
DO_SET_HOME's yaw 0 points home north).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from executive.autopilot.selection import Autopilot
from executive.io.mavlink.streams import StreamRequester
from executive.world.dialect import mavlink
from executive.world.state import GlobalPosition, HomePosition
from executive.world.vehicles import PROFILES

_M = mavlink
NAN = math.nan
HOME = HomePosition(-35.363261, 149.165230, 584.0, 0.0)
HERE = GlobalPosition(HOME.lat, HOME.lon, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
CUSTOM = float(_M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
CHANGE_MODE = float(_M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)

Intent = Callable[[Autopilot], object]

#: (firmware, vehicle, intent, message type, command, frame (COMMAND_INT) or None, param1..param7 with x/y in degrees)
ROWS: list[tuple[str, str, str, Intent, str, int, int | None, tuple[float, ...]]] = [
    # ArduPilot
    (
        "ardupilot",
        "rover",
        "set_mode GUIDED",
        lambda p: p.set_mode("GUIDED"),
        "COMMAND_LONG",
        _M.MAV_CMD_DO_SET_MODE,
        None,
        (CUSTOM, 15, 0, 0, 0, 0, 0),
    ),
    ("ardupilot", "rover", "arm", lambda p: p.arm(), "COMMAND_LONG", _M.MAV_CMD_COMPONENT_ARM_DISARM, None, (1, 0, 0, 0, 0, 0, 0)),
    (
        "ardupilot",
        "rover",
        "arm forced",
        lambda p: p.arm(force=True),
        "COMMAND_LONG",
        _M.MAV_CMD_COMPONENT_ARM_DISARM,
        None,
        (1, 2989, 0, 0, 0, 0, 0),
    ),
    (
        "ardupilot",
        "rover",
        "disarm forced",
        lambda p: p.disarm(force=True),
        "COMMAND_LONG",
        _M.MAV_CMD_COMPONENT_ARM_DISARM,
        None,
        (0, 21196, 0, 0, 0, 0, 0),
    ),
    ("ardupilot", "rover", "change_speed", lambda p: p.change_speed(1.5), "COMMAND_LONG", _M.MAV_CMD_DO_CHANGE_SPEED, None, (1, 1.5, -1, 0, 0, 0, 0)),
    (
        "ardupilot",
        "vtol",
        "change_speed air",
        lambda p: p.change_speed(18.0, airspeed=True),
        "COMMAND_LONG",
        _M.MAV_CMD_DO_CHANGE_SPEED,
        None,
        (0, 18, -1, 0, 0, 0, 0),
    ),
    (
        "ardupilot",
        "rover",
        "reposition",
        lambda p: p.reposition(-35.36, 149.17, 10.0),
        "COMMAND_INT",
        _M.MAV_CMD_DO_REPOSITION,
        _M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        (-1, CHANGE_MODE, 0, NAN, -35.36, 149.17, 10.0),
    ),
    (
        "ardupilot",
        "vtol",
        "take_off",
        lambda p: p.take_off(30.0, home=HOME, position=HERE, airborne=False),
        "COMMAND_LONG",
        _M.MAV_CMD_NAV_TAKEOFF,
        None,
        (0, 0, 0, NAN, NAN, NAN, 30.0),
    ),
    (
        "ardupilot",
        "vtol",
        "transition FW in AUTO",
        lambda p: p.transition("FW", mode="AUTO", position=HERE, heading_deg=0, mc_mode="QLOITER", ahead_m=600),
        "COMMAND_LONG",
        _M.MAV_CMD_DO_VTOL_TRANSITION,
        None,
        (_M.MAV_VTOL_STATE_FW, 0, 0, 0, 0, 0, 0),
    ),
    ("ardupilot", "vtol", "land (no mode)", lambda p: p.land(), "COMMAND_LONG", _M.MAV_CMD_DO_SET_MODE, None, (CUSTOM, 20, 0, 0, 0, 0, 0)),  # QLAND
    ("ardupilot", "sub", "land (no mode)", lambda p: p.land(), "COMMAND_LONG", _M.MAV_CMD_NAV_LAND, None, (0, 0, 0, NAN, NAN, NAN, NAN)),
    ("ardupilot", "rover", "set_home here", lambda p: p.set_home(), "COMMAND_LONG", _M.MAV_CMD_DO_SET_HOME, None, (1, 0, 0, NAN, NAN, NAN, NAN)),
    (
        "ardupilot",
        "rover",
        "set_home at",
        lambda p: p.set_home(-35.1, 149.2, 584.0),
        "COMMAND_INT",
        _M.MAV_CMD_DO_SET_HOME,
        _M.MAV_FRAME_GLOBAL,
        (0, 0, 0, NAN, -35.1, 149.2, 584.0),
    ),
    # PX4
    ("px4", "vtol", "set_mode RTL", lambda p: p.set_mode("RTL"), "COMMAND_LONG", _M.MAV_CMD_DO_SET_MODE, None, (CUSTOM, 4, 5, 0, 0, 0, 0)),
    ("px4", "vtol", "hold", lambda p: p.hold(), "COMMAND_LONG", _M.MAV_CMD_DO_SET_MODE, None, (CUSTOM, 4, 3, 0, 0, 0, 0)),
    ("px4", "vtol", "arm", lambda p: p.arm(), "COMMAND_LONG", _M.MAV_CMD_COMPONENT_ARM_DISARM, None, (1, 0, 0, 0, 0, 0, 0)),
    ("px4", "vtol", "arm forced", lambda p: p.arm(force=True), "COMMAND_LONG", _M.MAV_CMD_COMPONENT_ARM_DISARM, None, (1, 21196, 0, 0, 0, 0, 0)),
    (
        "px4",
        "vtol",
        "disarm forced",
        lambda p: p.disarm(force=True),
        "COMMAND_LONG",
        _M.MAV_CMD_COMPONENT_ARM_DISARM,
        None,
        (0, 21196, 0, 0, 0, 0, 0),
    ),
    (
        "px4",
        "vtol",
        "take_off",
        lambda p: p.take_off(30.0, home=HOME, position=HERE, airborne=False),
        "COMMAND_LONG",
        _M.MAV_CMD_NAV_TAKEOFF,
        None,
        (0, 0, 0, NAN, NAN, NAN, 614.0),
    ),
    (
        "px4",
        "vtol",
        "take_off, home unknown",
        lambda p: p.take_off(30.0, home=None, position=HERE, airborne=False),
        "COMMAND_LONG",
        _M.MAV_CMD_NAV_TAKEOFF,
        None,
        (0, 0, 0, NAN, NAN, NAN, NAN),
    ),
    (
        "px4",
        "vtol",
        "reposition",
        lambda p: p.reposition(-35.36, 149.17, 10.0),
        "COMMAND_INT",
        _M.MAV_CMD_DO_REPOSITION,
        _M.MAV_FRAME_GLOBAL_INT,
        (-1, CHANGE_MODE, 0, NAN, -35.36, 149.17, 594.0),
    ),
    (
        "px4",
        "vtol",
        "transition FW",
        lambda p: p.transition("FW", mode="AUTO.LOITER", position=HERE, heading_deg=0, mc_mode="QLOITER", ahead_m=600),
        "COMMAND_LONG",
        _M.MAV_CMD_DO_VTOL_TRANSITION,
        None,
        (_M.MAV_VTOL_STATE_FW, 0, 0, 0, 0, 0, 0),
    ),
    ("px4", "vtol", "change_speed", lambda p: p.change_speed(12.0), "COMMAND_LONG", _M.MAV_CMD_DO_CHANGE_SPEED, None, (1, 12, -1, 0, 0, 0, 0)),
    ("px4", "vtol", "land (no mode)", lambda p: p.land(), "COMMAND_LONG", _M.MAV_CMD_NAV_LAND, None, (0, 0, 0, NAN, NAN, NAN, NAN)),
    (
        "px4",
        "rover",
        "set_home at",
        lambda p: p.set_home(-35.1, 149.2, 584.0),
        "COMMAND_INT",
        _M.MAV_CMD_DO_SET_HOME,
        _M.MAV_FRAME_GLOBAL,
        (0, 0, 0, NAN, -35.1, 149.2, 584.0),
    ),
]


def same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, abs=1e-6)


@pytest.mark.parametrize(
    ("firmware", "kind", "intent", "ask", "message", "command", "frame", "params"), ROWS, ids=[f"{r[0]} {r[1]} {r[2]}" for r in ROWS]
)
def test_the_params_of_each_command_on_the_wire(vehicle, commander, link, firmware, kind, intent, ask, message, command, frame, params) -> None:
    vehicle.set(vehicle__home=HOME, vehicle__mode="AUTO.LOITER" if firmware == "px4" else "HOLD")
    port = Autopilot(commander, None, PROFILES[kind])
    port.adopt(_M.MAV_AUTOPILOT_PX4 if firmware == "px4" else _M.MAV_AUTOPILOT_ARDUPILOTMEGA, PROFILES[kind].mav_type)
    ask(port)
    commander.flush()
    (sent,) = [m for m in link.take() if m.get_type() in ("COMMAND_LONG", "COMMAND_INT")]
    assert (sent.get_type(), sent.command) == (message, command)
    if message == "COMMAND_INT":
        got = (sent.param1, sent.param2, sent.param3, sent.param4, sent.x * 1e-7, sent.y * 1e-7, sent.z)
        assert sent.frame == frame
    else:
        got = (sent.param1, sent.param2, sent.param3, sent.param4, sent.param5, sent.param6, sent.param7)
    assert all(same(a, b) for a, b in zip(got, params, strict=True)), f"sent {got}, expected {params}"


def test_stream_requests_ask_for_each_message_interval_with_the_flight_stacks_default_target(commander, link) -> None:
    """SET_MESSAGE_INTERVAL: param1 the message id, param2 the interval in µs, param3-6 0 (not used), param7 0 (flight-stack default)."""
    StreamRequester(commander, {"GLOBAL_POSITION_INT": 5.0}).restart()
    requester = StreamRequester(commander, {"GLOBAL_POSITION_INT": 5.0})
    requester.restart()
    requester.service()
    commander.flush()
    (sent,) = link.take("COMMAND_LONG")
    assert sent.command == _M.MAV_CMD_SET_MESSAGE_INTERVAL
    assert (sent.param1, sent.param2, sent.param3, sent.param4, sent.param5, sent.param6, sent.param7) == (33, 200000, 0, 0, 0, 0, 0)
