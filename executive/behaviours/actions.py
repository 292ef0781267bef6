"""The actions, by concept: :mod:`~executive.behaviours.commands` (commands and their acks, modes, arming, speed),
:mod:`~executive.behaviours.motion` (go to), :mod:`~executive.behaviours.depth` (depth and altitude, surfacing), :mod:`~executive.behaviours.vtol`
(take-off, landing, transitions, local points). Kept for users' trees that import them from here.
"""

from executive.behaviours.commands import Arm, ChangeSpeed, CommandAction, Disarm, HoldFor, SetMode
from executive.behaviours.depth import ChangeAltitude, ChangeDepth, Surface
from executive.behaviours.motion import GoTo
from executive.behaviours.vtol import GoToLocal, Land, TakeOff, VtolTransition

__all__ = [
    "Arm",
    "ChangeAltitude",
    "ChangeDepth",
    "ChangeSpeed",
    "CommandAction",
    "Disarm",
    "GoTo",
    "GoToLocal",
    "HoldFor",
    "Land",
    "SetMode",
    "Surface",
    "TakeOff",
    "VtolTransition",
]
