"""The autopilot port (intents and capabilities) behaviours use, and its back ends (ArduPilot, PX4)."""

from executive.autopilot.port import AutopilotName, AutopilotPort, Capabilities, Request, Target, VtolState

__all__ = ["AutopilotName", "AutopilotPort", "Capabilities", "Request", "Target", "VtolState"]
