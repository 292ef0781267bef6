"""Route and zone files of other tools read and written: QGroundControl plans, MAVLink mission items, Mission Planner's fence and rally files."""
