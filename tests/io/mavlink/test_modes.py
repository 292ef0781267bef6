"""Mode tables: ArduPilot numbers per firmware, PX4 main/sub modes, and the names trees use."""

from __future__ import annotations

import pytest

from executive.io.mavlink.modes import PX4_MODES, ArduPilotModes, Px4Modes, mode_table
from executive.world.dialect import mavlink, mavutil
from executive.world.vehicles import PLANE_MODES, ROVER_MODES, SUB_MODES


@pytest.mark.parametrize(
    ("mav_type", "name", "number"),
    [
        (mavlink.MAV_TYPE_GROUND_ROVER, "GUIDED", 15),
        (mavlink.MAV_TYPE_SURFACE_BOAT, "LOITER", 5),
        (mavlink.MAV_TYPE_SUBMARINE, "POSHOLD", 16),
        (mavlink.MAV_TYPE_SUBMARINE, "SURFACE", 9),
        (mavlink.MAV_TYPE_VTOL_QUADROTOR, "QLOITER", 19),
        (mavlink.MAV_TYPE_FIXED_WING, "GUIDED", 15),
    ],
)
def test_ardupilot_tables_by_vehicle_type(mav_type, name, number):
    table = mode_table(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, mav_type)
    assert table.encode(name) == (number, 0.0)
    assert table.encode(name.lower()) == (number, 0.0)
    assert table.decode(number) == name


def test_name_or_number_and_unknowns():
    table = ArduPilotModes(ROVER_MODES)
    assert table.encode(4) == (4.0, 0.0)
    assert table.decode(99) == "MODE(99)"
    with pytest.raises(KeyError):
        table.encode("WARP")
    with pytest.raises(KeyError):
        table.encode(2)  # Rover has no mode 2


def test_tables_differ_per_firmware():
    assert ROVER_MODES["AUTO"] == 10 and SUB_MODES["AUTO"] == 3 and PLANE_MODES["AUTO"] == 10
    assert ROVER_MODES["LOITER"] == 5 and PLANE_MODES["LOITER"] == 12


def test_unknown_vehicle_type_has_no_names():
    table = mode_table(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, mavlink.MAV_TYPE_QUADROTOR)
    assert table.decode(5) == "MODE(5)"


@pytest.mark.parametrize(
    ("name", "main", "sub"),
    [("MANUAL", 1, 0), ("POSCTL", 3, 0), ("AUTO.MISSION", 4, 4), ("AUTO.LOITER", 4, 3), ("AUTO.RTL", 4, 5), ("OFFBOARD", 6, 0)],
)
def test_px4_main_and_sub_modes(name, main, sub):
    table = mode_table(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_VTOL_QUADROTOR)
    assert isinstance(table, Px4Modes)
    assert table.encode(name) == (main, sub)
    assert table.decode((main << 16) | (sub << 24)) == name
    assert PX4_MODES[name] == (main << 16) | (sub << 24)


@pytest.mark.parametrize(("tree_name", "px4_name"), [("GUIDED", "OFFBOARD"), ("HOLD", "AUTO.LOITER"), ("RTL", "AUTO.RTL"), ("QLAND", "AUTO.LAND")])
def test_px4_equivalents_of_the_names_trees_use(tree_name, px4_name):
    table = Px4Modes()
    assert table.canonical(tree_name) == px4_name
    assert table.encode(tree_name) == table.encode(px4_name)


def test_set_mode_on_px4_sends_main_and_sub(commander, link):
    commander.modes = Px4Modes()
    commander.set_mode("HOLD")
    commander.flush()
    (msg,) = link.take()
    assert (msg.command, msg.param1, msg.param2, msg.param3) == (mavlink.MAV_CMD_DO_SET_MODE, 1.0, 4.0, 3.0)


def test_the_ardupilot_tables_are_pymavlink_s_but_where_the_firmware_s_source_differs():
    """pymavlink's mode_mapping_byname, corrected by Rover/mode.h (no LEARNING), ArduSub/mode.h (+2) and ArduPlane/mode.h (a name)."""
    rover = mavutil.mode_mapping_byname(mavlink.MAV_TYPE_GROUND_ROVER)
    assert dict(ROVER_MODES) == {name: n for name, n in rover.items() if name != "LEARNING"}
    assert dict(SUB_MODES) == mavutil.mode_mapping_byname(mavlink.MAV_TYPE_SUBMARINE) | {"MOTOR_DETECT": 20, "SURFTRAK": 21}
    plane = mavutil.mode_mapping_byname(mavlink.MAV_TYPE_VTOL_QUADROTOR)
    assert dict(PLANE_MODES) == {("LOITER_ALT_QLAND" if name == "LOITERALTQLAND" else name): n for name, n in plane.items()}
    assert PLANE_MODES["AUTOLAND"] == 26


def test_the_px4_numbers_are_pymavlink_s_px4_custom_modes():
    assert PX4_MODES["AUTO.RTL"] == mavutil.PX4_CUSTOM_MAIN_MODE_AUTO << 16 | mavutil.PX4_CUSTOM_SUB_MODE_AUTO_RTL << 24
    assert PX4_MODES["OFFBOARD"] == mavutil.PX4_CUSTOM_MAIN_MODE_OFFBOARD << 16
    assert PX4_MODES["AUTO.PRECLAND"] == 4 << 16 | 9 << 24  # pymavlink names no PRECLAND
