"""ArduPilot as a simulated autopilot: what every ArduPilot firmware does alike, then a module per firmware."""
