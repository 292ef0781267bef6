"""The autopilot link: the one object the runtime holds for the autopilot (connect, pump, flush, make safe), and the
parts of it that touch no socket: the route keeper (each route edit uploaded and read back) and the parameter watch."""

from executive.autopilot_link.link import MAKE_SAFE, SURVEY_S, AutopilotLink, MadeSafe, SeveralAutopilots

__all__ = ["MAKE_SAFE", "SURVEY_S", "AutopilotLink", "MadeSafe", "SeveralAutopilots"]
