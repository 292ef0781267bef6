"""What the executive derives from the vehicle's raw readings: a sane heading (the filterpy sanity filter) and the RC.

Neither touches a socket: each is a reader service over the blackboard, run after the links are drained.
"""
