"""Behaviours the trees are built from: guards (conditions), actions and flow control."""

from executive.behaviours.auto_depth import DepthsOnAutopilot
from executive.behaviours.auto_legs import AutopilotAtLeg, FollowAutoLeg, HorizonOnAutopilot
from executive.behaviours.auto_route import DriveRouteInAuto, KeepRouteOnAutopilot
from executive.behaviours.commands import Arm, ChangeSpeed, CommandAction, Disarm, HoldFor, SetMode
from executive.behaviours.depth import ChangeAltitude, ChangeDepth, Surface
from executive.behaviours.energy import EnergyEnough, EnergyFits
from executive.behaviours.failsafe import Failsafe, FailsafeNote
from executive.behaviours.flow import ForEachLeg, Timeout, UnlessPaused, WaitForGuards, WaitUntil
from executive.behaviours.guards import Armed, BatteryAbove, EkfOk, GpsNotGlitching, Guard, HeadingSane, LinkAlive, ModeIs
from executive.behaviours.mode_switch import ModeSwitchClear
from executive.behaviours.motion import GoTo
from executive.behaviours.parameters import ParameterIs
from executive.behaviours.position_guards import (
    AllWaypointsWithin,
    AltitudeWithin,
    DepthWithin,
    InsideGeofence,
    PositionKnown,
    RangefinderReaches,
    SpeedWithin,
    TargetWithin,
    inside_geofence,
)
from executive.behaviours.rc_guards import RcAutoMode, RcChannelHigh, RcFresh, RcNotLost, RcNotTakingOver, rc_auto_mode
from executive.behaviours.rc_switches import ArmSwitch, ModeSwitch, RouteEditSwitch
from executive.behaviours.readiness import ReadingsIn
from executive.behaviours.sampling import NothingToSample, Sample
from executive.behaviours.vtol import GoToLocal, Land, TakeOff, VtolTransition

__all__ = [
    "AllWaypointsWithin",
    "AltitudeWithin",
    "Arm",
    "ArmSwitch",
    "Armed",
    "AutopilotAtLeg",
    "BatteryAbove",
    "ChangeAltitude",
    "ChangeDepth",
    "ChangeSpeed",
    "CommandAction",
    "DepthWithin",
    "DepthsOnAutopilot",
    "Disarm",
    "DriveRouteInAuto",
    "EkfOk",
    "EnergyEnough",
    "EnergyFits",
    "Failsafe",
    "FailsafeNote",
    "FollowAutoLeg",
    "ForEachLeg",
    "GoTo",
    "GoToLocal",
    "GpsNotGlitching",
    "Guard",
    "HeadingSane",
    "HoldFor",
    "HorizonOnAutopilot",
    "InsideGeofence",
    "KeepRouteOnAutopilot",
    "Land",
    "LinkAlive",
    "ModeIs",
    "ModeSwitch",
    "ModeSwitchClear",
    "NothingToSample",
    "ParameterIs",
    "PositionKnown",
    "RangefinderReaches",
    "RcAutoMode",
    "RcChannelHigh",
    "RcFresh",
    "RcNotLost",
    "RcNotTakingOver",
    "ReadingsIn",
    "RouteEditSwitch",
    "Sample",
    "SetMode",
    "SpeedWithin",
    "Surface",
    "TakeOff",
    "TargetWithin",
    "Timeout",
    "UnlessPaused",
    "VtolTransition",
    "WaitForGuards",
    "WaitUntil",
    "inside_geofence",
    "rc_auto_mode",
]
