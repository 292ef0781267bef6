"""The vehicle's world as the executive knows it: the blackboard and the values on it, vehicle kinds,
geodesy and frames, fences, the seabed, the injected clock, and MAVLink's vocabulary."""
