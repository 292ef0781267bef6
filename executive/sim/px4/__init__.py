"""PX4 as a simulated autopilot."""
