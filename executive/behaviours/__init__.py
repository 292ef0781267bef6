"""Behaviours the trees are built from: guards (conditions), actions and flow control."""

from executive.behaviours.actions import Arm, CommandAction, Disarm, GoTo, SetMode
from executive.behaviours.flow import ForEachLeg, UnlessPaused, WaitForGuards, WaitUntil
from executive.behaviours.guards import Armed, EkfOk, Guard, LinkAlive, ModeIs, RcNotTakingOver

__all__ = [
    "Arm",
    "Armed",
    "CommandAction",
    "Disarm",
    "EkfOk",
    "ForEachLeg",
    "GoTo",
    "Guard",
    "LinkAlive",
    "ModeIs",
    "RcNotTakingOver",
    "SetMode",
    "UnlessPaused",
    "WaitForGuards",
    "WaitUntil",
]
